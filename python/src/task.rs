//! A task from Python: a built-in name, a task file's path, or a dict with a task file's keys,
//! with episode options (keyword arguments) over its `[episode]`. Everything goes through the
//! crate's task-file parser ([`TaskSpec`]), so a dict is checked exactly as a file is and its
//! errors name the key.

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use toolconf_messages::{Clip, ClipPath};
use toolconf_model::inputs::bounded_read::read_text_file;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::TaskKind;

use crate::errors::Failure;

/// How a dict names itself in errors: `task dict, key precision.theta: …`.
const DICT_SOURCE: &str = "task dict";
/// How episode keyword arguments over a built-in task name themselves in errors.
const OPTIONS_SOURCE: &str = "episode options";

/// The task `task` with `episode` (keyword arguments, may be empty) over its `[episode]`.
pub fn task_spec(
    task: &Bound<'_, PyAny>,
    episode: Option<&Bound<'_, PyDict>>,
) -> PyResult<TaskSpec> {
    let py = task.py();
    let episode = match episode {
        Some(kwargs) if !kwargs.is_empty() => {
            Some(table(kwargs, "episode", DICT_SOURCE).map_err(|f| f.into_pyerr(py))?)
        }
        _ => None,
    };
    let spec = if let Ok(dict) = task.cast::<PyDict>() {
        let mut t = table(dict, "", DICT_SOURCE).map_err(|f| f.into_pyerr(py))?;
        if let Some(e) = episode {
            merge_episode(&mut t, e);
        }
        TaskSpec::from_table(t, DICT_SOURCE).map_err(Failure::input)
    } else if let Ok(name) = task.extract::<PathBuf>() {
        named(&name, episode)
    } else {
        Err(Failure::Input(format!(
            "task = {}: expected a built-in task name ({}), a task file's path, or a dict with a \
             task file's keys",
            repr(task),
            toolconf_model::task::task_choices()
        )))
    };
    spec.map_err(|f| f.into_pyerr(py))
}

/// The first item of a task file sent as text (`toolconf.dask` to its workers):
/// `(TASK_TEXT, file name, text)`.
pub const TASK_TEXT: &str = "toolconf task file";

/// A task as [`task_spec`] takes it, or a task file sent as text (`(TASK_TEXT, file name,
/// text)`, what `toolconf._portable_task` makes of a path), read as that file would be: its
/// errors name the file, and `episode` goes over its `[episode]` table.
pub fn portable_spec(
    task: &Bound<'_, PyAny>,
    episode: Option<&Bound<'_, PyDict>>,
) -> PyResult<TaskSpec> {
    let py = task.py();
    let Ok((marker, file, text)) = task.extract::<(String, String, String)>() else {
        return task_spec(task, episode);
    };
    if marker != TASK_TEXT {
        return task_spec(task, episode);
    }
    let spec = TaskSpec::parse(&text, &file).map_err(|e| Failure::input(e).into_pyerr(py))?;
    let episode = match episode {
        Some(kwargs) if !kwargs.is_empty() => {
            table(kwargs, "episode", DICT_SOURCE).map_err(|f| f.into_pyerr(py))?
        }
        _ => return Ok(spec),
    };
    // The text parsed, so it is a table; read it again as one to put the options over it.
    let mut t: toml::Table = toml::from_str(&text).map_err(|e| Failure::input(e).into_pyerr(py))?;
    merge_episode(&mut t, episode);
    TaskSpec::from_table(t, &file).map_err(|e| Failure::input(e).into_pyerr(py))
}

/// A built-in task's name, else a task file (as `toolconf rank --task` reads its argument).
fn named(name: &Path, episode: Option<toml::Table>) -> Result<TaskSpec, Failure> {
    if let Some(kind) = name.to_str().and_then(|s| s.parse::<TaskKind>().ok()) {
        let mut spec = TaskSpec::builtin(kind);
        if let Some(e) = episode {
            let mut t = toml::Table::new();
            t.insert("kind".into(), kind.name().into());
            merge_episode(&mut t, e);
            spec.episode = TaskSpec::from_table(t, OPTIONS_SOURCE)
                .map_err(Failure::input)?
                .episode;
        }
        return Ok(spec);
    }
    if std::fs::metadata(name).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound) {
        return Err(Failure::Input(format!(
            "task '{}': neither a built-in task ({}) nor an existing task file",
            ClipPath(&name.to_string_lossy()),
            toolconf_model::task::task_choices()
        )));
    }
    let spec = TaskSpec::from_file(name).map_err(Failure::input)?;
    let Some(e) = episode else {
        return Ok(spec);
    };
    // The file parsed, so it is a table; read it again as one to put the options over it.
    let text = read_text_file(name, "task file")
        .map_err(|m| Failure::Input(format!("{}: {m}", spec.file)))?;
    let mut t: toml::Table = toml::from_str(&text).map_err(Failure::input)?;
    merge_episode(&mut t, e);
    TaskSpec::from_table(t, &spec.file).map_err(Failure::input)
}

