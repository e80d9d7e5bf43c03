//! Tool files: the user's own tools, one per row, read as a stream.
//!
//! CSV (any extension but `.json`): a header row, then one tool per row; a line that starts with
//! `#` is a comment (a tool's source, say) wherever it stands. Columns: `model`
//! (optional; an empty cell or no column means `arm2`), `name` (optional), and the parameter
//! names of the models used (`m1,m2,l1,l2` for arm2 and arm2_exact, `m1,m2,m3,l1,l2,l3` for
//! arm3, `tool_mass,tool_com_x,tool_com_y,tool_com_z,tool_ixx,tool_iyy,tool_izz` for the URDF
//! arms `panda` and `ur5`). Rows of different models share the file; a row leaves the columns its
//! model does not have empty. Each value must lie in its parameter's domain and the tool obey
//! its model's rule (`generated::validity`: > 0 for masses and lengths; a URDF tool's centre of
//! mass may be 0 or negative, within its bound, and its principal moments obey the triangle
//! inequality).
//!
//! JSON (`.json`): an array of objects with the same keys, e.g.
//! `[{"name": "hammer", "model": "arm2", "m1": 0.3, "m2": 0.4, "l1": 0.5, "l2": 0.2}]`.
//!
//! Rows are handed to a callback one at a time, so a file of 10⁷ tools is never held in memory,
//! and each row (a JSON tool) may be at most 1 MiB ([`crate::inputs::bounded_read`]), so that no file,
//! `/dev/zero` included, is read without bound. A bad row is an error naming the file, the line
//! (CSV) or tool number (JSON), the key and the value (clipped if long); the callback decides
//! whether it stops the read or is skipped. A column given twice in a CSV header, or a key twice
//! in a JSON tool, is refused.

use std::io::{BufReader, Read};
use std::path::Path;

use serde::de::{Error as _, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::{Map, Value};

use crate::inputs::bounded_read::{record_error, CsvRows, JsonElements, RecordLimit};
use crate::registry::{AnyTool, ModelKind};
use toolconf_messages::{Clip, ClipMessage, ClipPath, Short};

/// One tool read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolRow {
    /// 1-based position among the file's tools (header and blank lines not counted).
    pub row: usize,
    pub name: Option<String>,
    pub tool: AnyTool,
    /// The parameter columns the row left out, which took their model's default (a URDF tool's
    /// products of inertia and tip, zero): a task that reads the tip refuses a tool whose tip
    /// columns are among them ([`ToolRow::missing_tip`]).
    pub defaulted: Vec<&'static str>,
}

impl ToolRow {
    /// The tip columns (`tool_tip_*`) the row left out: a URDF tool's tip is its offset from the
    /// flange, and zero would silently put it at the flange.
    pub fn missing_tip(&self) -> Vec<&'static str> {
        let tip = |c: &&&str| c.starts_with("tool_tip_");
        self.defaulted.iter().filter(tip).copied().collect()
    }

    /// The name, or `row N` when the file gives none.
    pub fn label(&self) -> String {
        self.name
            .as_deref()
            .map_or_else(|| format!("row {}", self.row), |n| Clip(n).to_string())
    }
}

/// A bad tools file or row.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", if place.is_empty() { String::new() } else { format!(", {place}") })]
pub struct ToolFileError {
    pub file: String,
    /// `line 7`, `tool 3`, or empty for the whole file.
    pub place: String,
    pub message: String,
    /// A bad row that can be skipped; otherwise the file cannot be read on.
    pub row_level: bool,
}

/// What a row holds under one key.
enum Cell<'a> {
    Absent,
    Text(&'a str),
    Number(f64),
    Other(String),
}

/// Reads `path` and hands every row to `each`, in file order; returns the number of rows.
/// `each` gets bad rows as `Err` (with `row_level` set) and stops the read by returning `Err`.
/// A file without any row is an error.
pub fn read_tools(
    path: &Path,
    each: impl FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError>,
) -> Result<usize, ToolFileError> {
    let file_name = ClipPath(&path.to_string_lossy()).to_string();
    let fatal = |message: String| ToolFileError {
        file: file_name.clone(),
        place: String::new(),
        message,
        row_level: false,
    };
    let file = toolconf_files::input::open_stream(path).map_err(|e| match e {
        toolconf_files::input::InputError::NotAFile(kind) => {
            fatal(format!("is {kind}, not a tools file"))
        }
        toolconf_files::input::InputError::Io(e) => {
            fatal(format!("cannot open the tools file: {e}"))
        }
        e => fatal(e.to_string()),
    })?;
    let is_json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    read_tools_from(BufReader::new(file), &file_name, is_json, each)
}

