#!/usr/bin/env python3
"""A standalone no_std crate from a user's own model descriptions (`make crate`): each
description derived and checked as `make derive` does (derive.py: SymPy, checked by CasADi), then
rendered through the same templates, the crate's Cargo.toml included, into a folder outside
toolconf's workspace:

    make crate MODELS=<folder of *.toml> OUT=<folder> [TASKS=<file>] [NAME=<crate name>]
    derive/.venv/bin/python derive/make_crate.py --models DIR --out DIR [--tasks FILE] [--name NAME]

The crate holds Cargo.toml, src/lib.rs (the registry), src/tasks.rs, one src/<model>.rs per
model (named by the description's model.name, whatever its file is called), src/trig.rs,
src/powi.rs, each model's report, IR and CasADi vectors, and tests/vectors.rs, which checks every
generated function against the vectors: `cargo test --manifest-path OUT/Cargo.toml`. The tasks
are derive/tasks.toml's unless TASKS names other task definitions; the crate is named after OUT
unless NAME is given.

Everything is written into a temporary folder beside OUT and renamed into place at the end, so a
failure or an interrupt (Ctrl-C, SIGTERM, SIGHUP) leaves nothing behind and keeps the crate that
was there. What may happen to OUT is the one output-file rule of the command line and the reports,
in Rust (crates/files/src/folder.rs), which this script asks through the renderer before deriving
anything (toolconf-render --check-crate-out) and again to move the crate into place
(--install-crate). The crate holds an ownership manifest, .toolconf-crate, listing every file this
command wrote with its SHA-256; OUT must not exist, be an empty folder, or be a crate this command
made whose files are all still as listed, with nothing else in it but cargo's Cargo.lock and
target/ (which the new crate keeps): only then is it replaced. OUT may not be a symbolic link, lie
inside the repository, or hold the descriptions, their URDFs or the task file, and the crate gets
the permissions of any folder the user makes (0777 less the umask). Nothing in the repository
changes (the derivation runs in place, the renderer builds into target/). Bad input is one line
naming the file, key or value, status 2. make hands the arguments over in the environment, as
typed (`--from-make`: make_arguments), never through a shell; a path holding a newline or another
control character is refused (check_arguments).
"""

from __future__ import annotations

import os
import signal
import sys


def _interrupted_while_starting(*_) -> None:
    """Ctrl-C while the derivation's modules load, before the run has started: one line and the
    shell's status for an interrupt, no traceback. It exits at once (os._exit): the handler can
    run inside a library's import, whose bare `except:` would swallow a SystemExit and let the run
    go on; nothing has been made yet."""
    print("make crate: interrupted; nothing changed", file=sys.stderr)
    sys.stderr.flush()
    os._exit(130)


# First, before the imports that take a second: an interrupt during them is the line above. make
# starts this with SIGINT blocked (the Makefile): one that came while Python started is delivered
# here, to the handler.
if __name__ == "__main__":
    signal.signal(signal.SIGINT, _interrupted_while_starting)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

import argparse  # noqa: E402
import re  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
from concurrent.futures import ThreadPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

from toolconf_derive.description import RUST_KEYWORDS, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.files import read_toml, refused_character  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TASKS = ROOT / "derive" / "tasks.toml"
COMMAND = "make crate"
# Crates the generated crate names in its code: Rust's own, and the dependencies of
# templates/registry/Cargo.toml.tera (a test keeps this list and the template in step).
TAKEN_CRATE_NAMES = ("std", "core", "alloc", "proc_macro", "test", "nalgebra", "libm", "serde", "serde_json")


class Refused(Exception):
    """Bad input: the message (one line) and status 2."""


class Failed(Exception):
    """A failure to write OUT once the input was good: the message (one line) and status 1."""


