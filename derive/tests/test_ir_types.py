"""The IR's dataclasses (toolconf_derive/ir_types.py) mirror the renderer's structs
(derive/render/src/ir.rs): the same structs, each with the same fields in the same order, the same
ones optional (`Option` there, `| None` here) and the same ones left out of the JSON when None.
The renderer refuses unknown and missing keys, so a difference would otherwise show only when an
IR is rendered; this finds it without Rust."""

from __future__ import annotations

import dataclasses
import json
import re
import sys
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))

from toolconf_derive import ir_types  # noqa: E402

RUST = ROOT / "derive" / "render" / "src" / "ir.rs"
OMITTED = '#[serde(default, skip_serializing_if = "Option::is_none")]'


def rust_structs(text: str) -> dict[str, list[tuple[str, bool, bool]]]:
    """`pub struct`s of ir.rs: name -> [(field, optional, omitted when None)] in order."""
    structs = {}
    for m in re.finditer(r"^pub struct (\w+)(?:<[^>]*>)? \{\n(.*?)^\}", text, re.M | re.S):
        fields, omitted = [], False
        for line in m.group(2).splitlines():
            line = line.strip()
            if line == OMITTED:
                omitted = True
            f = re.fullmatch(r"pub (?:r#)?(\w+): (.+),", line)
            if f:
                fields.append((f.group(1), f.group(2).startswith("Option<"), omitted))
                omitted = False
        structs[m.group(1)] = fields
    return structs


def python_dataclasses() -> dict[str, list[tuple[str, bool, bool]]]:
    out = {}
    for name, cls in vars(ir_types).items():
        if isinstance(cls, type) and dataclasses.is_dataclass(cls) and cls.__module__ == ir_types.__name__:
            out[name] = [(f.name, str(f.type).endswith("| None"), bool(f.metadata.get("omit_none")))
                         for f in dataclasses.fields(cls)]
    return out


class MirrorTest(unittest.TestCase):
    def test_every_struct_has_its_dataclass_with_the_same_fields(self):
        rust = rust_structs(RUST.read_text())
        python = python_dataclasses()
        self.assertGreater(len(rust), 30, "ir.rs's structs were not found")
        self.assertEqual(sorted(rust), sorted(python))
        for name in rust:
            with self.subTest(struct=name):
                self.assertEqual(rust[name], python[name])

    def test_the_parser_sees_a_field_an_option_and_an_omitted_one(self):
        text = ('pub struct A<R = B> {\n    pub x: u64,\n    pub r#struct: Option<String>,\n'
                f'    {OMITTED}\n    pub y: Option<u64>,\n}}\n')
        self.assertEqual(rust_structs(text), {"A": [("x", False, False), ("struct", True, False), ("y", True, True)]})


class JsonTest(unittest.TestCase):
    def test_an_omitted_field_is_left_out_and_a_nullable_one_written_null(self):
        entry = ir_types.Entry(row=1, col=2)
        self.assertEqual(json.dumps(ir_types.as_json(entry)), '{"row": 1, "col": 2}')
        gradient = ir_types.GradientReport(reference="0.35", values=[ir_types.GradientValue("m", "1.0")], closed=None)
        self.assertEqual(ir_types.as_json(gradient),
                         {"reference": "0.35", "values": [{"name": "m", "value": "1.0"}], "closed": None})

    def test_the_fixture_ir_round_trips_through_the_dataclasses_byte_for_byte(self):
        # Read back into the dataclasses by their own field lists, written again: the same bytes.
        path = ROOT / "tests" / "fixtures" / "pendulum.json"
        text = path.read_text()
        ir = _load(ir_types.Ir, json.loads(text))
        self.assertIsInstance(ir.report, ir_types.ClosedFormReport)
        self.assertEqual(json.dumps(ir_types.as_json(ir), indent=1, ensure_ascii=False) + "\n", text)


def _load(cls, data):
    """`data` (JSON) as dataclass `cls`, by the names its fields' annotations give."""
    import typing
    hints = typing.get_type_hints(cls, vars(ir_types))
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name in data:
            kwargs[f.name] = _value(hints[f.name], data[f.name])
    unknown = set(data) - {f.name for f in dataclasses.fields(cls)}
    if unknown:
        raise ValueError(f"{cls.__name__}: unknown keys {sorted(unknown)}")
    return cls(**kwargs)


def _value(hint, data):
    import types
    import typing
    if data is None:
        return None
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        options = [a for a in typing.get_args(hint) if a is not type(None)]
        if len(options) > 1:  # the report: the kind whose fields the data has
            for option in options:
                if {f.name for f in dataclasses.fields(option)} == set(data):
                    return _load(option, data)
            raise ValueError(f"no kind of {hint} has the keys {sorted(data)}")
        return _value(options[0], data)
    if origin is list:
        return [_value(typing.get_args(hint)[0], d) for d in data]
    if dataclasses.is_dataclass(hint):
        return _load(hint, data)
    return data


if __name__ == "__main__":
    unittest.main()