/// [`read_tools`] of a tools file's bytes from `reader`, named `file_name` in errors: JSON if
/// `is_json`, else CSV.
pub fn read_tools_from<R: Read>(
    reader: R,
    file_name: &str,
    is_json: bool,
    mut each: impl FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError>,
) -> Result<usize, ToolFileError> {
    let rows = if is_json {
        // serde_json reads a byte at a time: the buffer goes between it and the limit.
        let bounded = BufReader::new(RecordLimit::new(reader, JsonElements::default()));
        read_json(bounded, file_name, &mut each)?
    } else {
        read_csv(reader, file_name, &mut each)?
    };
    if rows == 0 {
        return Err(ToolFileError {
            file: file_name.into(),
            place: String::new(),
            message: "no tools: the file has no rows".into(),
            row_level: false,
        });
    }
    Ok(rows)
}

fn read_csv<R: Read>(
    reader: R,
    file_name: &str,
    each: &mut impl FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError>,
) -> Result<usize, ToolFileError> {
    let error = |place: String, message: String, row_level| ToolFileError {
        file: file_name.into(),
        place,
        message,
        row_level,
    };
    let bounded = RecordLimit::new(reader, CsvRows::default());
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bounded);
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| {
            let (line, message) = csv_error(&e);
            error(format!("line {}", line.unwrap_or(1)), message, false)
        })?
        .iter()
        .map(str::to_string)
        .collect();
    if header.iter().all(String::is_empty) {
        return Err(error(
            String::new(),
            "no tools: the file is empty".into(),
            false,
        ));
    }
    check_keys(header.iter().map(String::as_str), "column")
        .map_err(|m| error("line 1 (header)".into(), m, false))?;
    let present = present_keys(|k| header.iter().any(|h| h == k));
    let mut record = csv::StringRecord::new();
    let mut rows = 0;
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {
                rows += 1;
                let line = record.position().map_or(0, |p| p.line());
                let cell = |key: &str| match header.iter().position(|h| h == key) {
                    None => Cell::Absent,
                    Some(i) => match record.get(i) {
                        None | Some("") => Cell::Absent,
                        Some(text) => Cell::Text(text),
                    },
                };
                let row = build_row(rows, &cell, &present)
                    .map_err(|m| error(format!("line {line}"), m, true));
                each(row)?;
            }
            Err(e) => {
                rows += 1;
                let (line, message) = csv_error(&e);
                let row_level = matches!(e.kind(), csv::ErrorKind::UnequalLengths { .. });
                let e = error(format!("line {}", line.unwrap_or(0)), message, row_level);
                if !row_level {
                    return Err(e);
                }
                each(Err(e))?;
            }
        }
    }
    Ok(rows)
}

/// A CSV error's line and message: a row too long or a quote never closed as the bounded
/// reader says ([`crate::inputs::bounded_read`]), a row of the wrong length in cells, else the `csv`
/// crate's words.
fn csv_error(e: &csv::Error) -> (Option<u64>, String) {
    match e.kind() {
        csv::ErrorKind::Io(io) => match record_error(io) {
            Some((line, message)) => (Some(line), message),
            None => (None, format!("cannot read the tools file: {io}")),
        },
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => (
            e.position().map(|p| p.line()),
            format!("the row has {len} cells, the header {expected_len}"),
        ),
        _ => (
            e.position().map(|p| p.line()),
            ClipMessage(&e.to_string()).to_string(),
        ),
    }
}

/// Keys a row may have: `name`, `model`, and every model's parameter names.
fn known_key(key: &str) -> bool {
    key == "name"
        || key == "model"
        || ModelKind::all()
            .iter()
            .any(|m| m.parameter_names().contains(&key))
}

fn known_keys() -> String {
    let mut keys = vec!["name", "model"];
    for m in ModelKind::all() {
        for p in m.parameter_names() {
            if !keys.contains(p) {
                keys.push(p);
            }
        }
    }
    keys.join(", ")
}

