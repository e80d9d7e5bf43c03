#!/usr/bin/env python3
"""The whole derivation chain: every model description -> derive.py (SymPy, checked by CasADi) ->
IR + test vectors -> toolconf-render (Tera + rustfmt) -> generated/, and the renderer's fixture.

    derive/.venv/bin/python derive/pipeline.py                    # update generated/ (make derive)
    derive/.venv/bin/python derive/pipeline.py --check            # drift check
    derive/.venv/bin/python derive/pipeline.py --check --portability   # and on an imitated older CPU

--check derives into a temporary folder and compares it byte for byte with generated/ and the
fixtures: it names every differing, missing or stale file and its first differing line, and
never touches the working tree (no git needed). --portability derives a second time with
numpy's optional CPU kernels switched off (NPY_DISABLE_CPU_FEATURES: every dispatchable feature
numpy finds on this machine, AVX-512 and AVX2 included) and glibc's libm held to its baseline
(GLIBC_TUNABLES), imitating an older CPU: the committed bytes must come out all the same. Both
derivations share the machine's cores (make test runs them together).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "derive"))
from toolconf_derive.description import check_tasks, load_model, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.reference import description_reference  # noqa: E402

MODELS = ROOT / "derive" / "models"
GENERATED = ROOT / "generated"
FIXTURES = ROOT / "tests" / "fixtures"
# The description file's reference, written from the reader's key tables (reference.py).
REFERENCE = ROOT / "docs" / "reference" / "description.md"
# The renderer's fixture: a small model with few vectors, pinned by tests/render_snapshot.rs.
FIXTURE_MODELS = [("pendulum", 3)]
# glibc's x86 features whose ifunc variants (libm's sin, cos, exp, log, pow...) depend on them.
GLIBC_OFF = ["AVX512F", "AVX512DQ", "AVX512BW", "AVX512VL", "AVX2", "FMA", "FMA4", "AVX"]


def _numpy_optional_features(env: dict[str, str]) -> list[str]:
    """The dispatchable CPU features numpy uses under `env` (its baseline is not among them)."""
    probe = ("from numpy._core import _multiarray_umath as m;"
             "print(' '.join(f for f in m.__cpu_dispatch__ if m.__cpu_features__.get(f)))")
    return subprocess.run([sys.executable, "-c", probe], env=env, check=True, capture_output=True,
                          text=True).stdout.split()


def restricted_environment(base: dict[str, str]) -> dict[str, str]:
    """The environment of an older CPU: numpy's dispatch reduced to its baseline, libm's to SSE2."""
    found = _numpy_optional_features(base)
    env = dict(base)
    if found:
        env["NPY_DISABLE_CPU_FEATURES"] = ",".join(found)
    env["GLIBC_TUNABLES"] = "glibc.cpu.hwcaps=" + ",".join("-" + f for f in GLIBC_OFF)
    still = _numpy_optional_features(env)
    if still:
        raise SystemExit(f"pipeline: NPY_DISABLE_CPU_FEATURES did not switch off numpy's {' '.join(still)}")
    print(f"pipeline: restricted CPU: numpy's optional kernels off ({','.join(found) or 'none found'}), "
          f"glibc hwcaps {env['GLIBC_TUNABLES'].split('=', 1)[1]}")
    return env


@dataclass
class Run:
    """One derivation of every model into `generated` and `fixtures` under `env`."""
    env: dict[str, str]
    generated: Path
    fixtures: Path

    def model_jobs(self) -> list[tuple[Path, Path, int]]:
        """(description, IR to write, vectors per function) for every model under derive/models."""
        return [(m, self.generated / f"{m.stem}.json", 100) for m in sorted(MODELS.glob("*.toml"))]

    def jobs(self) -> list[tuple[Path, Path, int]]:
        """The models' jobs and the renderer's fixtures'."""
        return self.model_jobs() + [(FIXTURES / f"{name}.toml", self.fixtures / f"{name}.json", n)
                                    for name, n in FIXTURE_MODELS]


def _cost(model: Path) -> int:
    """The derivation's cost grows steeply with the degrees of freedom: start the largest first."""
    with model.open("rb") as f:
        return int(tomllib.load(f).get("model", {}).get("dof", 1))


def validate_all(runs: list[Run]) -> None:
    """Reads and checks every description and the task file before anything is derived, so a
    mistake in one is reported at once, with every other mistake, not after the others' minutes
    of derivation (the checks of description.py; what only the derivation can find, such as an
    equilibrium residual, is reported as soon as that model's derivation stops)."""
    problems = []
    tasks = None
    try:
        tasks = load_tasks(ROOT / "derive" / "tasks.toml")
    except DescriptionError as err:
        problems.append(str(err))
    for model in sorted({job[0] for run in runs for job in run.jobs()}):
        try:
            # Its goals and [formulation] against the tasks too, where the task file could be read.
            description = load_model(model)
            if tasks is not None:
                check_tasks(description, tasks)
        except DescriptionError as err:
            problems.append(str(err))
    for p in problems:
        print(f"error: {p}", file=sys.stderr)
    if problems:
        print(f"pipeline: {len(problems)} description(s) refused; nothing was derived", file=sys.stderr)
        raise SystemExit(2)


