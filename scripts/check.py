#!/usr/bin/env python3
"""`make check`: the inner loop's checks of what the working tree changes against a base.

What changed (committed since the merge base with BASE, staged, unstaged and untracked files)
picks what runs: each Rust package a changed file belongs to gets clippy (warnings are errors)
and its unit tests (`--lib`, `--bins`); a changed integration test file (tests/X.rs, a crate's
tests/X.rs) runs itself; a changed derive/ module runs the derivation's tests named after it
(derive/tests/test_<module>.py); rustfmt checks the whole workspace (it takes a second). Nothing
else: `make test` is the whole suite, before a merge.

Usage: scripts/check.py [BASE] (default main). Prints each command before it runs it; stops at
the first that fails, with its status.
"""
from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV_PYTHON = ROOT / "derive" / ".venv" / "bin" / "python"
# clippy's warnings are errors, but one: `!(x > 0.0)` is how this code refuses NaN along with the
# values the comparison rules out, where `x <= 0.0` would let NaN through.
LINTS = ["-D", "warnings", "-A", "clippy::neg_cmp_op_on_partial_ord"]


def git(*args: str) -> list[str]:
    r = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)
    return r.stdout.split("\n") if r.returncode == 0 else []


def changed_files(base: str) -> list[str]:
    merge_base = (git("merge-base", "HEAD", base) or [""])[0] or "HEAD"
    names = git("diff", "--name-only", merge_base) + git("ls-files", "--others", "--exclude-standard")
    return sorted({n for n in names if n and (ROOT / n).exists()})


def workspace_packages() -> dict[str, str]:
    """Each workspace member's folder (relative to the root) and its package name."""
    members = tomllib.loads((ROOT / "Cargo.toml").read_text())["workspace"]["members"]
    found = {}
    for member in members:
        manifest = tomllib.loads((ROOT / member / "Cargo.toml").read_text())
        found["" if member == "." else member.rstrip("/") + "/"] = manifest["package"]["name"]
    return found


def package_of(path: str, packages: dict[str, str]) -> str | None:
    """The package whose folder holds `path` most closely (the root package last)."""
    folders = sorted((f for f in packages if path.startswith(f)), key=len, reverse=True)
    if not folders or (folders[0] == "" and not path.startswith(("src/", "tests/", "benches/", "examples/"))):
        return None
    return packages[folders[0]]


def integration_test(path: str) -> str | None:
    """`X` for a changed tests/X.rs (the root's or a crate's), else None."""
    p = Path(path)
    return p.stem if p.suffix == ".rs" and p.parent.name == "tests" else None


def plan(files: list[str]) -> list[list[str]]:
    packages = workspace_packages()
    folder_of = {name: ROOT / folder for folder, name in packages.items()}
    touched: dict[str, set[str]] = {}
    derive_tests: set[str] = set()
    for f in files:
        package = package_of(f, packages)
        if package is not None:
            tests = touched.setdefault(package, set())
            if (name := integration_test(f)) is not None:
                tests.add(name)
        if f.startswith("derive/") and f.endswith(".py"):
            stem = Path(f).stem
            test = stem if stem.startswith("test_") else f"test_{stem}"
            if (ROOT / "derive" / "tests" / f"{test}.py").exists():
                derive_tests.add(test)
    commands = [["cargo", "fmt", "--all", "--", "--check"]]
    for package in sorted(touched):
        # Generated code's shape is the templates' (the drift check and the snapshots review it).
        if package != "toolconf-generated":
            commands.append(["cargo", "clippy", "--quiet", "--no-deps", "-p", package, "--all-targets", "--", *LINTS])
        # The Python extension links against libpython only when maturin builds it.
        if package != "toolconf-python" and (targets := unit_targets(folder_of[package])):
            commands.append(["cargo", "test", "--quiet", "-p", package, *targets])
        for test in sorted(touched[package]):
            commands.append(["cargo", "test", "--quiet", "-p", package, "--test", test])
    python = str(VENV_PYTHON) if VENV_PYTHON.exists() else sys.executable
    for test in sorted(derive_tests):
        commands.append([python, "-m", "unittest", "discover", "-s", "derive/tests", "-p", f"{test}.py"])
    return commands


def unit_targets(folder: Path) -> list[str]:
    """cargo test's flags for a package's unit tests: its library's and its binaries'."""
    manifest = tomllib.loads((folder / "Cargo.toml").read_text())
    lib = "lib" in manifest or (folder / "src" / "lib.rs").exists()
    bins = "bin" in manifest or (folder / "src" / "main.rs").exists()
    return (["--lib"] if lib else []) + (["--bins"] if bins else [])


def main() -> int:
    base = sys.argv[1] if len(sys.argv) > 1 else "main"
    files = changed_files(base)
    print(f"check: {len(files)} files changed against {base}", flush=True)
    for command in plan(files):
        print("check: " + " ".join(command), flush=True)
        status = subprocess.run(command, cwd=ROOT).returncode
        if status:
            print(f"check: failed (status {status}): {' '.join(command)}", file=sys.stderr)
            return 1
    print("check: passed", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