/// Every model's parameter keys, each once, in [`ModelKind::all`] order; built again when a
/// model has been loaded since (at most [`crate::registry::MAX_LOADED`] times: each list is kept
/// for the life of the process, as the models are).
fn parameter_keys() -> &'static [&'static str] {
    static KEYS: std::sync::Mutex<(usize, &'static [&'static str])> =
        std::sync::Mutex::new((0, &[]));
    let models = ModelKind::all();
    let mut cached = KEYS.lock().unwrap_or_else(|p| p.into_inner());
    if cached.0 != models.len() {
        let mut keys = Vec::new();
        for m in &models {
            for &p in m.parameter_names() {
                if !keys.contains(&p) {
                    keys.push(p);
                }
            }
        }
        *cached = (models.len(), keys.leak());
    }
    cached.1
}

/// The parameter keys among `has`, in [`parameter_keys`] order.
fn present_keys(has: impl Fn(&str) -> bool) -> Vec<&'static str> {
    parameter_keys()
        .iter()
        .copied()
        .filter(|k| has(k))
        .collect()
}

/// Every key known and none twice; `noun` is "column" (CSV) or "key" (JSON).
fn check_keys<'a>(keys: impl Iterator<Item = &'a str>, noun: &str) -> Result<(), String> {
    let mut seen = Vec::new();
    for key in keys {
        if !known_key(key) {
            return Err(format!(
                "unknown {noun} '{}' (known: {})",
                Clip(key),
                known_keys()
            ));
        }
        if seen.contains(&key) {
            return Err(format!("{noun} '{key}' appears twice"));
        }
        seen.push(key);
    }
    Ok(())
}

/// One row's tool from its cells: the model, then each of its parameters, each in its domain
/// (in [1e-6, 1e6] for a "> 0" parameter, [`crate::validate::tool_parameter`]; a URDF tool's
/// centre of mass may be 0 or negative) and the tool valid by its model's rule; a parameter of another model must be empty.
///
/// `present`: the parameter keys the row may give at all (its file's columns, its object's
/// keys), in [`parameter_keys`] order, so that a file of one model does not look up every other
/// model's keys on every row.
fn build_row<'a>(
    row: usize,
    cell: &dyn Fn(&str) -> Cell<'a>,
    present: &[&'static str],
) -> Result<ToolRow, String> {
    let name = match cell("name") {
        Cell::Absent => None,
        Cell::Text(t) => Some(t.to_string()),
        Cell::Number(x) => Some(x.to_string()),
        Cell::Other(v) => return Err(format!("name = {} is not text", Clip(&v))),
    };
    // Built only for an error: most rows have none.
    let who = || {
        name.as_ref()
            .map_or(String::new(), |n| format!(" (tool '{}')", Clip(n)))
    };
    let model = match cell("model") {
        Cell::Absent => ModelKind::PAPER_ARM,
        Cell::Text(t) => t.parse().map_err(|e: String| format!("{e}{}", who()))?,
        Cell::Number(x) => {
            let x = Short(x);
            return Err(format!("model = {x} is not a model name{}", who()));
        }
        Cell::Other(v) => {
            let v = Clip(&v);
            return Err(format!("model = {v} is not a model name{}", who()));
        }
    };
    let names = model.parameter_names();
    let domains = model.parameter_domains();
    let defaults = model.parameter_defaults();
    let mut params = Vec::with_capacity(names.len());
    let mut defaulted = Vec::new();
    for ((&key, domain), default) in names.iter().zip(domains).zip(defaults) {
        let value = match (cell(key), default) {
            // A column the model gives a default for (a URDF tool's products of inertia and
            // tip, zero): files written before it was a parameter keep working.
            (Cell::Absent, Some(d)) => {
                defaulted.push(key);
                *d
            }
            (Cell::Absent, None) => {
                return Err(format!(
                    "{key} is missing (model {model} needs it){}",
                    who()
                ))
            }
            (Cell::Number(x), _) => x,
            (Cell::Text(t), _) => t
                .parse::<f64>()
                .map_err(|_| format!("{key} = '{}' is not a number{}", Clip(t), who()))?,
            (Cell::Other(v), _) => {
                return Err(format!("{key} = {} is not a number{}", Clip(&v), who()))
            }
        };
        if let Err(why) = crate::validate::tool_parameter(domain, value) {
            return Err(format!("{key} = {why}{}", who()));
        }
        params.push(value);
    }
    for &key in present {
        if !names.contains(&key) && !matches!(cell(key), Cell::Absent) {
            return Err(format!(
                "{key} is given, but model {model} has no parameter {key} (it takes {}){}",
                names.join(", "),
                who()
            ));
        }
    }
    let tool = AnyTool::new(model, &params).map_err(|e| format!("{e}{}", who()))?;
    Ok(ToolRow {
        row,
        name,
        tool,
        defaulted,
    })
}