def crate_name(out: Path, name: str | None) -> str:
    """The package name: NAME, or OUT's folder name; a Cargo package name either way, whose
    library name (- as _) the crate's own code can use as a path."""
    chosen = name if name is not None else out.name
    where = "NAME" if name is not None else f"OUT={out} (its folder name)"
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]*", chosen):
        raise Refused(f"{where}: '{chosen}' is not a crate name (a letter, then letters, digits, - or _); give NAME=")
    library = chosen.replace("-", "_")
    if library in RUST_KEYWORDS or library == "Self":
        raise Refused(f"{where}: '{chosen}' is a Rust keyword, which cannot name a crate; give NAME=")
    if library in TAKEN_CRATE_NAMES:
        raise Refused(f"{where}: '{chosen}' is the name of a crate the generated crate uses "
                      f"({', '.join(TAKEN_CRATE_NAMES)}); give NAME=")
    return chosen


def descriptions(models: Path) -> list[Path]:
    if not models.is_dir():
        raise Refused(f"MODELS={models}: not a folder")
    found = sorted(models.glob("*.toml"))
    if not found:
        raise Refused(f"MODELS={models}: no model descriptions (*.toml) in it")
    return found


def duplicate_model_names(found: list[Path]) -> None:
    """Two descriptions of one model would write one module twice. A description that does not
    parse is left for derive.py to report."""
    seen: dict[str, Path] = {}
    for path in found:
        try:
            model = read_toml(path).get("model", {})
        except DescriptionError:
            continue
        name = model.get("name") if isinstance(model, dict) else None
        if isinstance(name, str):
            if name in seen:
                raise Refused(f"{seen[name]} and {path} both describe the model '{name}' (model.name)")
            seen[name] = path


def inputs(models: Path, found: list[Path], tasks: Path) -> list[tuple[str, Path]]:
    """Every file the run reads, named as in its error: the descriptions' folder, the
    descriptions, the URDFs they name (resolved as the derivation resolves them) and the task
    file."""
    files = [(f"MODELS={models}", models)] + [(f"description {p}", p) for p in found] + [(f"TASKS={tasks}", tasks)]
    return files + urdf_inputs(found)


def urdf_inputs(found: list[Path]) -> list[tuple[str, Path]]:
    """The URDFs the descriptions name, resolved as the derivation resolves them (beside the
    description), each labelled for the folder rule's messages."""
    files = []
    for path in found:
        try:
            urdf = read_toml(path).get("urdf", {})
        except (DescriptionError, AttributeError):
            continue  # the derivation names what is wrong with it
        if isinstance(urdf, dict) and isinstance(urdf.get("file"), str):
            files.append((f"the URDF of {path}", Path(os.path.normpath(path.parent / urdf["file"]))))
    return files


def _dof(path: Path) -> int:
    try:
        return int(read_toml(path).get("model", {}).get("dof", 1))
    except (DescriptionError, AttributeError, TypeError, ValueError, OverflowError):
        return 1


def derive_all(found: list[Path], tasks: Path, folder: Path) -> int:
    """derive.py for every description into `folder`, largest first, as many at once as there
    are cores; its one-line errors are passed on. The worst status, 0 if all succeeded."""
    def derive(path: Path):
        # derive.py runs in the repository: a path relative to where make crate was run is made whole.
        cmd = [sys.executable, str(ROOT / "derive" / "derive.py"), str(Path.cwd() / path), "--tasks",
               str(Path.cwd() / tasks), "--out-dir", str(folder), "--command", COMMAND]
        return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)

    jobs = sorted(found, key=lambda p: -_dof(p))
    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as pool:
        results = list(pool.map(derive, jobs))
    for r in results:
        sys.stdout.write(r.stdout)
        sys.stderr.write(r.stderr)
    return max(r.returncode for r in results)


# The renderer's profile for make crate and make model: release, whose dependencies (serde,
# serde_json, sha2, toolconf-files) `make run`'s build of the command line has already compiled,
# so that a clone set up by `make run` builds only the rest (46 s on this 2-core machine, against
# 72 s for a debug build from nothing: the first `make model` of a new robot within 3 minutes).
RENDERER_PROFILE = ("--release",)


