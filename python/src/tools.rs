//! The tools `toolconf.rank` takes: a tools file's path, or columns in memory (a mapping of
//! column name to a 1-D sequence, which the package makes of a pandas DataFrame, a dict of
//! arrays or lists, or a NumPy structured array), read through the runtime's row checks
//! ([`read_columns`]) so that a bad row gets the file's message with `row N` for `line N`.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyMapping, PyString};
use toolconf::rank::ScreenError;
use toolconf::rank::{
    check_screened, screen_file_with_validation, screen_rows, EachRow, ModelTasks, Screen, ScreenBy,
};
use toolconf_model::inputs::tools_file::{read_columns, Column, MemoryCell, ToolFileError};

use crate::errors::Failure;

/// How a dict of columns names itself in errors (`tools dict, row 3: …`).
pub const DICT_SOURCE: &str = "tools dict";

/// Tools to rank: a file, or columns named `source` in errors.
pub enum Tools {
    File(PathBuf),
    Columns {
        source: String,
        columns: Vec<(String, Column)>,
    },
}

/// What one call of the cheap stage gives: the screen, and the bad rows skipped (as warnings).
pub struct Screened {
    pub screen: Screen,
    pub skipped: Vec<String>,
}

impl Tools {
    /// `tools` as a path or as a mapping of columns; `source` names the columns in errors.
    /// A list of `(name, column)` pairs is columns too: what `toolconf.rank` makes of a
    /// DataFrame, whose column names may repeat (and are then refused, as a file's header is).
    pub fn from_py(tools: &Bound<'_, PyAny>, source: Option<&str>) -> Result<Self, Failure> {
        let source = source.unwrap_or(DICT_SOURCE).to_string();
        let failed = |e: PyErr| Failure::Input(format!("{source}: {e}"));
        let items = if let Ok(mapping) = tools.cast::<PyMapping>() {
            Some(mapping.items().map_err(failed)?.into_any())
        } else if tools.is_instance_of::<PyList>() {
            Some(tools.clone())
        } else {
            None
        };
        if let Some(items) = items {
            let columns = columns(&items, &source)?;
            return Ok(Tools::Columns { source, columns });
        }
        if let Ok(path) = tools.extract::<PathBuf>() {
            return Ok(Tools::File(path));
        }
        Err(Failure::Input(format!(
            "tools = {}: expected a tools file's path, a pandas DataFrame, a dict of 1-D arrays \
             or lists, or a NumPy structured array",
            short_repr(tools)
        )))
    }

    /// The number of rows (of a table; a file's are known only once it is read).
    pub fn rows(&self) -> Option<usize> {
        match self {
            Tools::File(_) => None,
            Tools::Columns { columns, .. } => Some(columns.first().map_or(0, |(_, c)| c.len())),
        }
    }

    /// The cheap stage over these tools (the library's [`screen_rows`]), keeping `limit` tools
    /// by `by`, the rows numbered from `first_row`; with `whole`, also the checks of a whole
    /// input ([`check_screened`]).
    pub fn screen(
        &self,
        tasks: &ModelTasks,
        (limit, by): (Option<usize>, ScreenBy),
        skip_bad_rows: bool,
        first_row: usize,
        whole: bool,
    ) -> Result<Screened, Failure> {
        let task = tasks.kind.to_string();
        let mut skipped = Vec::new();
        let skipping = |bad: &ToolFileError| skipped.push(format!("toolconf: skipping {bad}"));
        let screened = match self {
            // No validation sample: the package ranks, it does not check claim (a).
            Tools::File(path) => screen_file_with_validation(
                path,
                tasks,
                &task,
                (limit, 0, by),
                skip_bad_rows,
                skipping,
            ),
            Tools::Columns { source, columns } => {
                let read = |each: &mut EachRow| read_columns(source, columns, first_row, each);
                screen_rows(source, read, tasks, (limit, by), skip_bad_rows, skipping).and_then(
                    |(screen, n)| {
                        if whole {
                            check_screened(&screen, n, source, &task)?;
                        }
                        Ok((screen, n))
                    },
                )
            }
        };
        let (screen, _) = screened.map_err(|e| match e {
            ScreenError::File(e) => Failure::input(e),
            ScreenError::Input(message) => Failure::Input(message),
        })?;
        Ok(Screened { screen, skipped })
    }
}

