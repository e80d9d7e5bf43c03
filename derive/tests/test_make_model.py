"""`make model`: one description, outside the repository, becomes a shared library with toolconf's
C ABI (and its header) that a program can load, with its progress shown step by step and nothing
in the repository changed; bad input is one line and status 2, with nothing left behind; an
interrupted run keeps the old library (part of make test)."""

from __future__ import annotations

import ctypes
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
MAKE_MODEL = [sys.executable, str(ROOT / "derive" / "make_model.py")]
PENDULUM = ROOT / "tests" / "fixtures" / "pendulum.toml"

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_make_crate import files_under, git_status  # noqa: E402


class MakeModel(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory(prefix="toolconf-make-model-")
        self.addCleanup(tmp.cleanup)
        self.base = Path(tmp.name)
        self.desc = self.base / "my_pendulum.toml"
        shutil.copy(PENDULUM, self.desc)

    def run_make_model(self, *args: str) -> subprocess.CompletedProcess:
        return subprocess.run([*MAKE_MODEL, *args], cwd=self.base, capture_output=True, text=True)

    def assert_refused(self, r: subprocess.CompletedProcess, *words: str, kept: dict | None = None):
        """Status 2, one line holding `words`, no traceback, and the base folder as it was (only
        the description in it, unless `kept` says what)."""
        self.assertEqual(r.returncode, 2, r.stderr)
        lines = r.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertTrue(lines[0].startswith("make model: "), lines[0])
        for w in words:
            self.assertIn(w, lines[0])
        self.assertNotIn("Traceback", r.stderr)
        self.assertEqual(r.stdout, "")
        if kept is None:
            self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml"])
        else:
            self.assertEqual(files_under(self.base), kept)

    def test_missing_or_clashing_arguments_are_one_line(self):
        out = str(self.base / "out")
        self.assert_refused(self.run_make_model(), "--out", "usage: make model DESC=")
        self.assert_refused(self.run_make_model("--out", out), "--desc", "--ir")
        self.assert_refused(self.run_make_model("--desc", str(self.desc)), "--out")
        self.assert_refused(self.run_make_model("--desc", str(self.desc), "--ir", "x.json", "--out", out),
                            "not allowed with")
        self.assert_refused(self.run_make_model("--ir", str(ROOT / "generated" / "arm2.json"), "--tasks",
                                                str(ROOT / "derive" / "tasks.toml"), "--out", out), "TASKS=")

    def test_make_without_desc_or_out_is_a_usage_line(self):
        for args in ([f"OUT={self.base / 'x'}"], [f"DESC={self.desc}"], []):
            r = subprocess.run(["make", "--no-print-directory", "-s", "model", *args], cwd=ROOT, capture_output=True,
                               text=True)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn("usage: make model DESC=", r.stderr)
        self.assertFalse((self.base / "x").exists())

    def test_a_bad_description_is_one_line_naming_the_file_and_key(self):
        out = str(self.base / "out")
        self.assert_refused(self.run_make_model("--desc", str(self.base / "none.toml"), "--out", out),
                            "DESC=", "none.toml", "does not exist")
        self.assert_refused(self.run_make_model("--desc", str(self.base), "--out", out), "DESC=", "not a file")
        text = PENDULUM.read_text()
        for broken, words in [
            (text.replace("dof = 1", 'dof = "one"'), ["my_pendulum.toml", "model.dof"]),
            (text.replace("[model]", "[model", 1), ["my_pendulum.toml", "not valid TOML"]),
            (text.replace('name = "pendulum"', 'name = "Pendulum!"', 1), ["my_pendulum.toml", "model.name"]),
        ]:
            self.desc.write_text(broken)
            self.assert_refused(self.run_make_model("--desc", str(self.desc), "--out", out), *words)
        shutil.copy(PENDULUM, self.desc)
        self.assert_refused(self.run_make_model("--desc", str(self.desc), "--tasks", str(self.base / "t.toml"),
                                                "--out", out), "TASKS=", "t.toml")

    def test_a_bad_ir_is_one_line(self):
        out = str(self.base / "out")
        bad = self.base / "bad.json"
        bad.write_text("{ not json")
        self.assert_refused(self.run_make_model("--ir", str(bad), "--out", out), "IR=", "bad.json", "not a model's IR",
                            kept=files_under(self.base))
        self.assert_refused(self.run_make_model("--ir", str(ROOT / "generated" / "arm2.vectors.json"), "--out", out),
                            "IR=", "arm2.vectors.json", kept=files_under(self.base))
        lone = self.base / "arm2.json"
        shutil.copy(ROOT / "generated" / "arm2.json", lone)
        self.assert_refused(self.run_make_model("--ir", str(lone), "--out", out), "test vectors",
                            kept=files_under(self.base))

    def test_an_out_inside_the_repository_or_a_link_or_a_foreign_folder_is_refused(self):
        before = git_status()
        for out in [ROOT / "mymodel", ROOT / "target" / "mymodel", ROOT]:
            r = self.run_make_model("--desc", str(self.desc), "--out", str(out))
            self.assert_refused(r, "inside the repository")
            self.assertFalse((ROOT / "mymodel").exists())
            self.assertFalse((ROOT / "target" / "mymodel").exists())
        if before is not None:
            self.assertEqual(git_status(), before)
        real = self.base / "real"
        real.mkdir()
        link = self.base / "lib"
        link.symlink_to(real)
        kept = files_under(self.base)
        self.assert_refused(self.run_make_model("--desc", str(self.desc), "--out", str(link)), f"OUT={link}",
                            "symbolic link", kept=kept)
        self.assertTrue(link.is_symlink())
        foreign = self.base / "foreign"
        foreign.mkdir()
        (foreign / "mine.txt").write_text("mine")
        kept = files_under(self.base)
        self.assert_refused(self.run_make_model("--desc", str(self.desc), "--out", str(foreign)), "other files",
                            "make model", kept=kept)
        # The description inside OUT: the library would replace it.
        inside = self.base / "holds"
        inside.mkdir()
        shutil.copy(PENDULUM, inside / "p.toml")
        kept = files_under(self.base)
        self.assert_refused(self.run_make_model("--desc", str(inside / "p.toml"), "--out", str(inside)), "DESC=",
                            kept=kept)

    def test_a_description_becomes_a_library_that_loads_and_computes_with_each_step_shown(self):
        before = git_status()
        out = self.base / "pendulum-lib"
        r = self.run_make_model("--desc", str(self.desc), "--out", str(out))
        self.assertEqual(r.returncode, 0, r.stderr)
        # One progress line per step, each with the time since the start and its own, in order:
        # reading, deriving (the equations, then each function), checking, rendering, compiling.
        steps = re.findall(r"^make model: \[ *([0-9.]+) s\] (\w+): (.*) \(([0-9.]+) s\)$", r.stderr, re.M)
        stages = [s[1] for s in steps]
        self.assertEqual(stages[0], "reading", r.stderr)
        for stage in ["deriving", "checking", "rendering", "compiling"]:
            self.assertIn(stage, stages, r.stderr)
        self.assertLess(stages.index("deriving"), stages.index("rendering"))
        self.assertLess(stages.index("rendering"), stages.index("compiling"))
        self.assertEqual(stages[-1], "compiling")
        derived = [s[2] for s in steps if s[1] == "deriving"]
        self.assertIn("dynamics: code", derived)
        self.assertIn("position_control_confidence: code", derived)
        self.assertTrue(any(s[2].startswith("dynamics: SymPy = CasADi") for s in steps if s[1] == "checking"))
        elapsed = [float(s[0]) for s in steps]
        self.assertEqual(elapsed, sorted(elapsed))
        self.assertIn("libtoolconf_model_pendulum", r.stdout)
        # The library, its header and its crate.
        library = out / "libtoolconf_model_pendulum.so"
        for name in ["toolconf_model.h", "Cargo.toml", "src/lib.rs", "tests/abi.rs", "generated/Cargo.toml",
                     "generated/pendulum.json", "generated/pendulum.vectors.json", "generated/src/pendulum.rs",
                     ".toolconf-crate"]:
            self.assertTrue((out / name).is_file(), name)
        self.assertTrue(library.is_file())
        header = (out / "toolconf_model.h").read_text()
        self.assertIn('#define TOOLCONF_MODEL_NAME "pendulum"', header)
        self.assertIn("#define TOOLCONF_DOF 1\n", header)
        self.assertTrue((out / ".toolconf-crate").read_text().startswith("# files written by `make model`"))
        # Loaded by a program (ctypes here): the version, the metadata and one function.
        lib = ctypes.CDLL(str(library))
        lib.toolconf_abi_version.restype = ctypes.c_uint32
        version = int(re.search(r"#define TOOLCONF_ABI_VERSION (\d+)u", header).group(1))
        self.assertEqual(lib.toolconf_abi_version(), version)
        lib.toolconf_tasks_fingerprint.restype = ctypes.c_char_p
        fingerprint = re.search(r'#define TOOLCONF_TASKS_FINGERPRINT "([0-9a-f]{64})"', header).group(1)
        self.assertEqual(lib.toolconf_tasks_fingerprint().decode(), fingerprint)
        vec = ctypes.c_double * 2
        x, u, p, x_dot = vec(0.3, -0.2), (ctypes.c_double * 1)(0.5), vec(0.4, 0.7), vec(0.0, 0.0)
        self.assertEqual(lib.toolconf_dynamics(x, u, p, x_dot), 0)
        # theta_ddot = 3/(m l^2) (T - m g l cos(theta) / 2), as the description says.
        m, l = 0.4, 0.7
        expected = 3 / (m * l ** 2) * (0.5 - m * 9.81 * l * __import__("math").cos(0.3) / 2)
        self.assertEqual(x_dot[0], -0.2)
        self.assertAlmostEqual(x_dot[1], expected, delta=1e-12 * abs(expected))
        self.assertEqual(lib.toolconf_dynamics(None, u, p, x_dot), 1)  # TOOLCONF_NULL_POINTER
        lib.toolconf_last_error.restype = ctypes.c_char_p
        self.assertIn(b"x is a null pointer", lib.toolconf_last_error())
        self.assertEqual(lib.toolconf_pi_u(99, p, p, x_dot), 2)  # TOOLCONF_UNKNOWN_TASK
        if before is not None:
            self.assertEqual(git_status(), before)

        # Made again over itself: replaced; then terminated while making it anew: the old library
        # is as it was, and no temporary folder is left.
        again = self.run_make_model("--desc", str(self.desc), "--out", str(out))
        self.assertEqual(again.returncode, 0, again.stderr)
        kept = files_under(out)
        run = subprocess.Popen([*MAKE_MODEL, "--desc", str(self.desc), "--out", str(out)], cwd=self.base,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 120
        while not any(p.name.startswith(".pendulum-lib-partial-") for p in self.base.iterdir()):
            self.assertIsNone(run.poll(), "make model ended before it was signalled")
            self.assertLess(time.monotonic(), deadline)
            time.sleep(0.01)
        run.send_signal(signal.SIGTERM)
        self.assertEqual(run.wait(timeout=300), 128 + signal.SIGTERM)
        self.assertEqual(files_under(out), kept)
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml", "pendulum-lib"])
        # A file of the user's in it: not replaced.
        (out / "notes.txt").write_text("mine")
        kept = files_under(self.base)
        self.assert_refused(self.run_make_model("--desc", str(self.desc), "--out", str(out)), "notes.txt",
                            "not written by `make model`", kept=kept)


if __name__ == "__main__":
    unittest.main()