/// Puts `episode`'s keys over `task`'s `[episode]` table (a non-table `episode` is left for
/// the parser to refuse).
fn merge_episode(task: &mut toml::Table, episode: toml::Table) {
    let slot = task
        .entry("episode")
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if let toml::Value::Table(t) = slot {
        t.extend(episode);
    }
}

/// A dict as a TOML table; `None` values are left out (the default). `at` is the dotted key of
/// the dict itself and `source` names the dict (`task dict`, `design dict`), for errors.
pub fn table(dict: &Bound<'_, PyDict>, at: &str, source: &str) -> Result<toml::Table, Failure> {
    let mut out = toml::Table::new();
    for (key, value) in dict.iter() {
        let Ok(key) = key.extract::<String>() else {
            return Err(Failure::Input(format!(
                "{source}, key {}: {} is not a string key",
                if at.is_empty() {
                    "(top level)".into()
                } else {
                    Clip(at).to_string()
                },
                repr(&key)
            )));
        };
        if value.is_none() {
            continue;
        }
        let path = if at.is_empty() {
            key.clone()
        } else {
            format!("{at}.{key}")
        };
        out.insert(key, to_toml(&value, &path, source)?);
    }
    Ok(out)
}

/// A Python value as TOML: bool, int, float (NumPy scalars included), str, list, tuple, NumPy
/// array (by `tolist()`) or dict.
fn to_toml(value: &Bound<'_, PyAny>, path: &str, source: &str) -> Result<toml::Value, Failure> {
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.is_truthy().unwrap_or(false)));
    }
    if value.is_instance_of::<PyInt>() {
        if let Ok(i) = value.extract::<i64>() {
            return Ok(toml::Value::Integer(i));
        }
        // Past i64 (TOML's integers): as a float, which the range checks then judge.
        if let Ok(x) = value.extract::<f64>() {
            return Ok(toml::Value::Float(x));
        }
    }
    if value.is_instance_of::<PyFloat>() {
        if let Ok(x) = value.extract::<f64>() {
            return Ok(toml::Value::Float(x));
        }
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_string()));
    }
    if let Ok(d) = value.cast::<PyDict>() {
        return table(d, path, source).map(toml::Value::Table);
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Result<Vec<_>, _> = value
            .try_iter()
            .map_err(|_| unsupported(value, path, source))?
            .map(|item| {
                item.map_err(|_| unsupported(value, path, source))
                    .and_then(|item| to_toml(&item, path, source))
            })
            .collect();
        return items.map(toml::Value::Array);
    }
    // NumPy arrays and scalars: their Python equivalents.
    if let Ok(plain) = value.call_method0("tolist") {
        if !plain.is(value) {
            return to_toml(&plain, path, source);
        }
    }
    Err(unsupported(value, path, source))
}

fn unsupported(value: &Bound<'_, PyAny>, path: &str, source: &str) -> Failure {
    Failure::Input(format!(
        "{source}, key {}: {} is not a number, string, list or dict",
        Clip(path),
        repr(value)
    ))
}

/// `repr(value)` as a message repeats it ([`Clip`]: one line, not long).
fn repr(value: &Bound<'_, PyAny>) -> String {
    let text = value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "<unprintable>".into());
    Clip(&text).to_string()
}

/// `method="fast"` (the command line's `--method`, and its default), `"explicit"` (MATLAB
/// ode45 exactly, the paper's numerics), `"auto"` or `"stiff"`: [`Method::name`]s.
///
/// [`Method::name`]: toolconf_integrators::Method::name
pub fn method(name: &str) -> Result<toolconf_integrators::Method, Failure> {
    name.parse()
        .map_err(|e: String| Failure::Input(format!("method = {e}")))
}
