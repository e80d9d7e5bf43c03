//! Loading the templates: the per-model ones with their variants and macros, and the registry's
//! tree laid out as the crate it renders to.

use std::path::{Path, PathBuf};

use crate::ir::Ir;
use crate::RenderError;

/// Loads every `*.tera` file of a folder, in name order, then those of its sub-folders but
/// the [`TREES`] as `<folder>/<file>` ([`load_variants`]): macros a template imports and per-model
/// variants of the top-level templates (`urdf/`).
pub fn load_templates(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    let mut all = load_folder(dir)?;
    all.extend(load_variants(dir)?);
    Ok(all)
}

/// Every `*.tera` file directly in `dir`, in name order.
fn load_folder(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    entries(dir, |p| p.extension().is_some_and(|x| x == "tera"))?
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).map_err(|source| RenderError::Io {
                path: p.clone(),
                source,
            })?;
            Ok((file_name(&p), text))
        })
        .collect()
}

/// The paths in `dir` that `keep` keeps, in order.
fn entries(dir: &Path, keep: impl Fn(&Path) -> bool) -> Result<Vec<PathBuf>, RenderError> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|source| RenderError::Io {
            path: dir.into(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| keep(p))
        .collect();
    paths.sort();
    Ok(paths)
}

/// The last part of `path`, as text.
fn file_name(path: &Path) -> String {
    path.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
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

/// The template that renders `name` for this model: a variant `<folder>/<name>` (loaded by
/// [`load_variants`]) when the IR's `templates` list names one, else `name` itself. A URDF
/// model's report is not the closed forms' (templates/urdf/report.md.tera).
pub fn variant<'a>(ir: &Ir, name: &'a str, templates: &'a [(String, String)]) -> &'a str {
    let wanted = ir.templates.as_deref().unwrap_or_default();
    templates
        .iter()
        .map(|(n, _)| n.as_str())
        .find(|n| wanted.iter().any(|w| w == n) && n.rsplit('/').next() == Some(name))
        .unwrap_or(name)
}

/// The sub-folders of the templates that are trees laid out as a crate, rendered once over all
/// models (`registry/`) or for a model library (`cabi/`), not per-model variants.
pub const TREES: [&str; 2] = ["registry", "cabi"];

/// Every `*.tera` file in the sub-folders of `dir` other than the [`TREES`], named
/// `<folder>/<file>`.
fn load_variants(dir: &Path) -> Result<Vec<(String, String)>, RenderError> {
    let folders = entries(dir, |p| {
        p.is_dir()
            && p.file_name()
                .is_some_and(|n| !TREES.iter().any(|t| n == *t))
    })?;
    let mut out = Vec::new();
    for folder in folders {
        let prefix = file_name(&folder);
        for (name, text) in load_folder(&folder)? {
            out.push((format!("{prefix}/{name}"), text));
        }
    }
    Ok(out)
}
