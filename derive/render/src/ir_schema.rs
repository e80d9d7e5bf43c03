//! The IR's types described for the derivation, which writes the documents this renderer reads:
//! `toolconf-render --ir-schema` prints them as a JSON Schema, committed as `derive/ir_schema.json`,
//! from which `derive/toolconf_derive/ir_types.py` builds its dataclasses. The structs of
//! [`crate::ir`] are so the one place the IR's fields are written; `tests/ir_schema.rs` fails,
//! rewriting the file, when it is not what they describe.
//!
//! The schema is of what a document holds as written (schemars' serialize contract): a field
//! missing from its struct's `required` is one left out of the JSON when it has no value
//! (`#[serde(default, skip_serializing_if = "Option::is_none")]`); every other field is always
//! written, `null` where it may have no value. Each struct's `properties` are in the order of its
//! fields, the order of the keys in the JSON, which serde-reflection reads from the `Deserialize`
//! impls (a JSON Schema's properties have no order of their own, and schemars' map sorts them).

use std::collections::BTreeMap;

use schemars::generate::SchemaSettings;
use serde::Serialize;
use serde_json::{Map, Value};
use serde_reflection::{ContainerFormat, Tracer, TracerConfig};

use crate::ir::{ClosedFormReport, Ir, UrdfReport, IR_SCHEMA};

/// The IR's JSON Schema as `derive/ir_schema.json` holds it (pretty-printed, one newline at the
/// end), or why it cannot be described.
pub fn ir_schema() -> Result<String, String> {
    let generator = SchemaSettings::draft2020_12()
        .for_serialize()
        .into_generator();
    let mut schema = generator.into_root_schema_for::<Ir>().to_value();
    // The one schema number this renderer reads, for the derivation to write.
    schema["properties"]["schema"]["const"] = IR_SCHEMA.into();
    let orders = field_orders()?;
    let written = in_order(&schema, "Ir", &orders)?;
    let text = serde_json::to_string_pretty(&written).map_err(|e| e.to_string())?;
    Ok(text + "\n")
}

/// Each struct's fields in the order its `Deserialize` impl names them (declaration order),
/// traced from the whole document: both kinds of report and everything they hold.
fn field_orders() -> Result<BTreeMap<String, Vec<String>>, String> {
    let mut tracer = Tracer::new(TracerConfig::default());
    let traced = |e: serde_reflection::Error| format!("tracing the IR's types: {e}");
    tracer
        .trace_simple_type::<Ir<ClosedFormReport>>()
        .map_err(traced)?;
    tracer.trace_simple_type::<UrdfReport>().map_err(traced)?;
    // Unchecked: an enum's variants may be left untraced (one pass reaches only its first), and
    // only the structs are read here; schemars names every variant.
    Ok(tracer
        .registry_unchecked()
        .into_iter()
        .filter_map(|(name, format)| match format {
            ContainerFormat::Struct(fields) => {
                Some((name, fields.into_iter().map(|f| f.name).collect()))
            }
            _ => None,
        })
        .collect())
}

/// A JSON value whose objects keep the order their keys were put in (serde_json's map, without
/// its `preserve_order` feature, which would change every map the workspace builds, sorts them).
enum Json {
    Value(Value),
    Object(Vec<(String, Json)>),
}

impl Serialize for Json {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Json::Value(v) => v.serialize(s),
            Json::Object(entries) => s.collect_map(entries.iter().map(|(k, v)| (k, v))),
        }
    }
}

/// `schema` (of the struct `name`, or the `$defs` holding the others) with each struct's
/// properties in its fields' order.
fn in_order(
    schema: &Value,
    name: &str,
    orders: &BTreeMap<String, Vec<String>>,
) -> Result<Json, String> {
    let Value::Object(map) = schema else {
        return Ok(Json::Value(schema.clone()));
    };
    let mut entries = Vec::new();
    for (key, value) in map {
        let value = match (key.as_str(), value) {
            ("properties", Value::Object(properties)) => {
                properties_in_order(properties, orders.get(name).map(Vec::as_slice))
                    .ok_or_else(|| format!("{name}: its schema's properties are not its fields"))?
            }
            ("$defs", Value::Object(defs)) => Json::Object(
                defs.iter()
                    .map(|(def, s)| Ok((def.clone(), in_order(s, def, orders)?)))
                    .collect::<Result<_, String>>()?,
            ),
            _ => Json::Value(value.clone()),
        };
        entries.push((key.clone(), value));
    }
    Ok(Json::Object(entries))
}

/// A struct's `properties` in the order of its `fields`; none if they are not the same names
/// (which would be a fault of this module, never of a document).
fn properties_in_order(properties: &Map<String, Value>, fields: Option<&[String]>) -> Option<Json> {
    let fields = fields
        .filter(|f| f.len() == properties.len() && f.iter().all(|f| properties.contains_key(f)))?;
    let entries = fields
        .iter()
        .map(|f| (f.clone(), Json::Value(properties[f].clone())));
    Some(Json::Object(entries.collect()))
}
