//! Renders a toolconf derivation IR (the JSON that `derive/derive.py` writes) through the Tera
//! templates in `templates/` into the generated crate (`generated/`, the package
//! toolconf-generated; or a crate of a user's own with `make crate`).
//!
//! A template named `<kind>.<ext>.tera` renders to `<model>.<ext>`, once per model, which
//! [`crate_path`] places in the crate (Rust sources under `src/`); a template under
//! `templates/registry/`, at `<path>.tera`, renders once over all models to `<path>` in the crate:
//! that folder is laid out as the crate (`Cargo.toml`, `src/lib.rs` with the model registry,
//! `src/tasks.rs`, `tests/vectors.rs`, ...). Rust output goes through rustfmt so that the
//! checked-in code is exactly what `make derive` produces.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::{json, Value};
use tera::{Context, Tera};

mod tasks;

/// The IR schema this renderer understands (`schema` in the JSON).
pub const IR_SCHEMA: u64 = 4;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path} is not valid JSON: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("IR schema {found} is not the one this renderer understands ({expected})")]
    Schema { found: String, expected: u64 },
    #[error("IR has no model.name")]
    NoModelName,
    #[error("template error: {0}")]
    Template(String),
    #[error("two templates render to the same file {0}")]
    Clash(String),
    #[error("task: {0}")]
    Task(String),
    #[error("rustfmt failed: {0}")]
    Rustfmt(String),
}

/// One rendered file: its name (relative to the output folder) and contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rendered {
    pub file_name: String,
    pub contents: String,
}

/// Reads and checks an IR file.
pub fn read_ir(path: &Path) -> Result<Value, RenderError> {
    let text = std::fs::read_to_string(path).map_err(|source| RenderError::Io {
        path: path.into(),
        source,
    })?;
    let ir: Value = serde_json::from_str(&text).map_err(|source| RenderError::Json {
        path: path.into(),
        source,
    })?;
    match ir.get("schema").and_then(Value::as_u64) {
        Some(IR_SCHEMA) => Ok(ir),
        other => Err(RenderError::Schema {
            found: format!("{other:?}"),
            expected: IR_SCHEMA,
        }),
    }
}

/// Loads every `*.tera` file of a folder, in name order, then those of its sub-folders but
/// `registry/` as `<folder>/<file>` ([`load_variants`]): macros a template imports
/// (`include/`) and per-model variants of the top-level templates (`urdf/`).
pub fn load_templates(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    let mut all = load_folder(dir)?;
    all.extend(load_variants(dir)?);
    Ok(all)
}

/// Every `*.tera` file directly in `dir`, in name order.
fn load_folder(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    let io = |source| RenderError::Io {
        path: dir.into(),
        source,
    };
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "tera"))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).map_err(|source| RenderError::Io {
                path: p.clone(),
                source,
            })?;
            let name = p
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            Ok((name, text))
        })
        .collect()
}

