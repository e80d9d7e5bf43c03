"""Fuzzing derive's description reader (Hypothesis): a model or tasks description, valid or
mutated by random edits (TOML's characters, keys, values of the wrong type, long runs), or
random bytes, is read by load_model / load_tasks. Each must give a description, or raise
DescriptionError with one line naming the file, at most a few hundred characters: never another
exception (derive.py would print a traceback instead of its one line and status 2).

    derive/.venv/bin/python -m unittest derive/tests/test_fuzz_description.py     (in make test)
    TOOLCONF_FUZZ_CASES=20000 derive/.venv/bin/python -m unittest derive/tests/test_fuzz_description.py

(200 cases per reader by default; the second line is the long run, docs/reference/errors.md.)
"""

from __future__ import annotations

import os
import sys
import tempfile
import unittest
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.files import MAX_DESCRIPTION_BYTES  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
BASES = {
    "model": [(ROOT / "tests" / "fixtures" / "pendulum.toml").read_text(),
              (ROOT / "derive" / "models" / "arm2_exact.toml").read_text()],
    "tasks": [(ROOT / "derive" / "tasks.toml").read_text()],
}
TOKENS = ['"', "'", "=", "[", "]", "{", "}", ",", "\n", ".", "#", "\\", " ", "\0", "Π", "nan", "inf",
          "1e308", "-1", "0", "true", "[]", "{}", '""', '"""', "[[", "]]", "name", "dof", "kind",
          "q", "q_dot", "u", "terms", "error", "theta", "explicit", "planar_chain", "links",
          "mass", "length", "payload", "gravity", "[model]", "[[parameters]]", "[dynamics]",
          "[equilibrium]", "[[task]]", "sensitivity", "defaults", "precision"]
CASES = int(os.environ.get("TOOLCONF_FUZZ_CASES", "200"))
MAX_MESSAGE = 600


@st.composite
def mutated(draw, kind: str) -> bytes:
    if draw(st.integers(0, 9)) == 0:
        return draw(st.binary(max_size=400))
    text = draw(st.sampled_from(BASES[kind]))
    for _ in range(draw(st.integers(0, 6))):
        at = draw(st.integers(0, len(text)))
        token = draw(st.sampled_from(TOKENS))
        action = draw(st.sampled_from(["insert", "delete", "replace", "repeat"]))
        if action == "insert":
            text = text[:at] + token + text[at:]
        elif action == "delete":
            text = text[:at] + text[at + draw(st.integers(1, 12)):]
        elif action == "replace":
            text = text[:at] + token + text[at + draw(st.integers(1, 8)):]
        else:
            text = text[:at] + token * draw(st.integers(1, 20_000)) + text[at:]
    return text.encode("utf-8", "surrogatepass")


class DescriptionReaderFuzz(unittest.TestCase):
    def read(self, data: bytes, reader) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "fuzz.toml"
            path.write_bytes(data)
            try:
                reader(path)
            except DescriptionError as err:
                message = str(err)
                self.assertNotIn("\n", message)
                self.assertTrue(message.startswith(f"{path}: "), message)
                self.assertLessEqual(len(message), MAX_MESSAGE + len(str(path)), message[:200])

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(mutated("model"))
    def test_model_descriptions(self, data: bytes) -> None:
        self.read(data, load_model)

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(mutated("tasks"))
    def test_task_descriptions(self, data: bytes) -> None:
        self.read(data, load_tasks)

    def test_a_file_past_the_size_limit_is_one_line(self) -> None:
        with self.assertRaises(DescriptionError) as caught:
            self.read_strict(b"#" * (MAX_DESCRIPTION_BYTES + 1))
        self.assertIn("larger than 1048576 bytes", str(caught.exception))
        # A device is refused by what it is, before a byte is read (a terminal would block).
        with self.assertRaises(DescriptionError) as caught:
            load_model(Path("/dev/zero"))
        self.assertEqual(str(caught.exception), "/dev/zero: a character device, not a description file")

    def read_strict(self, data: bytes) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "big.toml"
            path.write_bytes(data)
            load_model(path)


if __name__ == "__main__":
    unittest.main()
