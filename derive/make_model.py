#!/usr/bin/env python3
"""One model into a shared library with toolconf's C ABI (`make model`): the description read and
checked, derived alone (derive.py: SymPy or, for a URDF arm, CasADi graphs, each function checked
against its reference), rendered into a crate (templates/registry/ for the model's generated code,
templates/cabi/ for the library around it: crates/cabi's exports, the header toolconf_model.h),
and compiled by cargo into OUT:

    make model DESC=<description.toml> OUT=<folder> [TASKS=<file>]
    make model IR=<model.json> OUT=<folder>            # a committed IR: render and compile only
    derive/.venv/bin/python derive/make_model.py --desc FILE --out DIR [--tasks FILE]
    derive/.venv/bin/python derive/make_model.py --ir FILE --out DIR

OUT then holds the library (`libtoolconf_model_<model>.so`; `.dylib` on macOS), its header
`toolconf_model.h`, and the crate they were built from (Cargo.toml, src/, tests/ and generated/,
the model's generated crate with its IR, report and CasADi vectors): `cargo test --workspace
--manifest-path OUT/Cargo.toml` checks every export against the Rust functions, bit for bit, and
the generated code against the vectors. docs/reference/c-abi.md describes the ABI.

Progress goes to stderr, one line per step as it finishes, with the seconds since the start and
the step's own: reading and validating, deriving (the equations, then each function's code),
checking (each function's test vectors against its reference), rendering, compiling. The last
line, on stdout, names what was made.

The arguments, the description and the task file (or the IR, by the renderer's whole check:
its text, names, file names and code) are read and checked before anything else (a mistake is
one line naming the file, the key and the value, status 2). make hands the arguments over in the
environment, as typed (`--from-make`: make_crate.make_arguments), never through a shell; a path
holding a newline or another control character is refused. OUT follows make
crate's rule (crates/files/src/folder.rs, asked through the renderer: derive/make_crate.py): it
must not exist, be empty, or be a folder make model made whose files are all as it wrote them
(cargo's Cargo.lock and target/ aside); it may not be a symbolic link, lie inside the repository,
or hold an input. Everything is made in a temporary folder beside OUT and moved into place at the
end, so a failure or an interrupt leaves the old OUT as it was. Nothing in the repository
changes: the renderer and the library build into the repository's target/ (ignored by git; the
library's build under target/make-model/, or $CARGO_TARGET_DIR/make-model). That build folder is
shared by every run, so that the dependencies are built once; runs at once take turns to build
and install their library (build_lock), the later one saying that it waits.

The library's crate builds on the repository it was made from (toolconf-cabi and toolconf-core
by path, the model's generated crate in place of the repository's by cargo's [patch]), so that
its exports run the very code the command line and the on-robot controller run.
"""

from __future__ import annotations

import os
import signal
import sys

COMMAND = "make model"


def _interrupted_while_starting(*_) -> None:
    """Ctrl-C while the derivation's modules load, before the run has started: one line and the
    shell's status for an interrupt, no traceback. It exits at once (os._exit): the handler can
    run inside a library's import, whose bare `except:` would swallow a SystemExit and let the run
    go on; nothing has been made yet."""
    print(f"{COMMAND}: interrupted; nothing changed", file=sys.stderr)
    sys.stderr.flush()
    os._exit(130)


# First, before the imports that take a second: an interrupt during them is the line above. make
# starts this with SIGINT blocked (the Makefile): one that came while Python started is delivered
# here, to the handler.
signal.signal(signal.SIGINT, _interrupted_while_starting)
signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

import fcntl  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402
import shutil  # noqa: E402
import stat  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from pathlib import Path  # noqa: E402

import make_crate  # noqa: E402
from make_crate import Failed, Refused, check_arguments, folder_rule, install, make_arguments, renderer, urdf_inputs  # noqa: E402
from toolconf_derive.description import MAX_NAME, RUST_NAME, check_tasks, load_model, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.files import read_text  # noqa: E402

ROOT = make_crate.ROOT
TASKS = make_crate.TASKS
# The largest IR read: derive/render/src/ir.rs's MAX_IR_BYTES (the Panda's is 5.5 MB).
MAX_IR_BYTES = 128 << 20
VECTORS_FILE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*\.vectors\.json", re.ASCII)


