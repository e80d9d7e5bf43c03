"""The IR's dataclasses (toolconf_derive/ir_types.py) are built from derive/ir_schema.json, the JSON
Schema the renderer prints of its structs (derive/render/src/ir.rs, whose tests/ir_schema.rs keeps
the file what they describe). These check the building: every struct becomes a dataclass with its
fields in order and the ones left out when None marked so; the fixture IR that the renderer's tests
read goes through them byte for byte; and a schema that differs from the documents by a missing,
an extra or a moved field is caught by that round trip. Without Rust."""

from __future__ import annotations

import copy
import dataclasses
import json
import sys
import types
import typing
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))

from toolconf_derive import ir_types  # noqa: E402

FIXTURE = ROOT / "tests" / "fixtures" / "pendulum.json"


def schema() -> dict:
    return json.loads(ir_types.SCHEMA_FILE.read_text())


def structs(s: dict) -> dict[str, dict]:
    return {s["title"]: s} | {n: d for n, d in s["$defs"].items() if "properties" in d}


class BuildTest(unittest.TestCase):
    def test_every_struct_is_a_dataclass_with_its_fields_in_order(self):
        found = structs(schema())
        self.assertGreater(len(found), 30, "the schema's structs were not found")
        for name, s in found.items():
            with self.subTest(struct=name):
                cls = getattr(ir_types, name)
                self.assertEqual([f.name for f in dataclasses.fields(cls)], list(s["properties"]))
                self.assertEqual([f.name for f in dataclasses.fields(cls) if f.metadata.get("omit_none")],
                                 [k for k in s["properties"] if k not in s["required"]])
                self.assertIsInstance(typing.get_type_hints(cls), dict)  # every annotation resolves

    def test_the_fields_the_renderer_has_optional_are_so_here(self):
        # Independent of the builder: what ir.rs says of these fields, read off it by hand.
        hints = typing.get_type_hints(ir_types.Function)
        self.assertEqual(hints["sequence"], ir_types.Sequence | None)
        self.assertEqual(hints["cost"], ir_types.Cost)
        self.assertEqual(typing.get_type_hints(ir_types.Ir)["report"], ir_types.ClosedFormReport | ir_types.UrdfReport)
        self.assertEqual(typing.get_type_hints(ir_types.Cost)["kinds"], dict[str, int])
        self.assertEqual(ir_types.IR_SCHEMA, json.loads(FIXTURE.read_text())["schema"])

    def test_a_field_written_always_after_one_left_out_is_refused_naming_both(self):
        s = {"properties": {"a": {"type": ["string", "null"]}, "b": {"type": "integer"}}, "required": ["b"]}
        with self.assertRaisesRegex(ValueError, r"X: 'b' is written always but comes after 'a'"):
            ir_types.dataclass_of("X", s, {})

    def test_a_type_with_no_python_type_is_refused_naming_it(self):
        with self.assertRaisesRegex(ValueError, "'tuple'"):
            ir_types.annotation({"type": "tuple"}, {})


class JsonTest(unittest.TestCase):
    def test_an_omitted_field_is_left_out_and_a_nullable_one_written_null(self):
        entry = ir_types.Entry(row=1, col=2)
        self.assertEqual(json.dumps(ir_types.as_json(entry)), '{"row": 1, "col": 2}')
        gradient = ir_types.GradientReport(reference="0.35", values=[ir_types.GradientValue("m", "1.0")], closed=None)
        self.assertEqual(ir_types.as_json(gradient),
                         {"reference": "0.35", "values": [{"name": "m", "value": "1.0"}], "closed": None})

    def test_the_fixture_ir_round_trips_through_the_dataclasses_byte_for_byte(self):
        text = FIXTURE.read_text()
        ir = _load(vars(ir_types), ir_types.Ir, json.loads(text))
        self.assertIsInstance(ir.report, ir_types.ClosedFormReport)
        self.assertEqual(_written(ir), text)


class CaughtTest(unittest.TestCase):
    """A schema that is not the documents' (a field the renderer no longer has, a new one, two
    swapped) fails the round trip above: built from such a schema, the dataclasses refuse the
    fixture or write it otherwise."""

    def types_without(self, change) -> dict:
        s = copy.deepcopy(schema())
        change(s["$defs"]["Model"])
        return ir_types.dataclasses_of(s)

    def test_a_missing_field_is_caught(self):
        def drop(model):
            del model["properties"]["tip_dim"]
            model["required"].remove("tip_dim")
        built = self.types_without(drop)
        with self.assertRaisesRegex(ValueError, r"Model: unknown keys \['tip_dim'\]"):
            _load(built, built["Ir"], json.loads(FIXTURE.read_text()))

    def test_an_extra_field_is_caught(self):
        def add(model):
            model["properties"] = {"degrees": {"type": "integer"}} | model["properties"]
            model["required"].insert(0, "degrees")
        built = self.types_without(add)
        with self.assertRaisesRegex(TypeError, "degrees"):
            _load(built, built["Ir"], json.loads(FIXTURE.read_text()))

    def test_a_moved_field_is_caught(self):
        def swap(model):
            p = model["properties"]
            order = ["state_dim", "dof"] + [k for k in p if k not in ("dof", "state_dim")]
            model["properties"] = {k: p[k] for k in order}
        built = self.types_without(swap)
        text = FIXTURE.read_text()
        self.assertNotEqual(_written(_load(built, built["Ir"], json.loads(text))), text)


def _written(ir) -> str:
    """As derive.py writes an IR."""
    return json.dumps(ir_types.as_json(ir), indent=1, ensure_ascii=False) + "\n"


def _load(names: dict, cls, data):
    """`data` (JSON) as dataclass `cls`, by the classes `names` its fields' annotations name."""
    hints = typing.get_type_hints(cls, names)
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = set(data) - fields
    if unknown:
        raise ValueError(f"{cls.__name__}: unknown keys {sorted(unknown)}")
    return cls(**{k: _value(names, hints[k], v) for k, v in data.items()})


def _value(names: dict, hint, data):
    if data is None:
        return None
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        options = [a for a in typing.get_args(hint) if a is not type(None)]
        if len(options) > 1:  # the report: the kind whose fields the data has
            for option in options:
                if {f.name for f in dataclasses.fields(option)} == set(data):
                    return _load(names, option, data)
            raise ValueError(f"no kind of {hint} has the keys {sorted(data)}")
        return _value(names, options[0], data)
    if origin is list:
        return [_value(names, typing.get_args(hint)[0], d) for d in data]
    if dataclasses.is_dataclass(hint):
        return _load(names, hint, data)
    return data


if __name__ == "__main__":
    unittest.main()