def renderer(*args: str, **run) -> subprocess.CompletedProcess:
    """The renderer, toolconf-render, built into the repository's target/ when it is not."""
    return subprocess.run(["cargo", "run", *RENDERER_PROFILE, "--quiet", "-p", "toolconf-render", "--", *args],
                          cwd=ROOT, **run)


def render(folder: Path, name: str) -> int:
    irs = sorted(p for p in folder.glob("*.json") if not p.name.endswith(".vectors.json"))
    return renderer(*map(str, irs), "--templates", str(ROOT / "templates"), "--out", str(folder),
                    "--crate-name", name, "--standalone", stdout=subprocess.DEVNULL).returncode


def folder_rule(args: list[str], files: list[tuple[str, Path]], command: str = COMMAND) -> None:
    """The rule for OUT (crates/files/src/folder.rs, through the renderer), with every input of
    the run, for a folder `command` makes (make crate's or make model's); its refusal is raised as
    Refused, its failure to write as Failed. Paths go absolute but unresolved: the renderer runs
    in the repository and resolves them as the rule says."""
    args = [*args, "--repository", str(ROOT), "--command", command]
    for label, path in files:
        args += ["--input", label, str(Path.cwd() / path)]
    r = renderer(*args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, errors="replace")
    if r.returncode == 0:
        return
    last = (r.stderr.strip().splitlines() or [""])[-1]
    # Its own line is the last; anything before it is cargo's, building the renderer.
    if r.returncode in (1, 2) and last.startswith("toolconf-render: "):
        message = last.removeprefix("toolconf-render: ")
        raise Refused(message) if r.returncode == 2 else Failed(message)
    sys.stderr.write(r.stderr)
    raise Failed(f"the rule for OUT did not run: toolconf-render {args[0]} ended with status {r.returncode}")


INTERRUPTS = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}


def install(tmp: Path, out: Path, files: list[tuple[str, Path]], command: str = COMMAND) -> None:
    """Moves the finished crate into place by the rule, which checks OUT again, writes the
    ownership manifest and swaps the crates with the interrupts blocked. They wait here too until
    it is done: this process ending would end the renderer half-way."""
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, INTERRUPTS)
    try:
        folder_rule(["--install-crate", str(tmp), "--out", str(out)], files, command)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def make_crate(models: Path, out: Path, tasks: Path, name: str | None) -> int:
    check_arguments(COMMAND, [("MODELS", models), ("OUT", out), ("TASKS", tasks), ("NAME", name)])
    out = Path(os.path.abspath(out))  # the crate is named after the name given, links and all
    package = crate_name(out, name)
    found = descriptions(models)
    duplicate_model_names(found)
    try:
        load_tasks(tasks)  # read as derive.py reads it: a FIFO, a device or bad TOML is one line now
    except DescriptionError as err:
        raise Refused(f"TASKS={err}") from err
    files = inputs(models, found, tasks)
    folder_rule(["--check-crate-out", str(out)], files)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}-partial-", dir=out.parent))
    try:
        status = derive_all(found, tasks, tmp)
        if status:
            return status
        if render(tmp, package):
            print("make crate: rendering failed", file=sys.stderr)
            return 1
        made = sorted(p.stem for p in tmp.glob("*.json") if not p.name.endswith(".vectors.json"))
        install(tmp, out, files)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"make crate: {out}: crate {package} with the models {', '.join(made)}; "
          f"check it with `cargo test --manifest-path {out / 'Cargo.toml'}`")
    return 0


# make's arguments, as the Makefile hands them over: each variable's text as typed (make's
# `$(value ...)`), in the environment under this prefix, never through a shell command line.
MAKE_PREFIX = "TOOLCONF_MAKE_"