class Clock:
    """The progress lines: each step with the seconds since the start and its own."""

    def __init__(self) -> None:
        self.start = self.last = time.monotonic()
        self.steps: list[tuple[str, str, float]] = []

    def step(self, stage: str, what: str) -> None:
        now = time.monotonic()
        self.steps.append((stage, what, now - self.last))
        print(f"{COMMAND}: [{now - self.start:6.1f} s] {stage}: {what} ({now - self.last:.1f} s)",
              file=sys.stderr, flush=True)
        self.last = now


def read_description(desc: Path, tasks: Path):
    """The description and the task file, read and checked as make derive checks them before
    deriving (description.py): any mistake is Refused, one line."""
    if not desc.is_file():
        what = "does not exist" if not desc.exists() else "is not a file"
        raise Refused(f"DESC={desc}: {what}")
    try:
        task_list = load_tasks(tasks)
    except DescriptionError as err:
        raise Refused(f"TASKS={err}") from err
    try:
        model = load_model(desc)
        check_tasks(model, task_list)
    except DescriptionError as err:
        raise Refused(str(err)) from err
    return model


def read_ir(ir: Path) -> tuple[str, Path]:
    """A committed IR's model name and its test vectors beside it (`<name>.vectors.json`), read
    bounded (MAX_IR_BYTES) from a regular file; the renderer checks the rest (check_ir)."""
    if not os.path.lexists(ir):
        raise Refused(f"IR={ir}: does not exist")
    if not ir.name.endswith(".json") or ir.name.endswith(".vectors.json"):
        raise Refused(f"IR={ir}: not a model's IR (<model>.json, as make derive writes them into generated/)")
    try:
        document = json.loads(read_text(ir, MAX_IR_BYTES, "a model's IR"))
        name = document["model"]["name"]
        file = document["test_vectors"]["file"]
    except DescriptionError as err:
        raise Refused(f"IR={err}") from err
    except (ValueError, KeyError, TypeError, RecursionError) as err:
        raise Refused(f"IR={ir}: not a model's IR ({type(err).__name__}: {' '.join(str(err).split())[:200]})") from err
    if not isinstance(name, str) or not RUST_NAME.fullmatch(name) or len(name) > MAX_NAME:
        raise Refused(f"IR={ir}: model.name: {shown(name)} is not a model's name (a lower-case ASCII letter, then "
                      f"letters, digits or _, at most {MAX_NAME})")
    # A file beside the IR, by name: no folder, no link (a path out of the IR's folder, or a
    # link to one, would copy a file from elsewhere into OUT).
    if not isinstance(file, str) or not VECTORS_FILE.fullmatch(file):
        raise Refused(f"IR={ir}: test_vectors.file: {shown(file)} is not the name of a file beside the IR "
                      "(<model>.vectors.json; no folder)")
    vectors = ir.parent / file
    try:
        mode = os.lstat(vectors).st_mode
    except OSError:
        raise Refused(f"IR={ir}: its test vectors {vectors} are not beside it") from None
    if not stat.S_ISREG(mode):
        what = "a symbolic link" if stat.S_ISLNK(mode) else "not a regular file"
        raise Refused(f"IR={ir}: its test vectors {vectors} are {what}, not a file beside it")
    if os.lstat(vectors).st_size > MAX_IR_BYTES:
        raise Refused(f"IR={ir}: its test vectors {vectors} are larger than {MAX_IR_BYTES >> 20} MiB")
    return name, vectors


def shown(value) -> str:
    """A value quoted in a message: one line, at most 100 characters."""
    text = repr(value)
    return text if len(text) <= 100 else f"{text[:100]}… ({len(text)} characters)"


def check_ir(ir: Path) -> None:
    """The renderer's whole check of the IR (its shape, and each field of its kind: text, names,
    file names, code), before anything is made: its one line, status 2."""
    r = renderer("--check-ir", str(Path.cwd() / ir), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                 errors="replace")
    if r.returncode == 0:
        return
    last = (r.stderr.strip().splitlines() or [""])[-1].removeprefix("toolconf-render: ")
    if r.returncode == 2:
        raise Refused(f"IR={last}")
    sys.stderr.write(r.stderr)
    raise Failed(f"the renderer could not check IR={ir} (status {r.returncode})")


