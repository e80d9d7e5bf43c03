"""`make model`: one description, outside the repository, becomes a shared library with toolconf's
C ABI (and its header) that a program can load, with its progress shown step by step and nothing
in the repository changed; bad input is one line and status 2, with nothing left behind; an
interrupted run keeps the old library (part of make test)."""

from __future__ import annotations

import ctypes
import json
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
from test_make_crate import MAKE_ENV, assert_terminated_cleanly, files_under, git_status  # noqa: E402

# make's own line about a recipe that failed, `make: *** ...`, or `make[1]: *** ...` when these
# tests run under another make (make test).
MAKES_OWN = re.compile(r"make(\[\d+\])?: \*\*\* ")



def interruptible() -> None:
    """In the child, SIGINT's default action, as a shell in a terminal gives its foreground job: a
    test run started in the background of a non-interactive shell inherits SIGINT ignored, and an
    ignored signal is discarded even while make model's first lines hold it blocked."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class MakeModel(unittest.TestCase):
    def setUp(self):
        self.base = Path(self.enterContext(tempfile.TemporaryDirectory(prefix="toolconf-make-model-")))
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
                               text=True, env=MAKE_ENV)
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

    def run_make(self, *args: str) -> subprocess.CompletedProcess:
        return subprocess.run(["make", "--no-print-directory", "-s", *args], cwd=ROOT, capture_output=True, text=True,
                              env=MAKE_ENV)

    def own_lines(self, r: subprocess.CompletedProcess, command: str = "make model") -> list[str]:
        """stderr's lines but make's own (`make: *** [...] Error 2`), each checked to be the command's."""
        lines = [line for line in r.stderr.splitlines() if not MAKES_OWN.match(line)]
        for line in lines:
            self.assertTrue(line.startswith(f"{command}: "), r.stderr)
        return lines

    def test_make_arguments_are_data_never_shell_code(self):
        # Backticks, $(...), make's own $(shell ...), quotes and a newline in DESC, IR, OUT, TASKS
        # (and make crate's MODELS, NAME): nothing runs, each is one line, status 2.
        marker = self.base / "ran"
        code = [f"`touch {marker}1`", f"$(touch {marker}2)", f'"; touch {marker}3; "', f"$(shell touch {marker}4)",
                f"$$(touch {marker}5)", f"'; touch {marker}6; '"]
        out = self.base / "out"
        for c in code:
            for args in ([f"DESC={self.base}/{c}x.toml", f"OUT={out}"], [f"IR={self.base}/{c}.json", f"OUT={out}"],
                         [f"DESC={self.desc}", f"OUT={self.base}/{c}"], [f"DESC={self.desc}", f"TASKS={c}", f"OUT={out}"]):
                r = self.run_make("model", *args)
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertEqual(len(self.own_lines(r)), 1, r.stderr)
            r = self.run_make("crate", f"MODELS={self.base}/{c}", f"OUT={out}", f"NAME={c}")
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertEqual(len(self.own_lines(r, "make crate")), 1, r.stderr)
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml"])
        r = self.run_make("model", f"DESC={self.desc}", f"OUT={self.base}/a\nb")
        self.assertEqual(self.own_lines(r), [f"make model: OUT='{self.base}/a\\nb': holds U+000A (a control "
                                             f"character or line break) at character {len(str(self.base)) + 3}; give "
                                             "a path of one line"])
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml"])

    def test_an_ir_is_read_bounded_and_its_vectors_only_from_beside_it(self):
        out = str(self.base / "out")
        huge = self.base / "huge.json"
        with open(huge, "wb") as f:
            f.truncate(2 << 30)  # 2 GiB, sparse
        self.assert_refused(self.run_make_model("--ir", str(huge), "--out", out), f"IR={huge}", "larger than",
                            kept=files_under(self.base))
        huge.unlink()
        ir = json.loads((ROOT / "generated" / "msd.json").read_text())
        here = self.base / "msd.json"

        def refused(edit, *words, vectors: str | None = None):
            document = json.loads(json.dumps(ir))
            edit(document)
            here.write_text(json.dumps(document))
            if vectors is not None:
                (self.base / "msd.vectors.json").symlink_to(vectors)
            self.assert_refused(self.run_make_model("--ir", str(here), "--out", out), f"IR={here}", *words,
                                kept=files_under(self.base))
            for p in self.base.iterdir():
                if p.name.startswith("msd"):
                    p.unlink()

        for file in ("../../../../etc/hostname", "/etc/hostname", "sub/msd.vectors.json", ".vectors.json"):
            refused(lambda d, f=file: d["test_vectors"].update(file=f), "test_vectors.file", "not the name of a file")
        # The right name, but a link out of the folder.
        refused(lambda d: None, "symbolic link", vectors="/etc/hostname")
        for name in ("../../evil", "a" * 300, "Evil"):
            refused(lambda d, n=name: d["model"].update(name=n), "model.name")
        # The rest is the renderer's check, before anything is made: a line break in a title, code
        # in a closed form, each one line naming the key.
        shutil.copy(ROOT / "generated" / "msd.vectors.json", self.base / "msd.vectors.json")
        for edit, key in ((lambda d: d["model"].update(title="a\nb"), "model.title"),
                          (lambda d: d["functions"][0]["temporaries"].append({"name": "x", "rust": "{ abort() }"}),
                           "functions[0].temporaries")):
            document = json.loads(json.dumps(ir))
            edit(document)
            here.write_text(json.dumps(document))
            self.assert_refused(self.run_make_model("--ir", str(here), "--out", out), f"IR={here}", key,
                                kept=files_under(self.base))

    def test_a_long_name_or_a_tip_that_is_code_is_refused_before_anything_is_derived(self):
        out = str(self.base / "out")
        text = PENDULUM.read_text()
        for edit, key in ((text.replace('name = "pendulum"', f'name = "{"p" * 300}"'), "model.name"),
                          (text.replace('"l*sin(theta)"', '"__import__(\'os\').system(\'x\')"'), "tip.position[1]")):
            self.desc.write_text(edit)
            r = self.run_make_model("--desc", str(self.desc), "--out", out)
            self.assert_refused(r, "my_pendulum.toml", key)

    def test_an_interrupt_while_make_model_starts_is_one_line(self):
        # Ctrl-C (SIGINT to make's process group, as a terminal sends it) at times within the first
        # 0.1 s: never a traceback, at most one line of make model's, the shell's status for it.
        for delay in (0.0, 0.01, 0.02, 0.04, 0.06, 0.08, 0.1):
            run = subprocess.Popen(["make", "--no-print-directory", "-s", "model", f"DESC={self.desc}",
                                    f"OUT={self.base / 'out'}"], cwd=ROOT, stderr=subprocess.PIPE, text=True,
                                   env=MAKE_ENV, start_new_session=True, preexec_fn=interruptible)
            time.sleep(delay)
            os.killpg(run.pid, signal.SIGINT)
            stderr = run.communicate(timeout=300)[1]
            self.assertNotIn("Traceback", stderr)
            ours = [line for line in stderr.splitlines() if not MAKES_OWN.match(line)]
            self.assertLessEqual(len(ours), 1, stderr)
            self.assertIn(run.returncode, (-signal.SIGINT, 2, 130), stderr)
            if ours:
                self.assertEqual(ours, ["make model: interrupted; nothing changed"], stderr)
            self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml"])

    def test_two_runs_at_once_each_make_their_library(self):
        # Three runs at once, two of them to one OUT: each ends well and its library is whole; the
        # build folder is shared (the dependencies built once) and taken in turn.
        ir = ROOT / "generated" / "msd.json"
        outs = [self.base / "one", self.base / "two", self.base / "two"]
        runs = [subprocess.Popen([*MAKE_MODEL, "--ir", str(ir), "--out", str(out)], cwd=self.base,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for out in outs]
        results = [(run.communicate(timeout=900)[1], run.returncode) for run in runs]
        results = [(status, stderr) for stderr, status in results]
        for status, stderr in results:
            self.assertEqual(status, 0, stderr)
            self.assertNotIn("Traceback", stderr)
        self.assertTrue(any("waiting for another make model run" in stderr for _, stderr in results), results)
        for out in outs:
            library = out / "libtoolconf_model_msd.so"
            lib = ctypes.CDLL(str(library))
            lib.toolconf_abi_version.restype = ctypes.c_uint32
            header = (out / "toolconf_model.h").read_text()
            version = int(re.search(r"#define TOOLCONF_ABI_VERSION (\d+)u", header).group(1))
            self.assertEqual(lib.toolconf_abi_version(), version)
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml", "one", "two"])

    def test_a_description_becomes_a_library_that_loads_and_computes_with_each_step_shown(self):
        # Its text fields hold what would be code if pasted into the Rust: a unit that closes its
        # literal and adds a constructor writing a canary file, a title that closes a C comment,
        # an indented doctest, fences, quotes and a trigraph. They are text: the library builds,
        # loads, and the canary never appears.
        canary = self.base / "canary"
        unit = (f'kg", "", ""]; #[used] #[link_section = ".init_array"] static INIT: extern "C" fn() = init; '
                f'extern "C" fn init() {{ let _ = std::fs::write("{canary}", ""); }} const _X: [&str; 3] = ["')
        text = PENDULUM.read_text().replace('unit = "kg"', f"unit = {json.dumps(unit)}", 1)
        for old, new in (('title = "Uniform rod pendulum driven at its pivot"', 'title = "*/ #define X 1 /* ??/"'),
                         ('doc = "mass of the rod"', f'doc = "    std::fs::write(\\"{canary}\\", \\"\\"); //"'),
                         ('equations = ["moment balance at the pivot"]', 'equations = ["```", "~~~ rust"]')):
            self.assertIn(old, text)
            text = text.replace(old, new, 1)
        self.desc.write_text(text)
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
        self.assertFalse(canary.exists())
        self.assertIn(f"pub const PARAMETER_UNITS: [&str; 2] = [{json.dumps(unit)}, \"m\",",
                      (out / "generated" / "src" / "pendulum.rs").read_text())
        self.assertIn(" * * / #define X 1 / * ??/.\n", header)
        if before is not None:
            self.assertEqual(git_status(), before)

        # Made again over itself: replaced; then terminated while making it anew: the old library
        # is as it was, and no temporary folder is left.
        again = self.run_make_model("--desc", str(self.desc), "--out", str(out))
        self.assertEqual(again.returncode, 0, again.stderr)
        assert_terminated_cleanly(self, "make model", [*MAKE_MODEL, "--desc", str(self.desc), "--out", str(out)],
                                  self.base, out, ".pendulum-lib-partial-")
        self.assertEqual(sorted(p.name for p in self.base.iterdir()), ["my_pendulum.toml", "pendulum-lib"])
        # A file of the user's in it: not replaced.
        (out / "notes.txt").write_text("mine")
        kept = files_under(self.base)
        self.assert_refused(self.run_make_model("--desc", str(self.desc), "--out", str(out)), "notes.txt",
                            "not written by `make model`", kept=kept)


if __name__ == "__main__":
    unittest.main()
