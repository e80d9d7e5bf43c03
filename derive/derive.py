#!/usr/bin/env python3
"""Derive a model: read its description, derive it with SymPy, check it against CasADi, and write
the JSON IR that toolconf-render turns into generated/<model>.rs and generated/<model>.md.

    derive/.venv/bin/python derive/derive.py derive/models/arm2.toml --out generated/arm2.json

`make derive` runs this for every model and then renders; run that instead.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from toolconf_derive.crosscheck import DerivationMismatch  # noqa: E402
from toolconf_derive.description import DescriptionError, load_model, load_tasks  # noqa: E402
from toolconf_derive.functions import build_functions  # noqa: E402
from toolconf_derive.ir import model_ir  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.report import report_data  # noqa: E402
from toolconf_derive.symbolic import derive  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model", type=Path, help="model description (TOML)")
    ap.add_argument("--tasks", type=Path, default=HERE / "tasks.toml", help="task definitions (TOML)")
    ap.add_argument("--out", type=Path, required=True, help="where to write the JSON IR")
    ap.add_argument("--vectors", type=int, default=100, help="test vectors per function (default 100)")
    args = ap.parse_args()
    root = HERE.parent
    try:
        model = load_model(args.model)
        tasks = load_tasks(args.tasks)
        d = derive(model, tasks)
        functions = build_functions(d, CasadiModel(model))
        generator = {
            "command": "make derive",
            "model": str(args.model.resolve().relative_to(root)),
            "tasks": str(args.tasks.resolve().relative_to(root)),
            "ir": str(args.out.resolve().relative_to(root)),
            "derive": "derive/derive.py (SymPy derives, CasADi checks)",
            "render": "derive/render (Tera) + rustfmt",
        }
        ir = model_ir(d, functions, generator, report_data(d), args.vectors)
    except (DescriptionError, DerivationMismatch) as err:
        print(f"derive: {err}", file=sys.stderr)
        return 1
    args.out.write_text(json.dumps(ir, indent=1, ensure_ascii=False) + "\n")
    checked = sum(len(f["test_vectors"]) for f in ir["functions"])
    print(f"derive: {model.name}: {len(ir['functions'])} functions, {checked} points checked SymPy = CasADi -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