def derive(desc: Path, tasks: Path, folder: Path, clock: Clock) -> None:
    """derive.py for the one description into `folder`, its steps shown as they finish; its own
    one-line errors are passed on with its status."""
    cmd = [sys.executable, str(ROOT / "derive" / "derive.py"), str(Path.cwd() / desc), "--tasks",
           str(Path.cwd() / tasks), "--out-dir", str(folder), "--command", COMMAND, "--progress",
           "--jobs", str(os.cpu_count() or 1)]
    process = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               errors="replace")
    try:
        errors = []
        assert process.stderr is not None
        for line in process.stderr:
            parts = line.rstrip("\n").split("\t")
            if len(parts) == 3 and parts[0] == "progress":
                clock.step(parts[1], parts[2])
            else:
                errors.append(line)
                sys.stderr.write(line)
        out = process.stdout.read() if process.stdout else ""
        status = process.wait()
    finally:
        if process.poll() is None:
            process.terminate()
            process.wait()
    if status:
        raise SystemExit(status)
    summary = " ".join(out.split())
    if summary:
        print(f"{COMMAND}: {summary}", file=sys.stderr)


def render(ir: Path, staging: Path, clock: Clock) -> None:
    """The model's generated crate into staging/generated (the registry's templates, named
    toolconf-generated so that it stands in for the repository's) and the library's crate around
    it (templates/cabi/)."""
    generated = staging / "generated"
    steps = [
        ([str(ir), "--templates", str(ROOT / "templates"), "--out", str(generated), "--crate-name",
          "toolconf-generated"], "the generated crate (templates/registry/, model.rs.tera)"),
        ([str(ir), "--templates", str(ROOT / "templates"), "--model-library", str(staging), "--repository",
          str(ROOT)], "the library's crate and toolconf_model.h (templates/cabi/)"),
    ]
    for args, what in steps:
        r = renderer(*args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, errors="replace")
        if r.returncode:
            sys.stderr.write(r.stderr)
            raise Failed(f"rendering {what} failed")
        clock.step("rendering", what)


def target_dir() -> Path:
    """Where the library is built: a folder of its own in the repository's cargo target (the
    dependencies' builds are shared by every make model run)."""
    base = os.environ.get("CARGO_TARGET_DIR")
    return (Path(base) if base else ROOT / "target") / "make-model"


@contextmanager
def build_lock():
    """The one make model run at a time that builds in target_dir() and installs its OUT: two
    runs at once (to one OUT or to two) would otherwise overwrite or clean each other's library
    there. The dependencies' builds stay shared; a second run waits, saying so, and a run that
    ends releases the lock with its process."""
    folder = target_dir()
    folder.mkdir(parents=True, exist_ok=True)
    lock = folder / ".make-model.lock"
    with open(lock, "a") as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            print(f"{COMMAND}: waiting for another make model run to finish building in {folder} (it holds {lock})",
                  file=sys.stderr, flush=True)
            fcntl.flock(f, fcntl.LOCK_EX)
        yield


