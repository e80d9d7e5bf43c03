# toolconf: the two commands a user needs are `make run` and `make test`.
SHELL := /bin/bash
VENV := derive/.venv
PY := $(VENV)/bin/python
PY_DEV := $(VENV)/.python-dev-installed
# Deterministic derivation: the same inputs give byte-identical generated files.
export PYTHONHASHSEED := 0

.PHONY: run test check derive render drift-check venv clean-venv bench python-test crate model on-robot-test c-example-test loaded-models-test mujoco-test

## make run: build in release mode and reproduce the paper's Results (results/report.md).
run:
	cargo build --release --quiet
	./target/release/toolconf reproduce --out results/

## make bench: criterion benchmarks (Π^U per tool, closed-loop RHS, episodes, a batch of 1000, populations of 2000 tools, the Panda's joint and tip episodes,
## the default reproduce, the on-robot controller's tick, directly and through the C ABI); reports in
## target/criterion/ and examples/on_robot/bench/target/criterion/. Peers: benches/peers/run.sh.
bench:
	cargo bench --bench confidence --bench episode --bench stiff --bench reproduce --bench population --bench urdf_episode
	cargo bench -p toolconf-cabi --bench tick
	cargo bench --manifest-path examples/on_robot/bench/Cargo.toml

## make test: the whole suite, in two lanes at once (make -j2), each printing its output when it
## ends, then the tests that need both:
## - the derivation's lane: `make derive` reproduces generated/ byte for byte (on this CPU and on an
##   imitated older one: make drift-check), the derivation's own tests, then the model libraries the
##   tests that load one use (scripts/model_libraries.sh: every committed model and the xArm7);
## - the crates' lane: every crate's tests compiled (while the Python environment is made), the
##   Python package built (maturin develop, reusing the tests' builds: crates/workspace-hack),
##   the on-robot crate's tests (make on-robot-test), then the crates' tests run and the Python
##   package's.
## Then the tests that load a model library, on the libraries built once for all of them, two at a
## time. The Python crate is built by maturin alone (it has no Rust tests: `cargo test --workspace` would
## only build it a second time). The derivation's lane builds in target/derive-lane/ (the renderer,
## and the model libraries under make-model/): cargo locks a whole target folder while it builds,
## so neither lane waits for the other's cargo.
## The fuzzers of every parser run in it with bounded case counts (TOOLCONF_FUZZ_CASES raises
## them: docs/reference/errors.md), and so does the sweep of hostile inputs (tests/hostile.rs).
CARGO_TESTS = cargo test --workspace --exclude toolconf-python --quiet
# The command line that $(CARGO_TESTS) --no-run built for the integration tests (their
# CARGO_BIN_EXE_toolconf), which the Python and MuJoCo tests run: a `cargo build --bin toolconf`
# or a `cargo test --test NAME` selects fewer packages, so cargo unifies other features for the
# dependencies they share and compiles the model layer and the runtime again (measured: 151 and
# 318 CPU-seconds on a warm target/).
TEST_BIN = $(or $(CARGO_TARGET_DIR),$(CURDIR)/target)/debug/toolconf
test:
	@d=$$(mktemp -d) && trap 'rm -rf "$$d"' EXIT && \
	$(MAKE) --no-print-directory -j2 --output-sync=target derive-lane crates-lane TEST_LIBRARY_DIR=$$d && \
	TOOLCONF_TEST_LIBRARIES=$$d TOOLCONF_BIN=$(TEST_BIN) $(MAKE) --no-print-directory -j2 --output-sync=target \
	  c-example-test loaded-models-test mujoco-test

# make test's lanes (TEST_LIBRARY_DIR: the folder the model libraries go to). The tests compile
# while the Python environment is made (derive/.venv), which the derivation's lane waits for.
.PHONY: derive-lane crates-lane tests-compiled
tests-compiled:
	$(CARGO_TESTS) --no-run

derive-lane: export CARGO_TARGET_DIR = $(CURDIR)/target/derive-lane
derive-lane: $(PY_DEV)
	$(MAKE) --no-print-directory drift-check
	$(PY) -m unittest discover --start-directory derive/tests
	scripts/model_libraries.sh $(PY) $(TEST_LIBRARY_DIR)

