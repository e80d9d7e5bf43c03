//! Renders a toolconf derivation IR (the JSON that `derive/derive.py` writes) through the Tera
//! templates in `templates/` into the generated crate (`generated/`, the package
//! toolconf-generated; or a crate of a user's own with `make crate`).
//!
//! The IR is read into types ([`ir`]: an unknown key, a missing one or a value of the wrong kind
//! stops the render, naming the file, line and column), and each field checked for its kind
//! ([`ir_check`]: text of one line, names, file names, code in [`code`]'s grammar): an IR is data,
//! whoever wrote it. Text reaches the templates only escaped for where it goes ([`escape`]). Every decision about the Rust and the
//! reports written (names, signatures, bodies, counts, wording) is made here, in the views the
//! templates see ([`model_view`], [`functions`], [`tasks`], [`tool_rule`], [`registry`]); the
//! templates only loop over them.
//!
//! A template named `<kind>.<ext>.tera` renders to `<model>.<ext>`, once per model, which
//! [`crate_path`] places in the crate (Rust sources under `src/`); a template under
//! `templates/registry/`, at `<path>.tera`, renders once over all models to `<path>` in the crate:
//! that folder is laid out as the crate (`Cargo.toml`, `src/lib.rs` with the model registry,
//! `src/tasks.rs`, `tests/vectors.rs`, ...). The templates under `templates/cabi/` render once
//! for one model into the crate of a model library around it (`make model`: [`cabi`]). Rust output goes through rustfmt so that the
//! checked-in code is exactly what `make derive` produces; [`check_crate`] compares a crate
//! folder with what its IR renders to (`make render` writes it).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use tera::{Context, Tera};

pub mod cabi;
mod check;
pub mod code;
pub mod escape;
pub mod functions;
pub mod ir;
pub mod ir_check;
pub mod ir_schema;
pub mod model_view;
pub mod registry;
pub mod tasks;
mod templates;
pub mod tool_rule;

pub use check::{check_crate, crate_irs, render_crate, CrateFile};
pub use ir::{read_ir, Ir, IR_SCHEMA};
pub use registry::Package;
pub use templates::{load_template_tree, load_templates};

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Write(#[from] toolconf_files::WriteError),
    /// An IR that is not one this renderer renders (bad input): its file, key and why.
    #[error("{}: {}{problem}", path.display(), if key.is_empty() { String::new() } else { format!("{key}: ") })]
    Refused {
        path: PathBuf,
        key: String,
        problem: String,
    },
    #[error("{path} is not an IR this renderer reads: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("{path}: IR schema {} is not the one this renderer understands ({expected}); derive it again (make derive)", found.map_or_else(|| "none".to_string(), |s| s.to_string()))]
    Schema {
        path: PathBuf,
        found: Option<u64>,
        expected: u64,
    },
    #[error("template error: {0}")]
    Template(String),
    #[error("two templates render to the same file {0}")]
    Clash(String),
    #[error("task: {0}")]
    Task(String),
    #[error("rustfmt failed: {0}")]
    Rustfmt(String),
}

impl RenderError {
    /// Whether the error is the input's (an IR that cannot be rendered, status 2) rather than a
    /// failure to render or write one that can (status 1).
    pub fn is_refusal(&self) -> bool {
        matches!(
            self,
            RenderError::Refused { .. } | RenderError::Json { .. } | RenderError::Schema { .. }
        )
    }
}

/// One rendered file: its name (relative to the output folder) and contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rendered {
    pub file_name: String,
    pub contents: String,
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

/// A Tera engine over the templates, with no HTML escaping (the outputs are Rust and Markdown).
pub(crate) fn engine(templates: &[(String, String)]) -> Result<Tera, RenderError> {
    let mut tera = Tera::default();
    tera.autoescape_on(vec![]);
    tera.add_raw_templates(templates.iter().map(|(n, t)| (n.as_str(), t.as_str())))
        .map_err(|e| RenderError::Template(chain(&e)))?;
    Ok(tera)
}

/// Renders one template to `file_name`; a `.rs` file goes through rustfmt.
pub(crate) fn render_one(
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

fn context(view: &impl serde::Serialize) -> Result<Context, RenderError> {
    Context::from_serialize(view).map_err(|e| RenderError::Template(chain(&e)))
}

/// Renders the IR through each top-level template (or the variant its IR names); Rust outputs
/// are formatted with rustfmt.
pub fn render(ir: &Ir, templates: &[(String, String)]) -> Result<Vec<Rendered>, RenderError> {
    let tera = engine(templates)?;
    let context = context(&model_view::model_context(ir)?)?;
    let mut out: Vec<Rendered> = Vec::new();
    for (name, _) in templates.iter().filter(|(n, _)| !n.contains('/')) {
        let chosen = templates::variant(ir, name, templates);
        let ext = name
            .trim_end_matches(".tera")
            .rsplit('.')
            .next()
            .unwrap_or("txt");
        let file_name = format!("{}.{ext}", ir.model.name);
        if out.iter().any(|r| r.file_name == file_name) {
            return Err(RenderError::Clash(file_name));
        }
        out.push(render_one(&tera, chosen, &context, file_name)?);
    }
    Ok(out)
}

/// Renders the registry templates once over all models (in the order given), for `package`.
pub fn render_registry(
    irs: &[Ir],
    templates: &[(String, String)],
    package: &Package,
) -> Result<Vec<Rendered>, RenderError> {
    let tera = engine(templates)?;
    let context = context(&registry::registry_context(irs, package)?)?;
    templates
        .iter()
        .map(|(name, _)| {
            let file_name = name.trim_end_matches(".tera").to_string();
            render_one(&tera, name, &context, file_name)
        })
        .collect()
}

/// Formats Rust source with the toolchain's rustfmt (edition 2021, default style): `RUSTFMT`,
/// else `rustfmt` on the PATH.
pub fn rustfmt(source: &str) -> Result<String, RenderError> {
    let program = std::env::var("RUSTFMT").unwrap_or_else(|_| "rustfmt".into());
    rustfmt_with(&program, source)
}

/// [`rustfmt`] with the program `program`.
fn rustfmt_with(program: &str, source: &str) -> Result<String, RenderError> {
    let mut child = Command::new(program)
        .args(["--edition", "2021", "--emit", "stdout", "--quiet"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| {
            RenderError::Rustfmt(format!(
                "cannot start {program}: {e} (the renderer formats the Rust it writes with rustfmt: \
                 `rustup component add rustfmt`, or name it in RUSTFMT)"
            ))
        })?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_rustfmt_is_an_error_saying_how_to_get_it() {
        let e = rustfmt_with("/nonexistent/rustfmt", "fn f() {}")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cannot start /nonexistent/rustfmt")
                && e.contains("rustup component add rustfmt"),
            "{e}"
        );
    }
}