/// The columns of `items` (`(name, values)` pairs), in order.
fn columns(items: &Bound<'_, PyAny>, source: &str) -> Result<Vec<(String, Column)>, Failure> {
    let py = items.py();
    let failed = |e: PyErr| Failure::python(source, e);
    let numpy = py.import("numpy").map_err(failed)?;
    let mut out = Vec::new();
    for item in items.try_iter().map_err(failed)? {
        let item = item.map_err(failed)?;
        let (key, value): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract().map_err(|_| {
            Failure::Input(format!(
                "{source}: {} is not a (column name, values) pair",
                short_repr(&item)
            ))
        })?;
        let Ok(name) = key.extract::<String>() else {
            return Err(Failure::Input(format!(
                "{source}: column name {} is not text",
                short_repr(&key)
            )));
        };
        let context = format!("{source}, column '{}'", toolconf_messages::Clip(&name));
        let bad = |e: PyErr| Failure::python(&format!("{context}: not an array"), e);
        // An array stays as it is; a list is taken as objects, cell by cell (NumPy would turn
        // ['a', nan] into the text 'nan').
        let array = if value.hasattr("__array__").unwrap_or(false) {
            numpy.call_method1("asarray", (&value,))
        } else {
            let kwargs = pyo3::types::PyDict::new(py);
            kwargs.set_item("dtype", "object").map_err(failed)?;
            numpy.call_method("asarray", (&value,), Some(&kwargs))
        }
        .map_err(bad)?;
        let shape: Vec<usize> = array
            .getattr("shape")
            .and_then(|s| s.extract())
            .map_err(failed)?;
        if shape.len() != 1 {
            return Err(Failure::Input(format!(
                "{context}: has shape {shape:?}; a column is 1-D, one value per tool"
            )));
        }
        let kind: String = array
            .getattr("dtype")
            .and_then(|d| d.getattr("kind"))
            .and_then(|k| k.extract())
            .map_err(failed)?;
        // A whole array of booleans or complex numbers is refused as every array argument of
        // the package is; a list's odd cell is its row's error (as a file's cell is).
        if matches!(kind.as_str(), "b" | "c") {
            let dtype = array
                .getattr("dtype")
                .and_then(|d| d.str())
                .map_err(failed)?;
            return Err(Failure::Type(format!(
                "{context}: an array of {} (dtype {dtype}); a column holds numbers or text",
                if kind == "b" {
                    "booleans"
                } else {
                    "complex numbers"
                }
            )));
        }
        let column = if matches!(kind.as_str(), "f" | "i" | "u") {
            let (_, values) = crate::arrays::values(&array, "float64").map_err(failed)?;
            Column::Numbers(values)
        } else {
            let items = array.call_method0("tolist").map_err(failed)?;
            let cells: Result<Vec<MemoryCell>, Failure> = items
                .try_iter()
                .map_err(failed)?
                .map(|item| item.map(|i| cell(&i)).map_err(failed))
                .collect();
            Column::Cells(cells?)
        };
        out.push((name, column));
    }
    Ok(out)
}

/// One object's cell: None and NaN are empty, numbers and text are themselves, anything else
/// (a bool, a list, a date) is shown as Python shows it, for the row's error.
fn cell(value: &Bound<'_, PyAny>) -> MemoryCell {
    if value.is_none() {
        return MemoryCell::Empty;
    }
    if !value.is_instance_of::<PyBool>()
        && (value.is_instance_of::<PyInt>() || value.is_instance_of::<PyFloat>())
    {
        if let Ok(x) = value.extract::<f64>() {
            return MemoryCell::Number(x);
        }
    }
    if let Ok(s) = value.cast::<PyString>() {
        return MemoryCell::Text(s.to_string());
    }
    MemoryCell::Other(short_repr(value))
}

/// `repr(value)`, at most 60 characters (a whole list or frame is not a useful message).
pub fn short_repr(value: &Bound<'_, PyAny>) -> String {
    let text = value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "<unprintable>".into());
    if text.chars().count() <= 60 {
        return text;
    }
    let head: String = text.chars().take(57).collect();
    format!("{head}...")
}