# The crates' lane ends by installing MuJoCo's packages, while the other lane still works: the tests
# that load a model library then run two at a time without pip changing derive/.venv under them
# (mujoco-test tries a failed install again, and says so).
crates-lane: tests-compiled $(PY_DEV)
	$(PYTHON_BUILD)
	$(MAKE) --no-print-directory on-robot-test
	$(CARGO_TESTS)
	TOOLCONF_BIN=$(TEST_BIN) $(PYTHON_TESTS)
	@$(MAKE) --no-print-directory $(MUJOCO_INSTALLED) >/dev/null 2>&1 || true

## make check: the inner loop, after each edit (under 3 min warm): rustfmt over the workspace; clippy
## (warnings are errors) and the unit tests of each package the working tree changes against main
## (CHECK_BASE=<rev> for another base); each changed integration test file; the derivation's tests
## named after each changed derive/ module (scripts/check.py). make test, the whole suite, before a merge.
CHECK_BASE ?= main
check:
	@python3 scripts/check.py $(CHECK_BASE)

## make on-robot-test: the on-robot controller's own tests (examples/on_robot, a crate outside the
## workspace, as a robot's firmware would build it).
on-robot-test:
	cargo test --quiet --manifest-path examples/on_robot/Cargo.toml

## make c-example-test: the C example controller (examples/c_controller/main.c) on the Panda's model library,
## built by make model from the committed IR into a temporary folder, prints the Rust on-robot controller's
## torque and confidence, bit for bit (examples/on_robot/tests/panda_tick.rs).
c-example-test: $(PY)
	@$(MAKE) --no-print-directory -C examples/c_controller check PY=$(abspath $(PY))

## make loaded-models-test: models loaded at run time. Builds every model of the repository into a model
## library (make model IR=generated/<model>.json) and the UFactory xArm7, which the repository does not ship,
## from its unedited URDF (make model DESC=examples/robots/xarm7.toml), into a temporary folder (or takes
## those in $TOOLCONF_TEST_LIBRARIES, as make test gives them: scripts/model_libraries.sh); then checks
## that each loaded library gives its built-in model's numbers bit for bit in every operation and subcommand
## (tests/loaded_models.rs), that rank's 3-D view of the xArm7 works in headless Chromium (tests/view3d.rs), in Python and on Dask's workers (python/loaded_tests/), and the xArm7's
## dynamics against Pinocchio's aba; and runs the examples that load a library (examples/load_model.rs,
## examples/python/load_model.py) on the Panda's. Needs the Python package installed (make python-test does it).
loaded-models-test:
	@d=$$(mktemp -d) && trap 'rm -rf "$$d"' EXIT && \
	if [ -z "$$TOOLCONF_TEST_LIBRARIES" ]; then scripts/model_libraries.sh $(PY) $$d && export TOOLCONF_TEST_LIBRARIES=$$d; fi && \
	echo "loaded-models-test: $$(ls -d $$TOOLCONF_TEST_LIBRARIES/*/ | wc -l) model libraries" && \
	$(CARGO_TESTS) --test loaded_models -- --include-ignored && \
	$(CARGO_TESTS) --test examples -- --ignored && \
	$(CARGO_TESTS) --test view3d -- --ignored && \
	$(PY) -m pytest -q python/loaded_tests