def derive_all(runs: list[Run]) -> None:
    """Runs derive.py for every model of every run (as many at once as there are cores, largest
    models first), then the renderer for each run's generated/. Each model is reported as it
    finishes; the first failure is shown at once and the derivations not yet started are
    cancelled."""
    validate_all(runs)
    jobs = sorted(((run, *job) for run in runs for job in run.jobs()), key=lambda j: -_cost(j[1]))
    start = time.monotonic()

    def derive(job):
        run, model, out, vectors = job
        cmd = [sys.executable, str(ROOT / "derive" / "derive.py"), str(model.relative_to(ROOT)),
               "--out", str(out), "--vectors", str(vectors)]
        return subprocess.run(cmd, cwd=ROOT, env=run.env, capture_output=True, text=True)

    failed = False
    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as pool:
        futures = {pool.submit(derive, job): job for job in jobs}
        done = 0
        for future in as_completed(futures):
            if future.cancelled():
                continue
            done += 1
            r, model = future.result(), futures[future][1]
            sys.stdout.write(r.stdout)
            sys.stderr.write(r.stderr)
            state = "failed" if r.returncode else "derived"
            print(f"pipeline: {state} {model.stem} ({done}/{len(jobs)}, {time.monotonic() - start:.0f} s)",
                  file=sys.stderr, flush=True)
            if r.returncode and not failed:
                failed = True
                for f in futures:
                    f.cancel()
    if failed:
        raise SystemExit(1)
    for run in runs:
        irs = [str(out) for _, out, _ in run.model_jobs()]
        # release, as make crate and make model build it: one renderer build serves all three.
        render = ["cargo", "run", "--release", "--quiet", "-p", "toolconf-render", "--", *irs,
                  "--templates", str(ROOT / "templates"), "--out", str(run.generated)]
        if subprocess.run(render, cwd=ROOT, env=run.env).returncode:
            raise SystemExit(1)


def first_difference(a: bytes, b: bytes) -> str:
    la, lb = a.decode(errors="replace").splitlines(), b.decode(errors="replace").splitlines()
    for i, (x, y) in enumerate(zip(la, lb)):
        if x != y:
            return f"line {i + 1}:\n    committed: {x.strip()[:160]}\n    derived:   {y.strip()[:160]}"
    return f"line {min(len(la), len(lb)) + 1}: one file ends there ({len(la)} vs {len(lb)} lines)"


def files_under(folder: Path) -> set[Path]:
    """Every file under `folder`, sub-folders included, relative to it."""
    return {p.relative_to(folder) for p in folder.rglob("*") if p.is_file()}


def compare(derived: Path, committed: Path, whole_folder: bool) -> list[str]:
    """Problems found comparing the tree `derived` with `committed` (relative to the repository).
    With `whole_folder`, a committed file that the derivation no longer produces is stale too."""
    problems = []
    made = files_under(derived)
    for name in sorted(made):
        target = committed / name
        where = target.relative_to(ROOT)
        if not target.is_file():
            problems.append(f"{where}: make derive produces it, but it is not there")
            continue
        a, b = target.read_bytes(), (derived / name).read_bytes()
        if a != b:
            problems.append(f"{where} differs from what make derive produces, first at {first_difference(a, b)}")
    if whole_folder:
        for name in sorted(files_under(committed) - made):
            problems.append(f"{(committed / name).relative_to(ROOT)}: make derive no longer produces it (stale)")
    return problems


def write_replacing(path: Path, data: bytes) -> None:
    """`data` into `path` through a temporary file beside it: an interrupted write keeps the old
    file, and leaves no temporary file."""
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{path.name}.", delete=False) as f:
        f.write(data)
    try:
        os.replace(f.name, path)
    finally:
        if os.path.exists(f.name):
            os.unlink(f.name)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="derive into a temporary folder and compare")
    ap.add_argument("--portability", action="store_true",
                    help="with --check: also derive on an imitated CPU without AVX/AVX2/AVX-512/FMA and compare")
    args = ap.parse_args()
    env = dict(os.environ)
    env.setdefault("PYTHONHASHSEED", "0")
    reference = description_reference().encode()
    if not args.check:
        derive_all([Run(env, GENERATED, FIXTURES)])
        if not REFERENCE.exists() or REFERENCE.read_bytes() != reference:
            write_replacing(REFERENCE, reference)
        return 0
    checks = [("drift check", env)]
    if args.portability:
        checks.append(("restricted-CPU derivation", restricted_environment(env)))
    with tempfile.TemporaryDirectory(prefix="toolconf-derive-") as tmp:
        runs = []
        for k, (_, e) in enumerate(checks):
            run = Run(e, Path(tmp, str(k), "generated"), Path(tmp, str(k), "fixtures"))
            run.generated.mkdir(parents=True)
            run.fixtures.mkdir(parents=True)
            runs.append(run)
        derive_all(runs)
        failed = False
        for (what, _), run in zip(checks, runs):
            problems = compare(run.generated, GENERATED, True) + compare(run.fixtures, FIXTURES, False)
            if not REFERENCE.exists():
                problems.append(f"{REFERENCE.relative_to(ROOT)}: missing")
            elif REFERENCE.read_bytes() != reference:
                problems.append(f"{REFERENCE.relative_to(ROOT)}: {first_difference(REFERENCE.read_bytes(), reference)}")
            if problems:
                failed = True
                print(f"{what}: the committed generated files are not what make derive produces:", file=sys.stderr)
                for p in problems:
                    print(f"  {p}", file=sys.stderr)
            else:
                print(f"{what}: generated/ and tests/fixtures/ are byte for byte what make derive produces")
    if failed:
        print("run `make derive`, review the diff, and commit it", file=sys.stderr)
        return 1
    return 0


def guarded() -> int:
    """main() behind a last resort: an unforeseen error is one line and status 1, not a traceback."""
    try:
        return main()
    except Exception as err:  # noqa: BLE001 - SystemExit (the expected failures) passes through
        reason = " ".join(str(err).split()) or "no message"
        print(f"pipeline: error: {type(err).__name__}: {reason[:300]}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(guarded())
