//! What the model library's templates (templates/cabi/, rendered once for one model by
//! `make model`) see: the model's C and Rust names and sizes, its parameters, the tasks and
//! terms with their indices and C macro names, the task fingerprint, and where the library's
//! crate finds toolconf's (`toolconf-cabi`, and the generated crate its `[patch]` replaces).
//!
//! Every decision is made here; the templates only loop. The C ABI itself (the exports, their
//! signatures and types) is toolconf-cabi's (crates/cabi); the header's declarations are
//! checked against it by crates/cabi/tests/header.rs, and the fingerprint computed here from the
//! IR against the one the library computes from its generated code by the library's own test.

use std::path::{Path, PathBuf};

use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::check::CrateFile;
use crate::escape::{c_comment, toml_string};
use crate::ir::{Ir, Source};
use crate::tasks::{camel_case, string_literal};
use crate::{engine, load_template_tree, render_one, RenderError};

/// The version of the C ABI the templates declare: toolconf-cabi's `ABI_VERSION` (the
/// library's test compares them).
pub const ABI_VERSION: u32 = 2;

/// The library's crate: its package name, and the repository whose crates it builds on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LibraryPackage {
    pub name: String,
    pub repository: PathBuf,
}

impl LibraryPackage {
    /// `toolconf-model-<model>`, on the repository `repository` (absolute).
    pub fn for_model(model: &str, repository: &Path) -> Self {
        Self {
            name: format!("toolconf-model-{}", model.replace('_', "-")),
            repository: repository.to_path_buf(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NameView {
    pub name: String,
    pub index: usize,
    /// The C macro's suffix: the name in upper case (`TIP_POSITION`).
    pub macro_name: String,
    /// A C (and Rust) string literal of the name.
    pub literal: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterView {
    pub name: String,
    pub unit: String,
    pub index: usize,
    pub macro_name: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LibraryModelView {
    pub name: String,
    /// toolconf-core's marker type (`Panda`).
    pub marker: String,
    pub title_literal: String,
    /// The title and the description's path, each one line of a comment, Rust's, TOML's or the
    /// header's C block comment ([`c_comment`]).
    pub title_comment: String,
    pub description: String,
    pub dof: usize,
    pub state_dim: usize,
    pub parameter_count: usize,
    pub tip_dim: usize,
    pub parameters: Vec<ParameterView>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LibraryPackageView {
    pub name: String,
    /// The crate's name as Rust code names it (`toolconf_model_panda`).
    pub lib: String,
    /// TOML string literals of toolconf-cabi's path, and of the `[patch]` source URL of the
    /// generated crate toolconf-core depends on.
    pub cabi_path: String,
    pub generated_source: String,
    pub command: String,
    pub ir: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LibraryContext {
    pub model: LibraryModelView,
    pub tasks: Vec<NameView>,
    pub terms: Vec<NameView>,
    pub task_count: usize,
    pub term_count: usize,
    pub abi_version: u32,
    /// SHA-256 (hex) of [`fingerprint_text`].
    pub fingerprint: String,
    /// Its lines, for the header's comment.
    pub fingerprint_lines: Vec<String>,
    pub package: LibraryPackageView,
}

/// The canonical text of the IR's task and term list: toolconf-cabi's `fingerprint::text`
/// (crates/cabi/src/fingerprint.rs), made from the IR instead of the generated code.
pub fn fingerprint_text(ir: &Ir) -> String {
    let mut out = String::from("toolconf-tasks 1\n");
    for t in &ir.terms {
        let source = match t.read.source {
            Source::State => "state",
            Source::StateRate => "state_rate",
            Source::Control => "control",
            Source::Tip => "tip",
        };
        let block = if t.read.source == Source::Control {
            0
        } else {
            t.read.block
        };
        out += &format!("term {} {source} {block}\n", t.name);
    }
    for task in &ir.tasks {
        out += &format!("task {}", task.name);
        for term in &task.terms {
            out += &format!(" {term}");
        }
        out.push('\n');
    }
    out
}

/// SHA-256 of `text` in lowercase hex.
pub fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// `file://` and the absolute path `path`, percent-encoded as Cargo reads a source URL.
fn file_url(path: &Path) -> String {
    let mut url = String::from("file://");
    for b in path.to_string_lossy().bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            url.push(b as char);
        } else {
            url += &format!("%{b:02X}");
        }
    }
    url
}

/// A task's or term's view.
fn name_view(name: &str, index: usize) -> NameView {
    NameView {
        name: name.into(),
        index,
        macro_name: name.to_uppercase(),
        literal: string_literal(name),
    }
}

pub fn library_context(ir: &Ir, package: &LibraryPackage) -> Result<LibraryContext, RenderError> {
    let m = &ir.model;
    if !package.repository.is_absolute() {
        return Err(RenderError::Template(format!(
            "the repository {} must be given as an absolute path",
            package.repository.display()
        )));
    }
    let text = fingerprint_text(ir);
    let in_repo = |parts: &[&str]| {
        let mut p = package.repository.clone();
        p.extend(parts);
        p
    };
    Ok(LibraryContext {
        model: LibraryModelView {
            name: m.name.clone(),
            marker: camel_case(&m.name),
            title_literal: string_literal(&m.title),
            title_comment: c_comment(&m.title),
            description: c_comment(&ir.generator.model),
            dof: m.dof,
            state_dim: m.state_dim,
            parameter_count: m.parameters.len(),
            tip_dim: m.tip_dim,
            parameters: m
                .parameters
                .iter()
                .enumerate()
                .map(|(index, p)| ParameterView {
                    name: p.name.clone(),
                    unit: c_comment(&p.unit),
                    index,
                    macro_name: p.name.to_uppercase(),
                })
                .collect(),
        },
        tasks: ir
            .tasks
            .iter()
            .enumerate()
            .map(|(i, t)| name_view(&t.name, i))
            .collect(),
        terms: ir
            .terms
            .iter()
            .enumerate()
            .map(|(i, t)| name_view(&t.name, i))
            .collect(),
        task_count: ir.tasks.len(),
        term_count: ir.terms.len(),
        abi_version: ABI_VERSION,
        fingerprint: sha256_hex(&text),
        fingerprint_lines: text.lines().map(str::to_string).collect(),
        package: LibraryPackageView {
            name: package.name.clone(),
            lib: package.name.replace('-', "_"),
            cabi_path: toml_string(&in_repo(&["crates", "cabi"]).to_string_lossy()),
            generated_source: toml_string(&file_url(&in_repo(&["generated"]))),
            command: "make model".into(),
            ir: ir.generator.ir.clone(),
        },
    })
}

/// Renders the library's crate around a model's generated crate: every template under
/// `templates` (templates/cabi/, laid out as the crate), each to its path less `.tera`.
pub fn render_library(
    ir: &Ir,
    templates: &Path,
    package: &LibraryPackage,
) -> Result<Vec<CrateFile>, RenderError> {
    let tree = load_template_tree(templates)?;
    let tera = engine(&tree)?;
    let context = tera::Context::from_serialize(library_context(ir, package)?)
        .map_err(|e| RenderError::Template(e.to_string()))?;
    tree.iter()
        .map(|(name, _)| {
            let file = render_one(
                &tera,
                name,
                &context,
                name.trim_end_matches(".tera").to_string(),
            )?;
            Ok(CrateFile {
                path: PathBuf::from(&file.file_name),
                source: templates.join(name),
                contents: file.contents,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pendulum() -> Ir {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/pendulum.json");
        crate::ir::read_ir(&path).expect("fixture")
    }

    #[test]
    fn the_fingerprint_lists_every_term_and_task_in_order() {
        let ir = pendulum();
        let text = fingerprint_text(&ir);
        assert!(
            text.starts_with("toolconf-tasks 1\nterm theta state 0\n"),
            "{text}"
        );
        assert!(text.contains("term u control 0\n"), "{text}");
        assert!(
            text.contains("\ntask position theta theta_dot theta_ddot u\n"),
            "{text}"
        );
        assert_eq!(text.lines().count(), 1 + ir.terms.len() + ir.tasks.len());
        assert_eq!(
            sha256_hex("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn paths_are_escaped_for_toml_and_cargo() {
        assert_eq!(toml_string(r#"/a "b"\c"#), r#""/a \"b\"\\c""#);
        assert_eq!(
            file_url(Path::new("/my repo/généré")),
            "file:///my%20repo/g%C3%A9n%C3%A9r%C3%A9"
        );
        let ir = pendulum();
        let c = library_context(
            &ir,
            &LibraryPackage::for_model("arm2_exact", Path::new("/r")),
        )
        .unwrap();
        assert_eq!(c.package.name, "toolconf-model-arm2-exact");
        assert_eq!(c.package.lib, "toolconf_model_arm2_exact");
        assert_eq!(c.package.cabi_path, "\"/r/crates/cabi\"");
        assert_eq!(c.package.generated_source, "\"file:///r/generated\"");
        assert!(library_context(&ir, &LibraryPackage::for_model("x", Path::new("r"))).is_err());
    }
}