## make mujoco-test: the on-robot controller on MuJoCo (examples/mujoco/, docs/tutorials/mujoco.md). Installs the example's
## pinned requirements (examples/mujoco/requirements.txt) into derive/.venv, builds the Panda's model library from
## the committed IR into a temporary folder (or takes $TOOLCONF_TEST_LIBRARIES/panda), checks MuJoCo's plant against the library's open loop, then runs the
## example's comparison (compare.py) of the catalogue's touch task against toolconf simulate and asserts its bounds
## and ranking (examples/mujoco/test_mujoco.py). Where mujoco cannot be installed, one line says so and it is skipped.
MUJOCO_INSTALLED := $(VENV)/.mujoco-installed
mujoco-test:
	@d=$$(mktemp -d) && trap 'rm -rf "$$d"' EXIT && \
	if ! $(MAKE) --no-print-directory $(MUJOCO_INSTALLED) >$$d/install.log 2>&1; then \
	  echo "mujoco-test: skipped: mujoco cannot be installed here: $$(grep -m 1 -i 'error' $$d/install.log || tail -n 1 $$d/install.log)"; \
	  exit 0; \
	fi && \
	if [ -z "$$TOOLCONF_TEST_LIBRARIES" ]; then scripts/model_libraries.sh $(PY) $$d panda >/dev/null && export TOOLCONF_TEST_LIBRARIES=$$d; fi && \
	TOOLCONF_MUJOCO_LIBRARY=$$TOOLCONF_TEST_LIBRARIES/panda $(PY) -m pytest -q examples/mujoco

$(MUJOCO_INSTALLED): examples/mujoco/requirements.txt $(PY)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check -r examples/mujoco/requirements.txt
	touch $@

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

## make render: re-render generated/ from its committed IR (generated/*.json) through templates/
## (Tera + rustfmt), with no derivation and no Python: what to run after a change to templates/ or
## derive/render. cargo test's tests/render_ensure.rs fails, naming the file and line, until it is.
render:
	cargo run --quiet -p toolconf-render -- --crate generated

# make crate's and make model's arguments are data, whatever they hold (a quote, `$(...)`, a
# backtick, a newline): each reaches the script as typed, in the environment (make's $(value),
# which expands nothing), never through a shell command line; and they are not exported as make
# exports a command line's variables (expanded, which would run a `$(shell ...)` in one). The
# script starts with SIGINT blocked (GNU env's --block-signal, where env has it) until its first
# lines have installed their handler: an interrupt while Python starts waits for it, and is one
# line, never a traceback.
MAKE_ARGUMENTS := MODELS OUT TASKS NAME DESC IR
BLOCK_SIGINT := $(shell env --block-signal=INT true 2>/dev/null && echo env --block-signal=INT)
unexport $(MAKE_ARGUMENTS)
crate model: export TOOLCONF_MAKE_MODELS = $(value MODELS)
crate model: export TOOLCONF_MAKE_OUT = $(value OUT)
crate model: export TOOLCONF_MAKE_TASKS = $(value TASKS)
crate model: export TOOLCONF_MAKE_NAME = $(value NAME)
crate model: export TOOLCONF_MAKE_DESC = $(value DESC)
crate model: export TOOLCONF_MAKE_IR = $(value IR)

## make crate MODELS=<folder> OUT=<folder> [TASKS=<file>] [NAME=<crate>]: derive the model descriptions in
## MODELS (with derive/tasks.toml, or TASKS) into a standalone no_std crate at OUT, with its own
## test against the CasADi vectors (cargo test --manifest-path OUT/Cargo.toml); nothing in the
## repository changes (derive/make_crate.py).
crate: $(PY)
	@exec $(BLOCK_SIGINT) $(PY) derive/make_crate.py --from-make

## make model DESC=<description> OUT=<folder> [TASKS=<file>]: validate, derive and build ONE model into a
## shared library with toolconf's C ABI in OUT (libtoolconf_model_<model>.so, toolconf_model.h, and the
## crate they came from), showing each step; `make model IR=generated/<model>.json OUT=<folder>` renders
## and compiles a model derived before. Nothing in the repository changes (derive/make_model.py,
## docs/reference/c-abi.md).
model: $(PY)
	@exec $(BLOCK_SIGINT) $(PY) derive/make_model.py --from-make

## make drift-check: derive into a temporary folder, twice: as this CPU does, and with numpy's
## optional kernels (AVX-512, AVX2, ...) and glibc's AVX/FMA variants switched off; fail, naming
## each file and its first differing line, if either differs from what is committed.
drift-check: $(PY)
	$(PY) derive/pipeline.py --check --portability

clean-venv:
	rm -rf $(VENV)
