"""The IR's types: one dataclass per struct of the renderer's derive/render/src/ir.rs, built at import
from derive/ir_schema.json, the JSON Schema the renderer prints of those structs (`toolconf-render
--ir-schema`; its test derive/render/tests/ir_schema.rs keeps the file what ir.rs says). So the IR's
fields are written once, in Rust, where the documents are read: each dataclass here has its
struct's name, docs and fields in the same order, which is the order of the keys in the JSON.

A field the schema does not list as `required` is left out of the JSON when it is None (the
renderer's `#[serde(default, skip_serializing_if = "Option::is_none")]`) and defaults to None, as
`omitted()` makes it; every other field is written, as `null` when it is None. `as_json` turns a
document of these into what json.dumps writes. `IR_SCHEMA` is the schema number the renderer reads.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import field
from pathlib import Path
from typing import Any

SCHEMA_FILE = Path(__file__).resolve().parents[1] / "ir_schema.json"

# JSON Schema's scalar types as Python's, for the fields' annotations.
_SCALARS = {"string": "str", "integer": "int", "number": "float", "boolean": "bool", "null": "None"}


def omitted():
    """A field left out of the JSON when it is None."""
    return field(default=None, metadata={"omit_none": True})


def as_json(value: Any) -> Any:
    """`value` as JSON data: a dataclass as an object of its fields in order (an `omitted()` one
    left out when None), lists and dicts item by item, anything else as it is."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: as_json(getattr(value, f.name)) for f in dataclasses.fields(value)
                if not (f.metadata.get("omit_none") and getattr(value, f.name) is None)}
    if isinstance(value, (list, tuple)):
        return [as_json(v) for v in value]
    if isinstance(value, dict):
        return {k: as_json(v) for k, v in value.items()}
    return value


def annotation(schema: dict, defs: dict) -> str:
    """The Python type that a field's JSON Schema describes, as an annotation's text: a struct by
    its name (which the module resolves), any other of the `defs` it names as what it is (an enum
    as `str`, the report as its two kinds). For readers and typing.get_type_hints only: nothing
    here checks a value's type (the renderer does, naming the key)."""
    if "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[1]
        return name if "properties" in defs[name] else annotation(defs[name], defs)
    if "anyOf" in schema or "oneOf" in schema:
        options = [annotation(s, defs) for s in schema.get("anyOf") or schema["oneOf"]]
    else:
        kinds = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        options = [_kind(kind, schema, defs) for kind in kinds]
    # One of each, None last (`float | None`), as they would be written by hand.
    unique = sorted(dict.fromkeys(options), key=lambda o: o == "None")
    return " | ".join(unique)


def _kind(kind: str, schema: dict, defs: dict) -> str:
    if kind == "array":
        return f"list[{annotation(schema['items'], defs)}]"
    if kind == "object":
        return f"dict[str, {annotation(schema['additionalProperties'], defs)}]"
    if kind not in _SCALARS:
        raise ValueError(f"{SCHEMA_FILE.name}: no Python type for the JSON Schema type {kind!r}")
    return _SCALARS[kind]


def dataclass_of(name: str, schema: dict, defs: dict) -> type:
    """The dataclass of the struct `name` whose JSON Schema is `schema` (`defs`: the others, by
    name, which its fields refer to): its properties in order, one the schema does not require an
    `omitted()` field. Those must come after every written one, as a dataclass's defaults must
    (and the callers build these by position too)."""
    required = schema.get("required", [])
    fields, optional_seen = [], None
    for key, sub in schema["properties"].items():
        if key in required:
            if optional_seen:
                raise ValueError(f"{SCHEMA_FILE.name}: {name}: {key!r} is written always but comes after "
                                 f"{optional_seen!r}, which is left out when None; put it first in ir.rs")
            fields.append((key, annotation(sub, defs)))
        else:
            optional_seen = key
            fields.append((key, annotation(sub, defs), omitted()))
    cls = dataclasses.make_dataclass(name, fields, namespace={"__doc__": schema.get("description")})
    # make_dataclass would name another module; the annotations resolve in this one.
    cls.__module__ = __name__
    return cls


def dataclasses_of(schema: dict) -> dict[str, type]:
    """Every struct of an IR's JSON Schema (the document at its root, the rest under `$defs`; an
    enum or the report's choice of kinds is no struct) as its dataclass, by name."""
    defs = schema.get("$defs", {})
    structs = {schema["title"]: schema} | {n: s for n, s in defs.items() if "properties" in s}
    return {name: dataclass_of(name, s, defs) for name, s in structs.items()}


_SCHEMA = json.loads(SCHEMA_FILE.read_text(encoding="utf-8"))
IR_SCHEMA: int = _SCHEMA["properties"]["schema"]["const"]
_TYPES = dataclasses_of(_SCHEMA)
globals().update(_TYPES)
__all__ = ["IR_SCHEMA", "annotation", "as_json", "dataclass_of", "dataclasses_of", "omitted", *_TYPES]
