# toolconf: the two commands a user needs are `make run` and `make test`.
SHELL := /bin/bash
VENV := derive/.venv
PY := $(VENV)/bin/python
MODELS := $(wildcard derive/models/*.toml)
IRS := $(patsubst derive/models/%.toml,generated/%.json,$(MODELS))
# Deterministic derivation: the same inputs give byte-identical generated files.
export PYTHONHASHSEED := 0

.PHONY: run test derive drift-check venv clean-venv bench

## make run: build in release mode and reproduce the paper's Results (results/report.md).
run:
	cargo build --release --quiet
	./target/release/toolconf reproduce --out results/

## make bench: criterion benchmarks (Π^U per tool, closed-loop RHS, episodes, a batch of 1000,
## the default reproduce); reports in target/criterion/. Peers: bench/peers/run.sh.
bench:
	cargo bench --bench confidence --bench episode --bench stiff --bench reproduce

## make test: the whole suite, including the check that `make derive` leaves generated/ unchanged.
test: drift-check
	cargo test --workspace --quiet

venv: $(PY)

$(PY): derive/requirements.txt
	python3 -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check -r derive/requirements.txt
	touch $(PY)

## make derive: model descriptions -> SymPy (checked by CasADi) -> JSON IR -> Tera -> rustfmt.
derive: $(PY)
	@for m in $(MODELS); do \
	  $(PY) derive/derive.py $$m --out generated/$$(basename $$m .toml).json || exit 1; \
	done
	$(PY) derive/derive.py tests/fixtures/pendulum.toml --out tests/fixtures/pendulum.json --vectors 3
	cargo run --quiet -p toolconf-render -- $(IRS) --templates templates --out generated

## make drift-check: regenerate and fail if anything generated differs from what is committed.
drift-check: derive
	@if [ -n "$$(git status --porcelain -- generated tests/fixtures)" ]; then \
	  git status --short -- generated tests/fixtures; git --no-pager diff --stat -- generated tests/fixtures; \
	  echo "drift-check: make derive changed generated files: commit them (after review)"; exit 1; \
	fi
	@echo "drift-check: generated/ is what make derive produces"

clean-venv:
	rm -rf $(VENV)
