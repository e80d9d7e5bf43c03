"""docs/reference/description.md is the reference of the description file: every key the reader accepts is
documented there, nothing it does not accept is, and the committed file is what reference.py
writes (make derive rewrites it; the drift check names its first differing line)."""

from __future__ import annotations

import sys
import tomllib
import unittest
from pathlib import Path

DERIVE = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(DERIVE))

from toolconf_derive.description import load_model  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.reference import MEANING, description_reference, undocumented  # noqa: E402

ROOT = DERIVE.parent


class ReferenceTest(unittest.TestCase):
    def test_every_key_the_reader_knows_is_documented_and_no_other(self):
        self.assertEqual(undocumented(), [])

    def test_the_committed_reference_is_current(self):
        committed = (ROOT / "docs" / "reference" / "description.md").read_text()
        self.assertEqual(committed, description_reference(), "run `make derive` and commit docs/reference/description.md")

    def test_every_key_the_shipped_descriptions_use_is_in_the_reference(self):
        tables = {t for t, _ in MEANING}
        for path in sorted((DERIVE / "models").glob("*.toml")):
            data = tomllib.loads(path.read_text())
            for table, body in data.items():
                self.assertIn(("(top level)", table), MEANING, f"{path.name}: [{table}]")
                if table in tables and isinstance(body, dict):
                    for key in body:
                        self.assertIn((table, key), MEANING, f"{path.name}: {table}.{key}")

    def test_a_missing_urdf_names_the_description_the_key_and_the_rule(self):
        import tempfile
        text = (DERIVE / "models" / "panda.toml").read_text().replace(
            'file = "../robots/panda_description/urdf/panda.urdf"', 'file = "robots/panda.urdf"')
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp, "mine.toml")
            path.write_text(text)
            with self.assertRaises(DescriptionError) as caught:
                load_model(path)
        message = str(caught.exception)
        self.assertIn(str(path), message)
        self.assertIn("urdf.file", message)
        self.assertIn("relative to the folder of the description", message)


if __name__ == "__main__":
    unittest.main()


class DocsExample(unittest.TestCase):
    def test_the_urdf_arms_reference_example_description_loads_as_written(self):
        import re
        import tempfile
        text = (ROOT / "docs" / "reference" / "urdf-arms.md").read_text()
        block = re.search(r"## The description \(kind `urdf`\)\n\n```toml\n(.*?)```", text, re.S).group(1)
        with tempfile.TemporaryDirectory() as tmp:
            # The example sits where derive/models/ does, so its relative urdf.file resolves.
            models = Path(tmp, "derive", "models")
            models.mkdir(parents=True)
            path = models / "example.toml"
            path.write_text(block)
            Path(tmp, "derive", "robots").symlink_to(DERIVE / "robots")
            model = load_model(path)
        self.assertEqual(model.name, "panda")
        self.assertEqual(model.dof, 7)
