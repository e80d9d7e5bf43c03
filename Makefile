# toolconf: the two commands a user needs are `make run` and `make test`.
SHELL := /bin/bash
VENV := derive/.venv
PY := $(VENV)/bin/python
PY_DEV := $(VENV)/.python-dev-installed
# Deterministic derivation: the same inputs give byte-identical generated files.
export PYTHONHASHSEED := 0

.PHONY: run test derive drift-check venv clean-venv bench python-test

## make run: build in release mode and reproduce the paper's Results (results/report.md).
run:
	cargo build --release --quiet
	./target/release/toolconf reproduce --out results/

## make bench: criterion benchmarks (Π^U per tool, closed-loop RHS, episodes, a batch of 1000, populations of 2000 tools,
## the default reproduce); reports in target/criterion/. Peers: bench/peers/run.sh.
bench:
	cargo bench --bench confidence --bench episode --bench stiff --bench reproduce --bench population

## make test: the whole suite: `make derive` reproduces generated/ byte for byte (on this CPU and
## on an imitated older one), the derivation's own tests, the crate's, then the Python package's.
## The fuzzers of every parser run in it with bounded case counts (TOOLCONF_FUZZ_CASES raises
## them: README "Bad input"), and so does the sweep of hostile inputs (tests/hostile.rs).
test: drift-check $(PY_DEV)
	$(PY) -m unittest discover --start-directory derive/tests
	cargo test --workspace --quiet
	$(PYTHON_BUILD)
	$(PYTHON_TESTS)

## make python-test: builds the Python package (python/, `import toolconf`) into derive/.venv
## with maturin (debug profile, in the workspace's target/, so the crate is not built twice),
## then runs its pytest suite against the command line's JSON.
PYTHON_BUILD = VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --quiet --manifest-path python/Cargo.toml
PYTHON_TESTS = $(PY) -m pytest -q python/tests
python-test: $(PY_DEV)
	$(PYTHON_BUILD)
	$(PYTHON_TESTS)

venv: $(PY)

$(PY): derive/requirements.txt
	python3 -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check -r derive/requirements.txt
	touch $(PY)

# maturin and pytest (pinned) for the Python package, added to the same environment.
$(PY_DEV): python/requirements-dev.txt $(PY)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check -r python/requirements-dev.txt
	touch $(PY_DEV)

## make derive: model descriptions -> SymPy (checked by CasADi) -> JSON IR + test vectors -> Tera
## -> rustfmt, into generated/ (and the renderer's fixture in tests/fixtures/).
derive: $(PY)
	$(PY) derive/pipeline.py

## make drift-check: derive into a temporary folder, twice: as this CPU does, and with numpy's
## optional kernels (AVX-512, AVX2, ...) and glibc's AVX/FMA variants switched off; fail, naming
## each file and its first differing line, if either differs from what is committed.
drift-check: $(PY)
	$(PY) derive/pipeline.py --check --portability

clean-venv:
	rm -rf $(VENV)