/// Loads every `*.tera` file under `dir` and its sub-folders, in path order, each named by its
/// path relative to `dir` with `/` between folders (`src/lib.rs.tera`): the registry templates,
/// laid out as the crate they render to.
pub fn load_template_tree(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    let mut out = Vec::new();
    let mut pending = vec![PathBuf::new()];
    while let Some(relative) = pending.pop() {
        let folder = dir.join(&relative);
        let io = |source| RenderError::Io {
            path: folder.clone(),
            source,
        };
        for entry in std::fs::read_dir(&folder).map_err(io)? {
            let entry = entry.map_err(io)?;
            let name = relative.join(entry.file_name());
            if entry.file_type().map_err(io)?.is_dir() {
                pending.push(name);
            } else if name.extension().is_some_and(|x| x == "tera") {
                let path = dir.join(&name);
                let text = std::fs::read_to_string(&path)
                    .map_err(|source| RenderError::Io { path, source })?;
                let parts: Vec<String> = name
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push((parts.join("/"), text));
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Where a per-model file goes in the crate: Rust sources (`arm2.rs`) are modules under `src/`,
/// the rest (`arm2.md`, and the IR and vectors that derive.py writes) stays at the crate root.
pub fn crate_path(file_name: &str) -> PathBuf {
    if file_name.ends_with(".rs") {
        Path::new("src").join(file_name)
    } else {
        PathBuf::from(file_name)
    }
}

/// The crate the registry renders: its package name, and whether it is a crate of its own
/// (`make crate`: an empty `[workspace]` table, so that no enclosing workspace claims it) or a
/// member of toolconf's workspace (`generated/`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Package {
    pub name: String,
    pub standalone: bool,
}

impl Package {
    /// toolconf's own generated crate, `generated/`.
    pub fn in_repository() -> Self {
        Self {
            name: "toolconf-generated".into(),
            standalone: false,
        }
    }
}

/// A Tera engine over the templates, with no HTML escaping (the outputs are Rust and Markdown).
fn engine(templates: &[(String, String)]) -> Result<Tera, RenderError> {
    let mut tera = Tera::default();
    tera.autoescape_on(vec![]);
    tera.add_raw_templates(templates.iter().map(|(n, t)| (n.as_str(), t.as_str())))
        .map_err(|e| RenderError::Template(chain(&e)))?;
    Ok(tera)
}

/// Renders one template to `file_name`; a `.rs` file goes through rustfmt.
fn render_one(
    tera: &Tera,
    template: &str,
    context: &Context,
    file_name: String,
) -> Result<Rendered, RenderError> {
    let text = tera
        .render(template, context)
        .map_err(|e| RenderError::Template(chain(&e)))?;
    let contents = if file_name.ends_with(".rs") {
        rustfmt(&text)?
    } else {
        text
    };
    Ok(Rendered {
        file_name,
        contents,
    })
}

/// Renders the IR through each template; Rust outputs are formatted with rustfmt.
pub fn render(
    source: &Value,
    templates: &[(String, String)],
) -> Result<Vec<Rendered>, RenderError> {
    let model = source
        .pointer("/model/name")
        .and_then(Value::as_str)
        .ok_or(RenderError::NoModelName)?;
    let tera = engine(templates)?;
    let mut ir = source.clone();
    ir["tasks"] = Value::from(tasks::tasks_with_rust(&ir)?);
    ir["tool_rule_view"] = tool_rule_entry(&ir["model"])?;
    let context = Context::from_value(ir).map_err(|e| RenderError::Template(chain(&e)))?;
    let mut out: Vec<Rendered> = Vec::new();
    for (name, _) in templates.iter().filter(|(n, _)| !n.contains('/')) {
        let chosen = variant(source, name, templates);
        let ext = name
            .trim_end_matches(".tera")
            .rsplit('.')
            .next()
            .unwrap_or("txt");
        let file_name = format!("{model}.{ext}");
        if out.iter().any(|r| r.file_name == file_name) {
            return Err(RenderError::Clash(file_name));
        }
        out.push(render_one(&tera, chosen, &context, file_name)?);
    }
    Ok(out)
}

/// The template that renders `name` for this model: a variant `<folder>/<name>` (loaded by
/// [`load_variants`]) when the IR's `templates` list names one, else `name` itself. A URDF
/// model's report is not the closed forms' (templates/urdf/report.md.tera).
fn variant<'a>(ir: &Value, name: &'a str, templates: &'a [(String, String)]) -> &'a str {
    let wanted: Vec<&str> = ir
        .get("templates")
        .and_then(Value::as_array)
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    templates
        .iter()
        .map(|(n, _)| n.as_str())
        .find(|n| wanted.contains(n) && n.rsplit('/').next() == Some(name))
        .unwrap_or(name)
}

/// Every `*.tera` file in the sub-folders of `dir` other than `registry/`, named
/// `<folder>/<file>`.
fn load_variants(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    let io = |source| RenderError::Io {
        path: dir.into(),
        source,
    };
    let mut folders: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir() && p.file_name().is_some_and(|n| n != "registry"))
        .collect();
    folders.sort();
    let mut out = Vec::new();
    for folder in folders {
        let prefix = folder
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        for (name, text) in load_folder(&folder)? {
            out.push((format!("{prefix}/{name}"), text));
        }
    }
    Ok(out)
}

/// The registry's view of one model: what the runtime needs to name and size it. The Rust names
/// are decided here, not in the templates: the marker type is the model's name in CamelCase
/// (`arm2_exact` → `Arm2Exact`), its tool type that plus `Tool`, and the title a Rust literal.
fn registry_entry(ir: &Value) -> Result<Value, RenderError> {
    let model = ir.get("model").ok_or(RenderError::NoModelName)?;
    let name = model
        .get("name")
        .and_then(Value::as_str)
        .ok_or(RenderError::NoModelName)?;
    let marker = tasks::camel_case(name);
    let mut entry = model.clone();
    entry["marker"] = Value::from(marker.clone());
    entry["tool"] = Value::from(marker + "Tool");
    entry["description"] = ir["generator"]["model"].clone();
    // A Rust string literal (quotes escaped) for the macro's arguments.
    let title = model.get("title").and_then(Value::as_str).unwrap_or(name);
    entry["title_literal"] = Value::from(format!("{title:?}"));
    entry["functions"] = Value::from(
        ir.get("functions")
            .and_then(Value::as_array)
            .map(|fs| fs.iter().map(vector_test_entry).collect::<Vec<_>>())
            .unwrap_or_default(),
    );
    entry["tool_rule"] = tool_rule_entry(model)?;
    entry["rigid_body"] = rigid_body_entry(ir);
    Ok(entry)
}

/// The function that is a model's own rigid-body dynamics (U the joint torques): the URDF arms'
/// `rigid_body_dynamics` (their plant adds joint impedance), else the model's plant `dynamics`,
/// which for the other kinds is the equations of motion with U the torques (or force) itself.
fn rigid_body_entry(ir: &Value) -> Value {
    let has = |name: &str| {
        ir.get("functions")
            .and_then(Value::as_array)
            .is_some_and(|fs| {
                fs.iter()
                    .any(|f| f.get("name").and_then(Value::as_str) == Some(name))
            })
    };
    if has("rigid_body_dynamics") {
        json!({"function": "rigid_body_dynamics", "doc": "the rigid-body dynamics alone (the model's plant adds joint impedance)"})
    } else {
        json!({"function": "dynamics", "doc": "the model's plant, which is its rigid-body dynamics"})
    }
}

/// The planar arms' rule, for a model whose IR states none (`model.tool_rule`): every parameter
/// (a mass, a length, a stiffness) finite and > 0, random tools drawn from the paper's
/// [0.1, 0.6] ("Implementation details"), no constraint across parameters.
fn default_tool_rule(count: usize) -> Value {
    let positive = json!({"lo": 0.0, "hi": null, "lo_open": true, "hi_open": true});
    json!({
        "domains": vec![positive; count],
        "constraints": [],
        "sample": vec![json!([0.1, 0.6]); count],
    })
}

/// The registry's view of a model's tool rule (templates/registry/src/validity.rs.tera): each
/// domain's bounds as Rust literals and its rule in words, the constraints' coefficients and
/// text, the sampling box; the IR's `model.tool_rule`, or [`default_tool_rule`].
fn tool_rule_entry(model: &Value) -> Result<Value, RenderError> {
    let parameters = model
        .get("parameters")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let rule = model
        .get("tool_rule")
        .cloned()
        .unwrap_or_else(|| default_tool_rule(parameters.len()));
    let bad = |what: &str| RenderError::Template(format!("model.tool_rule: {what}"));
    let list = |key: &str| -> Result<Vec<Value>, RenderError> {
        rule.get(key)
            .and_then(Value::as_array)
            .cloned()
            .ok_or_else(|| bad(&format!("no {key}")))
    };
    let (domains, sample) = (list("domains")?, list("sample")?);
    if domains.len() != parameters.len() || sample.len() != parameters.len() {
        return Err(bad("one domain and one sampling box per parameter"));
    }
    let mut rendered_domains = Vec::new();
    for (d, p) in domains.iter().zip(&parameters) {
        let unit = p.get("unit").and_then(Value::as_str).unwrap_or("");
        rendered_domains.push(
            domain_entry(d, unit).ok_or_else(|| bad("a domain needs lo, hi, lo_open, hi_open"))?,
        );
    }
    let mut constraints = Vec::new();
    for c in list("constraints")? {
        let coefficients: Vec<String> = c
            .get("coefficients")
            .and_then(Value::as_array)
            .filter(|a| a.len() == parameters.len())
            .ok_or_else(|| bad("a constraint needs one coefficient per parameter"))?
            .iter()
            .map(|x| {
                x.as_f64()
                    .map(rust_f64)
                    .ok_or_else(|| bad("a coefficient is not a number"))
            })
            .collect::<Result<_, _>>()?;
        let text = c.get("text").and_then(Value::as_str).unwrap_or("");
        constraints
            .push(json!({"coefficients": coefficients, "rule": format!("{text:?}"), "text": text}));
    }
    let mut boxes = Vec::new();
    for (b, d) in sample.iter().zip(&mut rendered_domains) {
        match b
            .as_array()
            .map(|a| a.iter().map(Value::as_f64).collect::<Vec<_>>())
            .as_deref()
        {
            Some([Some(lo), Some(hi)]) => {
                boxes.push(json!({"lo": rust_f64(*lo), "hi": rust_f64(*hi)}));
                d["sample"] = Value::from(format!("[{lo}, {hi}]"));
            }
            _ => return Err(bad("a sampling box is not [lo, hi]")),
        }
    }
    for (d, p) in rendered_domains.iter_mut().zip(&parameters) {
        d["name"] = p.get("name").cloned().unwrap_or(Value::Null);
    }
    Ok(json!({"domains": rendered_domains, "constraints": constraints, "sample": boxes}))
}

/// One domain: its bounds as Rust literals (a missing bound is infinite) and the rule in words,
/// e.g. "a finite number > 0", "a finite number in [-1, 1] m".
fn domain_entry(d: &Value, unit: &str) -> Option<Value> {
    let bound = |key: &str| -> Option<Option<f64>> {
        match d.get(key)? {
            Value::Null => Some(None),
            v => v.as_f64().map(Some),
        }
    };
    let (lo, hi) = (bound("lo")?, bound("hi")?);
    let (lo_open, hi_open) = (d.get("lo_open")?.as_bool()?, d.get("hi_open")?.as_bool()?);
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    let words = match (lo, hi) {
        (None, None) => "a finite number".to_string(),
        (Some(l), None) => format!(
            "a finite number {} {l}{unit}",
            if lo_open { ">" } else { ">=" }
        ),
        (None, Some(h)) => format!(
            "a finite number {} {h}{unit}",
            if hi_open { "<" } else { "<=" }
        ),
        (Some(l), Some(h)) => format!(
            "a finite number in {}{l}, {h}{}{unit}",
            if lo_open { "(" } else { "[" },
            if hi_open { ")" } else { "]" }
        ),
    };
    Some(json!({
        "lo": lo.map_or("f64::NEG_INFINITY".to_string(), rust_f64),
        "hi": hi.map_or("f64::INFINITY".to_string(), rust_f64),
        "lo_open": lo_open,
        "hi_open": hi_open,
        "rule": format!("{words:?}"),
        "words": words,
    }))
}

/// An f64 as a Rust literal that reads back as the same double (`{:?}` is the shortest
/// round-trip form and always has a `.` or an exponent).
fn rust_f64(x: f64) -> String {
    format!("{x:?}")
}

/// What the vector test needs of one generated function: its argument and output names, and
/// the pattern binding its outputs (a one-output function returns the matrix, not a 1-tuple).
fn vector_test_entry(function: &Value) -> Value {
    let names = |key: &str| -> Vec<String> {
        function
            .get(key)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.get("name").and_then(Value::as_str).map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    let outputs = names("outputs");
    let pattern = match outputs.as_slice() {
        [one] => one.clone(),
        many => format!("({})", many.join(", ")),
    };
    json!({
        "name": function.get("name").cloned().unwrap_or(Value::Null),
        "args": names("args"),
        "outputs": outputs,
        "pattern": pattern,
    })
}

/// The same `generator` entry of every IR (the command, the task definitions), or an error
/// naming the first model that differs.
fn shared_generator(irs: &[Value], key: &str) -> Result<String, RenderError> {
    let of = |ir: &Value| {
        ir.pointer(&format!("/generator/{key}"))
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string()
    };
    let first = irs.first().map(of).unwrap_or_default();
    match irs.iter().find(|ir| of(ir) != first) {
        Some(ir) => Err(RenderError::Template(format!(
            "model {} has generator.{key} {:?}, the first model {first:?}: the models of one crate come from one run",
            ir.pointer("/model/name").cloned().unwrap_or(Value::Null),
            of(ir)
        ))),
        None => Ok(first),
    }
}

/// "position, velocity or acceleration (or 1, 2, 3)": how messages list the tasks, as a Rust
/// string literal.
fn task_choices(tasks: &[Value]) -> String {
    let names: Vec<&str> = tasks
        .iter()
        .filter_map(|t| t.get("name").and_then(Value::as_str))
        .collect();
    let numbers: Vec<String> = tasks
        .iter()
        .filter_map(|t| t.get("index").and_then(Value::as_u64))
        .map(|n| n.to_string())
        .collect();
    let names = match names.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    format!("{:?}", format!("{names} (or {})", numbers.join(", ")))
}

/// Renders the registry templates once over all models (in the order given), for `package`.
pub fn render_registry(
    irs: &[Value],
    templates: &[(String, String)],
    package: &Package,
) -> Result<Vec<Rendered>, RenderError> {
    let models = irs
        .iter()
        .map(registry_entry)
        .collect::<Result<Vec<_>, _>>()?;
    let tera = engine(templates)?;
    let tasks = tasks::task_list(irs)?;
    let mut context = Context::new();
    context.insert("models", &models);
    context.insert("task_choices", &task_choices(&tasks));
    context.insert("tasks", &tasks);
    context.insert(
        "package",
        &json!({
            "name": package.name,
            "lib": package.name.replace('-', "_"),
            "standalone": package.standalone,
            "command": shared_generator(irs, "command")?,
            "tasks": shared_generator(irs, "tasks")?,
        }),
    );
    templates
        .iter()
        .map(|(name, _)| {
            let file_name = name.trim_end_matches(".tera").to_string();
            render_one(&tera, name, &context, file_name)
        })
        .collect()
}

/// Formats Rust source with the toolchain's rustfmt (edition 2021, default style).
pub fn rustfmt(source: &str) -> Result<String, RenderError> {
    let mut child = Command::new(std::env::var("RUSTFMT").unwrap_or_else(|_| "rustfmt".into()))
        .args(["--edition", "2021", "--emit", "stdout", "--quiet"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| RenderError::Rustfmt(format!("cannot start rustfmt: {e}")))?;
    child
        .stdin
        .take()
        .ok_or_else(|| RenderError::Rustfmt("no stdin".into()))?
        .write_all(source.as_bytes())
        .map_err(|e| RenderError::Rustfmt(e.to_string()))?;
    let output = child
        .wait_with_output()
        .map_err(|e| RenderError::Rustfmt(e.to_string()))?;
    if !output.status.success() {
        return Err(RenderError::Rustfmt(
            String::from_utf8_lossy(&output.stderr).into_owned(),
        ));
    }
    String::from_utf8(output.stdout).map_err(|e| RenderError::Rustfmt(e.to_string()))
}

fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}
