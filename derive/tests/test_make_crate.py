"""`make crate`: a user's own descriptions, outside the repository, become a standalone no_std
crate that passes its own vector test, and nothing in the repository changes; bad input is one
line and status 2, with nothing left behind (part of make test)."""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MAKE_CRATE = [sys.executable, str(ROOT / "derive" / "make_crate.py")]
PENDULUM = ROOT / "tests" / "fixtures" / "pendulum.toml"
# The crates' builds share one folder under target/ (ignored by git), so a second run is quick.
TARGET = ROOT / "target" / "make-crate-test"
# `make` as a user runs it, without a parent make's flags: make test runs these tests in a lane of
# `make -j2`, whose jobserver a child make cannot reach (it would warn on stderr).
MAKE_ENV = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}


def git_status() -> str | None:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return None
    return subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout


def files_under(folder: Path) -> dict[str, bytes]:
    """Every entry under `folder`: a file's bytes, a link's target, b"/" for a folder."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        out[rel] = (b"-> " + os.readlink(p).encode()) if p.is_symlink() else b"/" if p.is_dir() else p.read_bytes()
    return out


def assert_terminated_cleanly(test: unittest.TestCase, what: str, command: list[str], base: Path, out: Path,
                              partial: str) -> None:
    """`command` (`what`, run in `base`, making `out` anew) terminated by SIGTERM once its
    temporary folder (`partial` and a suffix, in `base`) is there: it ends with the signal's
    status and leaves what is under `out` as it was."""
    kept = files_under(out)
    run = subprocess.Popen(command, cwd=base, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while not any(p.name.startswith(partial) for p in base.iterdir()):
        test.assertIsNone(run.poll(), f"{what} ended before it was signalled")
        test.assertLess(time.monotonic(), deadline)
        time.sleep(0.01)
    run.send_signal(signal.SIGTERM)
    test.assertEqual(run.wait(timeout=300), 128 + signal.SIGTERM)
    test.assertEqual(files_under(out), kept)


class MakeCrate(unittest.TestCase):
    def setUp(self):
        self.base = Path(self.enterContext(tempfile.TemporaryDirectory(prefix="toolconf-make-crate-")))
        self.models = self.base / "descriptions"
        self.models.mkdir()

    def run_make_crate(self, out: Path, *extra: str) -> subprocess.CompletedProcess:
        return subprocess.run([*MAKE_CRATE, "--models", str(self.models), "--out", str(out), *extra],
                              cwd=self.base, capture_output=True, text=True)

    def assert_refused(self, r: subprocess.CompletedProcess, *words: str):
        self.assertEqual(r.returncode, 2, r.stderr)
        lines = r.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        for w in words:
            self.assertIn(w, lines[0])
        self.assertNotIn("Traceback", r.stderr)
        # Nothing left in the folder the crate would have gone to (its temporary folder included).
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["descriptions"])

    def test_a_renamed_description_outside_the_repository_makes_a_crate_that_passes_its_test(self):
        # The model is my_pendulum, the crate my-pendulum: its library my_pendulum has a module
        # my_pendulum, which the crate's own test must still tell apart. Its torque is called t0,
        # the name of the first temporary, which the temporaries then skip.
        text = PENDULUM.read_text().replace('name = "pendulum"', 'name = "my_pendulum"', 1)
        text = text.replace('name = "torque"', 'name = "t0"', 1).replace("(torque -", "(t0 -", 1)
        self.assertIn('name = "t0"', text)
        self.assertIn("(t0 -", text)
        (self.models / "my_renamed_copy.toml").write_text(text)
        before = git_status()
        out = self.base / "my-pendulum"
        r = self.run_make_crate(out)
        self.assertEqual(r.returncode, 0, r.stderr)
        # The module is named by the description's model.name, not by its file.
        self.assertTrue((out / "src" / "my_pendulum.rs").is_file())
        self.assertFalse((out / "src" / "my_renamed_copy.rs").exists())
        for name in ["Cargo.toml", "my_pendulum.json", "my_pendulum.vectors.json", "my_pendulum.md", "src/lib.rs",
                     "src/tasks.rs", "src/trig.rs", "src/powi.rs", "tests/vectors.rs"]:
            self.assertTrue((out / name).is_file(), name)
        manifest = (out / "Cargo.toml").read_text()
        self.assertIn('name = "my-pendulum"', manifest)
        self.assertIn("\n[workspace]\n", manifest)
        self.assertIn("#![no_std]", (out / "src" / "lib.rs").read_text())
        self.assertIn("pub mod my_pendulum;", (out / "src" / "lib.rs").read_text())
        test = subprocess.run(["cargo", "test", "--quiet", "--manifest-path", str(out / "Cargo.toml")],
                              cwd=self.base, capture_output=True, text=True,
                              env={**os.environ, "CARGO_TARGET_DIR": str(TARGET)})
        self.assertEqual(test.returncode, 0, test.stdout + test.stderr)
        self.assertIn("functions_match_casadi_vectors", subprocess.run(
            ["cargo", "test", "--quiet", "--manifest-path", str(out / "Cargo.toml"), "--", "--list"],
            cwd=self.base, capture_output=True, text=True, env={**os.environ, "CARGO_TARGET_DIR": str(TARGET)}).stdout)
        self.assert_owned(out)
        # A folder the user makes, not mkdtemp's 0700.
        mask = os.umask(0)
        os.umask(mask)
        self.assertEqual(out.stat().st_mode & 0o777, 0o777 & ~mask)
        # Made again over itself: replaced, not refused, cargo's lock file kept; and the
        # repository is as it was.
        self.assertTrue((out / "Cargo.lock").is_file())
        lock = (out / "Cargo.lock").read_bytes()
        again = self.run_make_crate(out)
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["descriptions", "my-pendulum"])
        self.assertEqual((out / "Cargo.lock").read_bytes(), lock)
        self.assert_owned(out)
        if before is not None:
            self.assertEqual(git_status(), before)
        # Terminated while making it anew: the old crate is as it was, and no temporary is left.
        assert_terminated_cleanly(self, "make crate", [*MAKE_CRATE, "--models", str(self.models), "--out", str(out)],
                                  self.base, out, ".my-pendulum-partial-")
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["descriptions", "my-pendulum"])
        # A file of the user's in it, or a file of the crate the user changed: not replaced.
        (out / "notes.txt").write_text("mine")
        r = self.run_make_crate(out)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("notes.txt", r.stderr)
        self.assertIn("not written by", r.stderr)
        self.assertEqual((out / "notes.txt").read_text(), "mine")
        (out / "notes.txt").unlink()
        with (out / "src" / "lib.rs").open("a") as f:
            f.write("// my change\n")
        r = self.run_make_crate(out)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("lib.rs was changed", r.stderr)
        self.assertTrue((out / "src" / "lib.rs").read_text().endswith("// my change\n"))
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["descriptions", "my-pendulum"])

    def assert_owned(self, out: Path):
        """The ownership manifest lists exactly the crate's files (cargo's aside), each with
        its SHA-256."""
        lines = (out / ".toolconf-crate").read_text().splitlines()
        self.assertTrue(lines[0].startswith("# files written by `make crate`"), lines[0])
        listed = dict(reversed(line.split("  ", 1)) for line in lines[1:])
        present = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()
                   and p.name != ".toolconf-crate" and p.relative_to(out).parts[0] not in ("Cargo.lock", "target")}
        self.assertEqual(set(listed), present)
        for name, digest in listed.items():
            self.assertEqual(hashlib.sha256((out / name).read_bytes()).hexdigest(), digest, name)

    def test_a_bad_description_is_the_derivations_one_line_error(self):
        (self.models / "broken.toml").write_text(PENDULUM.read_text().replace("dof = 1", 'dof = "one"'))
        self.assert_refused(self.run_make_crate(self.base / "out"), "broken.toml", "model.dof")

    def test_bad_folders_and_names_are_refused(self):
        self.assert_refused(self.run_make_crate(self.base / "out"), "no model descriptions")
        shutil.copy(PENDULUM, self.models / "a.toml")
        shutil.copy(PENDULUM, self.models / "b.toml")
        self.assert_refused(self.run_make_crate(self.base / "out"), "a.toml", "b.toml", "pendulum")
        (self.models / "b.toml").unlink()
        self.assert_refused(self.run_make_crate(self.base / "out", "--name", "9lives"), "NAME", "9lives")
        # Valid for Cargo, but the crate's own test could not name the crate it tests.
        self.assert_refused(self.run_make_crate(self.base / "crate"), "OUT=", "'crate' is a Rust keyword")
        self.assert_refused(self.run_make_crate(self.base / "out", "--name", "nalgebra"), "NAME", "a crate the generated")
        self.assert_refused(self.run_make_crate(self.base / "out", "--tasks", str(self.base / "none.toml")),
                            "TASKS", "none.toml")
        foreign = self.base / "foreign"  # a folder with other files in it
        foreign.mkdir()
        (foreign / "mine.txt").write_text("mine")
        r = self.run_make_crate(foreign)
        self.assertEqual((r.returncode, r.stderr.count("\n")), (2, 1), r.stderr)
        self.assertIn("other files", r.stderr)
        self.assertEqual([p.name for p in foreign.iterdir()], ["mine.txt"])

    def assert_kept(self, r: subprocess.CompletedProcess, snapshot: dict[str, bytes], *words: str):
        """Refused with one line holding `words`, and every file of `snapshot` as it was, and
        nothing else under the base folder."""
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        for w in words:
            self.assertIn(w, r.stderr)
        self.assertEqual(files_under(self.base), snapshot)

    def test_an_out_that_holds_the_descriptions_or_the_tasks_is_refused(self):
        out = self.base / "out"
        mine = out / "mymodels"
        mine.mkdir(parents=True)
        shutil.copy(PENDULUM, mine / "pendulum.toml")
        snapshot = files_under(self.base)
        r = subprocess.run([*MAKE_CRATE, "--models", str(mine), "--out", str(out)], cwd=self.base,
                           capture_output=True, text=True)
        self.assert_kept(r, snapshot, f"OUT={out}", "MODELS=")
        # OUT the descriptions' folder itself.
        r = subprocess.run([*MAKE_CRATE, "--models", str(mine), "--out", str(mine)], cwd=self.base,
                           capture_output=True, text=True)
        self.assert_kept(r, snapshot, "MODELS=")
        # A task file inside OUT.
        shutil.copy(PENDULUM, self.models / "pendulum.toml")
        shutil.copy(ROOT / "derive" / "tasks.toml", out / "tasks.toml")
        snapshot = files_under(self.base)
        r = self.run_make_crate(out, "--tasks", str(out / "tasks.toml"))
        self.assert_kept(r, snapshot, "TASKS=", "is inside it")

    def test_a_folder_whose_cargo_toml_looks_like_a_crate_of_ours_is_not_replaced(self):
        shutil.copy(PENDULUM, self.models / "pendulum.toml")
        out = self.base / "fake"
        out.mkdir()
        (out / "Cargo.toml").write_text("# @generated by `make crate`\n[package]\nname = \"fake\"\n")
        (out / "thesis.tex").write_text("years of work")
        snapshot = files_under(self.base)
        self.assert_kept(self.run_make_crate(out), snapshot, f"OUT={out}", ".toolconf-crate")
        # A manifest that does not list a file present is no licence either.
        (out / ".toolconf-crate").write_text(
            "# files written by `make crate`; the crate is replaced only while they are as listed\n"
            f"{hashlib.sha256((out / 'Cargo.toml').read_bytes()).hexdigest()}  Cargo.toml\n")
        snapshot = files_under(self.base)
        self.assert_kept(self.run_make_crate(out), snapshot, "thesis.tex", "not written by")

    def test_an_out_inside_the_repository_is_refused(self):
        shutil.copy(PENDULUM, self.models / "pendulum.toml")
        before = git_status()
        for out in [ROOT / "mycrate", ROOT / "target" / "mycrate", ROOT]:
            r = self.run_make_crate(out, "--name", "mycrate")
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn("inside the repository", r.stderr)
            self.assertFalse((ROOT / "mycrate").exists())
            self.assertFalse((ROOT / "target" / "mycrate").exists())
        if before is not None:
            self.assertEqual(git_status(), before)

    def test_an_out_that_is_a_symbolic_link_is_refused_and_both_ends_stay(self):
        shutil.copy(PENDULUM, self.models / "pendulum.toml")
        real = self.base / "real"
        real.mkdir()
        link = self.base / "mycrate"
        link.symlink_to(real)
        snapshot = files_under(self.base)
        self.assert_kept(self.run_make_crate(link), snapshot, f"OUT={link}", "symbolic link")
        self.assertTrue(link.is_symlink())
        dangling = self.base / "nothing"
        dangling.symlink_to(self.base / "missing")
        snapshot = files_under(self.base)
        self.assert_kept(self.run_make_crate(dangling), snapshot, f"OUT={dangling}", "symbolic link")

    def test_the_taken_crate_names_are_the_templates_dependencies(self):
        sys.path.insert(0, str(ROOT / "derive"))
        from make_crate import TAKEN_CRATE_NAMES
        manifest = (ROOT / "templates" / "registry" / "Cargo.toml.tera").read_text()
        sections = re.findall(r"^\[(?:dev-)?dependencies\]\n((?:(?!\[).*\n)*)", manifest, re.M)
        dependencies = {m for body in sections for m in re.findall(r"^([a-z][a-z0-9_-]*) =", body, re.M)}
        self.assertTrue(dependencies)
        self.assertLessEqual(dependencies, set(TAKEN_CRATE_NAMES))

    def test_make_without_models_or_out_is_a_usage_line(self):
        r = subprocess.run(["make", "--no-print-directory", "crate", f"OUT={self.base / 'x'}"], cwd=ROOT,
                           capture_output=True, text=True, env=MAKE_ENV)
        self.assertEqual(r.returncode, 2)
        self.assertIn("usage: make crate MODELS=", r.stderr)


if __name__ == "__main__":
    unittest.main()
