#!/usr/bin/env python3
"""Derive a model: read its description, derive it with SymPy, check it against CasADi, and write
the JSON IR that toolconf-render turns into generated/<model>.rs and generated/<model>.md, and
beside it the CasADi test vectors (<name>.vectors.json for --out <name>.json).

    derive/.venv/bin/python derive/derive.py derive/models/arm2.toml --out generated/arm2.json

`make derive` runs this for every model and then renders; run that instead.
"""

from __future__ import annotations

import signal
import sys

# An interrupt is no error: the run ends quietly with the shell's status for it (make model, which
# runs this, says it in one line), even while the modules below load.
signal.signal(signal.SIGINT, lambda *_: sys.exit(130))

import argparse  # noqa: E402
import json  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from toolconf_derive import progress  # noqa: E402
from toolconf_derive.crosscheck import DerivationMismatch  # noqa: E402
from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.files import text_problem  # noqa: E402
from toolconf_derive.functions import build_functions  # noqa: E402
from toolconf_derive.exact import ExactEvaluationError  # noqa: E402
from toolconf_derive.ir import IR_SCHEMA, model_ir, vectors_document  # noqa: E402
from toolconf_derive.ir_types import Generator, as_json  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.report import report_data  # noqa: E402
from toolconf_derive.sequence import SequenceError  # noqa: E402
from toolconf_derive.symbolic import derive  # noqa: E402
from toolconf_derive.urdf_functions import urdf_documents  # noqa: E402
from toolconf_derive.urdf_model import UrdfMismatch  # noqa: E402

# Test vectors per function for a URDF model (make derive asks 100 of every model).
URDF_VECTORS = 12


def shown(path: Path, root: Path) -> str:
    """A path as the generated files name it: relative to the repository when inside it, so the
    bytes do not depend on where the checkout is."""
    resolved = path.resolve()
    return str(resolved.relative_to(root)) if resolved.is_relative_to(root) else str(path)


def write(path: Path, document) -> None:
    """`document` (ir_types' dataclasses, or a dict of them) as JSON."""
    path.write_text(json.dumps(as_json(document), indent=1, ensure_ascii=False) + "\n")


def main() -> int:
    """derive.py's run behind a last resort: whatever goes wrong unforeseen is one line and status
    1 (a traceback is no message for a user)."""
    # Overflow and invalid values are checked where they matter (crosscheck, exact) and reported
    # as one line; NumPy's own warnings would only add lines to it.
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    try:
        return run()
    except Exception as err:  # noqa: BLE001 - the last resort, every expected error is handled in run()
        reason = one_line(str(err)) or "no message"
        print(f"derive: error: {' '.join(sys.argv[1:2])}: {type(err).__name__}: {reason[:300]}", file=sys.stderr)
        return 1


def one_line(text: str) -> str:
    return " ".join(text.split())


def run() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model", type=Path, help="model description (TOML)")
    ap.add_argument("--tasks", type=Path, default=HERE / "tasks.toml", help="task definitions (TOML)")
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", type=Path,
                       help="where to write the JSON IR (any path ending in .json; the vectors go beside it)")
    where.add_argument("--out-dir", type=Path,
                       help="the folder to write <model name>.json and its vectors into (the name is the "
                            "description's model.name, whatever the file is called)")
    ap.add_argument("--vectors", type=int, default=100, help="test vectors per function (default 100)")
    ap.add_argument("--command", default="make derive",
                    help="the command the generated files name as their maker (default: make derive)")
    ap.add_argument("--jobs", type=int, default=1,
                    help="processes checking a URDF model's functions (default 1; make model: every core)")
    ap.add_argument("--progress", action="store_true",
                    help="report each step as it finishes on stderr (toolconf_derive/progress.py; make model)")
    args = ap.parse_args()
    if args.progress:
        progress.enable(sys.stderr)
    root = HERE.parent
    if args.out is not None and args.out.suffix != ".json":
        print(f"derive: --out {args.out}: the IR's file name must end in .json", file=sys.stderr)
        return 2
    folder = args.out_dir if args.out is None else args.out.parent
    if not folder.is_dir():
        flag = f"--out {args.out}" if args.out is not None else f"--out-dir {args.out_dir}"
        print(f"derive: {flag}: the folder {folder} does not exist", file=sys.stderr)
        return 2
    if args.jobs < 1:
        print(f"derive: --jobs {args.jobs}: need at least one process", file=sys.stderr)
        return 2
    if args.vectors < 1:
        print(f"derive: --vectors {args.vectors}: need at least one test vector per function", file=sys.stderr)
        return 2
    for flag, path in (("model", args.model), ("--tasks", args.tasks)):
        # The paths are named in the generated files: one line of text.
        problem = text_problem(str(path))
        if problem:
            print(f"derive: {flag} {str(path)!r}: {problem}", file=sys.stderr)
            return 2
    try:
        model = load_model(args.model)
        out = args.out if args.out is not None else args.out_dir / f"{model.name}.json"
        vectors_out = out.with_suffix(".vectors.json")
        tasks = load_tasks(args.tasks)
        # Names, not the paths written to: the same bytes wherever --out points (the drift check
        # derives into a temporary folder and compares).
        generator = Generator(
            command=args.command,
            model=shown(args.model, root),
            tasks=shown(args.tasks, root),
            ir=out.name,
            vectors=vectors_out.name,
            derive="derive/derive.py (SymPy derives, CasADi checks)",
            render="derive/render (Tera) + rustfmt",
        )
        if model.dynamics_kind == "urdf":
            # CasADi SX, not SymPy (derive/toolconf_derive/urdf_model.py); each test vector is
            # checked in 50-digit arithmetic on two graphs of thousands of instructions, so fewer.
            generator.derive = "derive/derive.py (CasADi SX: RNEA/CRBA/LDL^T, checked against ABA)"
            ir, vectors = urdf_documents(model, tasks, generator, min(args.vectors, URDF_VECTORS), IR_SCHEMA,
                                        args.jobs)
        else:
            d = derive(model, tasks)
            functions = build_functions(d, CasadiModel(model))
            ir = model_ir(d, functions, generator, report_data(d), args.vectors)
            vectors = vectors_document(d, functions, generator, args.vectors)
    except DescriptionError as err:
        # Bad input: one line naming the file, the key and the problem.
        print(f"derive: {err}", file=sys.stderr)
        return 2
    except (DerivationMismatch, ExactEvaluationError, UrdfMismatch, SequenceError) as err:
        # A check that failed: the model's file, the function and output, the first line of why.
        print(f"derive: {args.model}: {one_line(str(err).splitlines()[0] if str(err) else type(err).__name__)}",
              file=sys.stderr)
        return 1
    except RecursionError:
        print(f"derive: {args.model}: an expression nested too deeply to derive", file=sys.stderr)
        return 2
    try:
        write(out, ir)
        write(vectors_out, vectors)
    except OSError as err:
        print(f"derive: cannot write {err.filename}: {err.strerror}", file=sys.stderr)
        return 1
    if model.dynamics_kind == "urdf" and model.chain.ignored_dynamics:
        # urdf.py's rule: the plant's joint damping is the description's [impedance].
        print(f"derive: {model.chain.path}: note: <dynamics> damping/friction of joints "
              f"{', '.join(model.chain.ignored_dynamics)} ignored: the plant's joint damping is the "
              "description's [impedance]", file=sys.stderr)
    checked = sum(len(f["vectors"]) for f in vectors["functions"])
    print(f"derive: {model.name}: {len(ir.functions)} functions, {checked} points checked SymPy = CasADi "
          f"-> {out}, {vectors_out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
