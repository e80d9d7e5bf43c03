"""The drift check's comparison and derive.py's command line (part of make test)."""

from __future__ import annotations

import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import pipeline  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DERIVE = [sys.executable, str(ROOT / "derive" / "derive.py")]


class Compare(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        # Inside the repository's tree, as pipeline.compare names files relative to it.
        self.addCleanup(self.tmp.cleanup)
        base = Path(self.tmp.name)
        self.derived, self.committed = base / "derived", base / "committed"
        self.derived.mkdir()
        self.committed.mkdir()
        self.root, pipeline.ROOT = pipeline.ROOT, base
        self.addCleanup(setattr, pipeline, "ROOT", self.root)

    def test_identical_folders_have_no_problem(self):
        for d in (self.derived, self.committed):
            (d / "a.rs").write_text("fn a() {}\n")
        self.assertEqual(pipeline.compare(self.derived, self.committed, True), [])

    def test_names_the_file_and_its_first_differing_line(self):
        (self.derived / "a.rs").write_text("one\ntwo\nthree\n")
        (self.committed / "a.rs").write_text("one\n2\nthree\n")
        (problem,) = pipeline.compare(self.derived, self.committed, True)
        self.assertIn("committed/a.rs", problem)
        self.assertIn("line 2", problem)
        self.assertIn("committed: 2", problem)
        self.assertIn("derived:   two", problem)

    def test_missing_and_stale_files(self):
        (self.derived / "new.rs").write_text("x\n")
        (self.committed / "old.rs").write_text("y\n")
        problems = pipeline.compare(self.derived, self.committed, True)
        self.assertEqual(len(problems), 2)
        self.assertIn("it is not there", problems[0])
        self.assertIn("stale", problems[1])
        # For tests/fixtures only the produced files count: old.rs is not stale there.
        self.assertEqual(len(pipeline.compare(self.derived, self.committed, False)), 1)

    def test_the_whole_tree_counts(self):
        # The generated crate has sub-folders (src/, tests/): a difference, a missing and a stale
        # file there are found as at the top.
        for d in (self.derived, self.committed):
            (d / "src").mkdir()
            (d / "Cargo.toml").write_text("[package]\n")
        (self.derived / "src" / "lib.rs").write_text("one\n")
        (self.committed / "src" / "lib.rs").write_text("two\n")
        (self.derived / "src" / "new.rs").write_text("x\n")
        (self.committed / "tests").mkdir()
        (self.committed / "tests" / "old.rs").write_text("y\n")
        problems = pipeline.compare(self.derived, self.committed, True)
        self.assertEqual(len(problems), 3, problems)
        self.assertIn("committed/src/lib.rs differs", problems[0])
        self.assertIn("committed/src/new.rs: make derive produces it", problems[1])
        self.assertIn("committed/tests/old.rs: make derive no longer produces it (stale)", problems[2])

    def test_a_shorter_file(self):
        (self.derived / "a.rs").write_text("one\ntwo\n")
        (self.committed / "a.rs").write_text("one\n")
        (problem,) = pipeline.compare(self.derived, self.committed, True)
        self.assertIn("line 2: one file ends there", problem)


class DeriveCommandLine(unittest.TestCase):
    def run_derive(self, *args):
        return subprocess.run([*DERIVE, "tests/fixtures/pendulum.toml", *args], cwd=ROOT,
                              capture_output=True, text=True)

    def test_out_anywhere_writes_the_same_bytes_as_the_fixture(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "pendulum.json"
            r = self.run_derive("--out", str(out), "--vectors", "3")
            self.assertEqual(r.returncode, 0, r.stderr)
            for name in ("pendulum.json", "pendulum.vectors.json"):
                self.assertEqual((Path(tmp) / name).read_bytes(), (ROOT / "tests/fixtures" / name).read_bytes(), name)

    def test_a_missing_folder_is_one_line_and_status_2(self):
        r = self.run_derive("--out", "/nonexistent-folder/x.json")
        self.assertEqual(r.returncode, 2)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertIn("/nonexistent-folder", r.stderr)
        self.assertNotIn("Traceback", r.stderr)

    def test_an_out_that_is_not_json_is_refused(self):
        r = self.run_derive("--out", "/tmp/x.txt")
        self.assertEqual(r.returncode, 2)
        self.assertIn("must end in .json", r.stderr)


if __name__ == "__main__":
    unittest.main()


class ValidateFirst(unittest.TestCase):
    """make derive reads every description before it derives any: two broken descriptions are both
    named, with status 2, and no derivation is started."""

    def test_every_refused_description_is_named_before_any_derivation(self):
        import contextlib
        import io
        with tempfile.TemporaryDirectory() as tmp:
            models = Path(tmp)
            good = (ROOT / "derive" / "models" / "arm2.toml").read_text()
            (models / "a.toml").write_text(good.replace("dof = 2", 'dof = "two"'))
            (models / "b.toml").write_text(good.replace("[equilibrium]", "[equilibrium]\nspeed = 1"))
            (models / "c.toml").write_text(good)
            saved, pipeline.MODELS = pipeline.MODELS, models
            self.addCleanup(setattr, pipeline, "MODELS", saved)
            started = []
            run = pipeline.Run({}, models / "generated", models / "fixtures")
            err = io.StringIO()
            with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as caught:
                original = pipeline.subprocess.run
                pipeline.subprocess.run = lambda *a, **k: started.append(a)
                try:
                    pipeline.derive_all([run])
                finally:
                    pipeline.subprocess.run = original
        self.assertEqual(caught.exception.code, 2)
        self.assertEqual(started, [])
        text = err.getvalue()
        self.assertIn("a.toml: model.dof", text)
        self.assertIn("b.toml: equilibrium", text)
        self.assertNotIn("c.toml", text)
        self.assertIn("2 description(s) refused; nothing was derived", text)