def compile_library(staging: Path, clock: Clock) -> Path:
    """cargo build --release of the library's crate; the shared library copied into staging.
    The repository's Cargo.lock seeds the crate's, so that it builds with the versions toolconf
    is built and tested with (and without the network, where they are in cargo's cache)."""
    shutil.copyfile(ROOT / "Cargo.lock", staging / "Cargo.lock")
    manifest = staging / "Cargo.toml"
    env = {**os.environ, "CARGO_TARGET_DIR": str(target_dir())}
    r = subprocess.run(["cargo", "build", "--release", "--manifest-path", str(manifest), "--message-format",
                        "json-render-diagnostics"], cwd=staging, env=env, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, errors="replace")
    if r.returncode:
        sys.stderr.write("".join(r.stderr.splitlines(keepends=True)[-40:]))
        raise Failed(f"cargo build --release --manifest-path {manifest} failed (status {r.returncode})")
    library = None
    for line in r.stdout.splitlines():
        try:
            message = json.loads(line)
        except ValueError:
            continue
        if message.get("reason") == "compiler-artifact" and "cdylib" in message.get("target", {}).get("kind", []):
            found = [Path(f) for f in message.get("filenames", []) if Path(f).suffix in (".so", ".dylib", ".dll")]
            library = found[0] if found else library
    if library is None:
        raise Failed(f"cargo built {manifest} but named no shared library")
    shutil.copyfile(library, staging / library.name)
    clock.step("compiling", f"{library.name} (cargo build --release, in {target_dir()})")
    # The crate's own builds are keyed by the staging folder's path, which no later run has:
    # removed, so that the folder keeps only what the next run can use (the dependencies').
    subprocess.run(["cargo", "clean", "--release", "--manifest-path", str(manifest), "-p", "toolconf-generated",
                    "-p", "toolconf-core", "-p", "toolconf-cabi", "-p", library_package(staging), "--quiet"],
                   cwd=staging, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return staging / library.name


def library_package(staging: Path) -> str:
    """The library crate's package name (its Cargo.toml's first `name = "..."`)."""
    for line in (staging / "Cargo.toml").read_text().splitlines():
        if line.startswith("name = "):
            return line.split('"')[1]
    return "toolconf-model"


def build_renderer() -> float:
    """Builds toolconf-render (the folder rule and the rendering run it) where it is not built
    yet, before anything is shown: the seconds that took (after `make run`: 46 s, the release
    build sharing its dependencies; make_crate.RENDERER_PROFILE says why release)."""
    started = time.monotonic()
    r = subprocess.run(["cargo", "build", *make_crate.RENDERER_PROFILE, "--quiet", "-p", "toolconf-render"], cwd=ROOT,
                       stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True, errors="replace")
    if r.returncode:
        sys.stderr.write(r.stderr)
        raise Failed("cargo build -p toolconf-render failed: the renderer is needed to check OUT and render")
    return time.monotonic() - started


def make_model(desc: Path | None, ir: Path | None, out: Path, tasks: Path) -> int:
    clock = Clock()
    check_arguments(COMMAND, [("DESC", desc), ("IR", ir), ("OUT", out), ("TASKS", tasks)])
    out = Path(os.path.abspath(out))
    # Everything is checked (the input, then OUT) before the first line of progress.
    if desc is not None:
        model = read_description(desc, tasks)
        name = model.name
        files = [(f"DESC={desc}", desc), (f"TASKS={tasks}", tasks)] + urdf_inputs([desc])
        read = f"{desc} (model {name}, {model.dof} DOF) and {tasks}: valid; OUT={out}: may be made"
    else:
        assert ir is not None
        name, vectors = read_ir(ir)
        files = [(f"IR={ir}", ir), (f"the test vectors of IR={ir}", vectors)]
        read = f"{ir} (model {name}), derived before: no derivation; OUT={out}: may be made"
    built = build_renderer()
    if ir is not None:
        check_ir(ir)
    folder_rule(["--check-crate-out", str(out)], files, COMMAND)
    if built > 2:
        read += f" (toolconf-render built first: {built:.0f} s)"
    clock.step("reading", read)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}-partial-", dir=out.parent))
    try:
        generated = staging / "generated"
        generated.mkdir()
        if desc is not None:
            derive(desc, tasks, generated, clock)
            ir_file = generated / f"{name}.json"
        else:
            assert ir is not None
            ir_file = generated / ir.name
            shutil.copyfile(ir, ir_file)
            shutil.copyfile(vectors, generated / vectors.name)
        render(ir_file, staging, clock)
        with build_lock():
            library = compile_library(staging, clock)
            install(staging, out, files, COMMAND)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    print(f"{COMMAND}: {out}: {library.name} and toolconf_model.h (model {name}, C ABI of crates/cabi) in "
          f"{time.monotonic() - clock.start:.0f} s; check it with "
          f"`cargo test --workspace --manifest-path {out / 'Cargo.toml'}`")
    return 0


def main() -> int:
    # make's arguments come in the environment, as typed (the Makefile's `model` target).
    argv = make_arguments([("DESC", "--desc"), ("IR", "--ir"), ("OUT", "--out"), ("TASKS", "--tasks")])
    ap = make_crate.Arguments(COMMAND, "make model DESC=<description> OUT=<folder> [TASKS=<file>], "
                              "or IR=<model.json> OUT=<folder>", __doc__)
    source = ap.add_mutually_exclusive_group(required=True)
    source.add_argument("--desc", type=Path, help="the model description (TOML)")
    source.add_argument("--ir", type=Path, help="a model's IR derived before (generated/<model>.json)")
    ap.add_argument("--out", type=Path, required=True, help="the library's folder (new, empty, or made by this)")
    ap.add_argument("--tasks", type=Path, default=None, help="task definitions (default derive/tasks.toml)")
    args = ap.parse_args(argv)
    if args.ir is not None and args.tasks is not None:
        ap.error("TASKS= goes with DESC=: an IR was derived with its task definitions")
    tasks = args.tasks if args.tasks is not None else TASKS
    # From here an interrupt is the run's: run_reported says it and the old OUT stays.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    return make_crate.run_reported(COMMAND, args.out, lambda: make_model(args.desc, args.ir, args.out, tasks))


if __name__ == "__main__":
    sys.exit(main())
