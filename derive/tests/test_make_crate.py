"""`make crate`: a user's own descriptions, outside the repository, become a standalone no_std
crate that passes its own vector test, and nothing in the repository changes; bad input is one
line and status 2, with nothing left behind (part of make test)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MAKE_CRATE = [sys.executable, str(ROOT / "derive" / "make_crate.py")]
PENDULUM = ROOT / "tests" / "fixtures" / "pendulum.toml"
# The crates' builds share one folder under target/ (ignored by git), so a second run is quick.
TARGET = ROOT / "target" / "make-crate-test"


def git_status() -> str | None:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return None
    return subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout


class MakeCrate(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory(prefix="toolconf-make-crate-")
        self.addCleanup(tmp.cleanup)
        self.base = Path(tmp.name)
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
        # Made again over itself: replaced, not refused; and the repository is as it was.
        again = self.run_make_crate(out)
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["descriptions", "my-pendulum"])
        if before is not None:
            self.assertEqual(git_status(), before)

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
        foreign = self.base / "descriptions"  # a folder with other files in it
        self.assert_refused(self.run_make_crate(foreign), "other files")

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
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn("usage: make crate MODELS=", r.stderr)


if __name__ == "__main__":
    unittest.main()
