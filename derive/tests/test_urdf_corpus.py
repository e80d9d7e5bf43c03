"""The derivation's URDF reader against the corpus both URDF readers share (tests/fixtures/urdf/,
cases.json): each file accepted or refused as listed, a refusal one line naming the file and
holding the listed phrase. The tool reader (crates/tool-urdf/) is run on the same
files by tests/urdf_corpus.rs, so that the two agree on what a URDF is (the URDF specification's
rules: a <limit> on every revolute and prismatic joint, its absent bounds 0; the links one tree;
numbers ASCII decimals).

    derive/.venv/bin/python -m unittest derive/tests/test_urdf_corpus.py
"""

from __future__ import annotations

import json
import sys
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))

from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.urdf import read_chain  # noqa: E402

CORPUS = ROOT / "tests" / "fixtures" / "urdf"


class Corpus(unittest.TestCase):
    def test_each_file_is_accepted_or_refused_as_listed(self):
        cases = json.loads((CORPUS / "cases.json").read_text())["cases"]
        self.assertGreater(len(cases), 10)
        for case in cases:
            path = CORPUS / case["file"]
            with self.subTest(case["file"]):
                if case["accepted"]:
                    chain = read_chain(path, "base", "flange")
                    self.assertEqual(chain.dof, 1)
                    continue
                with self.assertRaises(DescriptionError) as caught:
                    read_chain(path, "base", "flange")
                message = str(caught.exception)
                self.assertTrue(message.startswith(f"{path}: "), message)
                self.assertNotIn("\n", message)
                self.assertIn(case["derive"], message)

    def test_an_absent_bound_is_zero(self):
        chain = read_chain(CORPUS / "limit_bounds_absent.urdf", "base", "flange")
        self.assertEqual(chain.limits, ((0.0, 0.0),))
        self.assertEqual(read_chain(CORPUS / "good.urdf", "base", "flange").limits, ((-2.0, 2.0),))


if __name__ == "__main__":
    unittest.main()