/// Visits the top-level array one element at a time.
struct Elements<'f, F> {
    file: &'f str,
    each: &'f mut F,
    rows: usize,
    stopped: Option<ToolFileError>,
}

impl<'de, F> Visitor<'de> for &mut Elements<'_, F>
where
    F: FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError>,
{
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("an array of tools (objects)")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while let Some(Object { map, twice }) = seq.next_element::<Object>()? {
            self.rows += 1;
            let row = self.rows;
            let keys = map.keys().map(String::as_str).chain(twice.as_deref());
            let result = check_keys(keys, "key")
                .and_then(|()| {
                    let present = present_keys(|k| map.contains_key(k));
                    build_row(row, &|key| json_cell(&map, key), &present)
                })
                .map_err(|message| ToolFileError {
                    file: self.file.into(),
                    place: format!("tool {row}"),
                    message,
                    row_level: true,
                });
            if let Err(e) = (self.each)(result) {
                self.stopped = Some(e);
                return Err(A::Error::custom("stopped"));
            }
        }
        Ok(())
    }
}

/// One tool's object, and the first key it gives twice if any (a `Map` alone would keep the
/// last value silently, where the CSV reader refuses a column given twice).
struct Object {
    map: Map<String, Value>,
    twice: Option<String>,
}

impl<'de> Deserialize<'de> for Object {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Entries;
        impl<'de> Visitor<'de> for Entries {
            type Value = Object;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a tool (an object)")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut entries: A) -> Result<Object, A::Error> {
                let mut object = Object {
                    map: Map::new(),
                    twice: None,
                };
                while let Some((key, value)) = entries.next_entry::<String, Value>()? {
                    if object.map.contains_key(&key) {
                        object.twice.get_or_insert(key);
                    } else {
                        object.map.insert(key, value);
                    }
                }
                Ok(object)
            }
        }
        d.deserialize_map(Entries)
    }
}

fn json_cell<'a>(object: &'a Map<String, Value>, key: &str) -> Cell<'a> {
    match object.get(key) {
        None | Some(Value::Null) => Cell::Absent,
        Some(Value::String(s)) if s.is_empty() => Cell::Absent,
        Some(Value::String(s)) => Cell::Text(s),
        Some(Value::Number(n)) => n.as_f64().map_or(Cell::Other(n.to_string()), Cell::Number),
        Some(other) => Cell::Other(other.to_string()),
    }
}

fn read_json<R: std::io::Read>(
    reader: R,
    file_name: &str,
    each: &mut impl FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError>,
) -> Result<usize, ToolFileError> {
    let mut elements = Elements {
        file: file_name,
        each,
        rows: 0,
        stopped: None,
    };
    let mut de = serde_json::Deserializer::from_reader(reader);
    let parsed =
        serde::Deserializer::deserialize_seq(&mut de, &mut elements).and_then(|()| de.end());
    if let Some(e) = elements.stopped {
        return Err(e);
    }
    parsed.map_err(|e| {
        let (line, message) = if e.is_io() {
            let io = std::io::Error::from(e);
            match record_error(&io) {
                Some((line, message)) => (line as usize, message),
                None => (0, format!("cannot read the tools file: {io}")),
            }
        } else {
            let message = format!("not a JSON array of tools: {}", ClipMessage(&e.to_string()));
            (e.line(), message)
        };
        ToolFileError {
            file: file_name.into(),
            place: format!("line {line}"),
            message,
            row_level: false,
        }
    })?;
    Ok(elements.rows)
}

// Tools held in memory (the Python package's DataFrames, dicts and structured arrays): the
// same row checks over columns instead of a file's lines.
mod columns;
pub use columns::{read_columns, Column, MemoryCell};