def make_arguments(names: list[tuple[str, str]]) -> list[str] | None:
    """With the only argument `--from-make` (the Makefile's targets): the options of the make
    variables given, `--out=<OUT as typed>`, from the environment; else None (sys.argv's)."""
    if sys.argv[1:] != ["--from-make"]:
        return None
    return [f"{flag}={os.environ[MAKE_PREFIX + name]}" for name, flag in names
            if os.environ.get(MAKE_PREFIX + name)]


def check_arguments(command: str, given: list[tuple[str, Path | str | None]]) -> None:
    """Each path or name given is one line of text: a line break or another control character in
    one is refused, naming the argument (it would reach messages, file names and generated
    files)."""
    for label, value in given:
        if value is None:
            continue
        c = refused_character(str(value))
        if c is not None:
            text = str(value)
            shown = repr(text if len(text) <= 100 else text[:100] + "…")
            raise Refused(f"{label}={shown}: holds U+{ord(c):04X} (a control character or line break) at character "
                          f"{text.index(c) + 1}; give a path of one line")


class Arguments(argparse.ArgumentParser):
    """Argument errors as one line and status 2, as every other refusal: `command`'s message and
    its make usage."""

    def __init__(self, command: str, make_usage: str, description: str | None):
        super().__init__(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)
        self.command, self.make_usage = command, make_usage

    def error(self, message: str):
        print(f"{self.command}: {message} (usage: {self.make_usage})", file=sys.stderr)
        raise SystemExit(2)


def main() -> int:
    argv = make_arguments([("MODELS", "--models"), ("OUT", "--out"), ("TASKS", "--tasks"), ("NAME", "--name")])
    ap = Arguments(COMMAND, "make crate MODELS=<folder of model descriptions> OUT=<folder> [TASKS=<file>] "
                   "[NAME=<crate>]", __doc__)
    ap.add_argument("--models", type=Path, required=True, help="folder of model descriptions (*.toml)")
    ap.add_argument("--out", type=Path, required=True, help="the crate's folder (new, empty, or made by this)")
    ap.add_argument("--tasks", type=Path, default=TASKS, help="task definitions (default derive/tasks.toml)")
    ap.add_argument("--name", help="the crate's package name (default: OUT's folder name)")
    args = ap.parse_args(argv)
    # From here an interrupt is the run's: run_reported says it and the old OUT stays.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    return run_reported("make crate", args.out, lambda: make_crate(args.models, args.out, args.tasks, args.name))


def run_reported(command: str, out: Path, body) -> int:
    """`body()`'s status, every way it can end as one line on stderr naming `command`: a refusal
    (status 2), a failure (1), an interrupt (130, nothing changed), an OSError naming a path, and
    anything unforeseen (1, never a traceback). A terminated or hung-up run cleans up as an
    interrupted one does (the temporary folder goes, the old OUT stays), and ends with the shell's
    status for the signal."""
    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, lambda number, _: sys.exit(128 + number))
    try:
        return body()
    except Refused as err:
        print(f"{command}: {err}", file=sys.stderr)
        return 2
    except Failed as err:
        print(f"{command}: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{command}: interrupted; nothing changed", file=sys.stderr)
        return 130
    except OSError as err:
        print(f"{command}: {os_error(err, out)}", file=sys.stderr)
        return 1
    except Exception as err:  # noqa: BLE001 - the last resort: one line, never a traceback
        reason = " ".join(str(err).split()) or "no message"
        print(f"{command}: error: {type(err).__name__}: {reason[:300]}", file=sys.stderr)
        return 1


def os_error(err: OSError, out: Path) -> str:
    """An OSError in words that always name a path (OUT's, when the error names none)."""
    path = err.filename if err.filename is not None else out
    also = f" -> {err.filename2}" if err.filename2 is not None else ""
    return f"cannot write {path}{also}: {err.strerror or err}"


if __name__ == "__main__":
    sys.exit(main())
