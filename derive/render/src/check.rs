//! A whole crate rendered in memory from its IR, and compared byte for byte with a crate folder
//! (the render-only check: `toolconf-render --crate generated --check`, and the root package's
//! tests/render_ensure.rs), without Python.

use std::path::{Path, PathBuf};

use crate::ir::{read_ir, Ir};
use crate::RenderError;
use crate::{crate_path, load_template_tree, load_templates, render, render_registry, Package};

/// One file of a rendered crate: where it goes (relative to the crate folder), what it was
/// rendered from, and its contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CrateFile {
    pub path: PathBuf,
    pub source: PathBuf,
    pub contents: String,
}

/// The IRs of a crate folder, in the order its registry lists the models: every `*.json` but the
/// `*.vectors.json`, by file name (as `make derive` and `make crate` render them).
pub fn crate_irs(folder: &Path) -> Result<Vec<PathBuf>, RenderError> {
    let io = |source| RenderError::Io {
        path: folder.into(),
        source,
    };
    let mut irs = Vec::new();
    for entry in std::fs::read_dir(folder).map_err(io)? {
        let path = entry.map_err(io)?.path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if path.is_file() && name.ends_with(".json") && !name.ends_with(".vectors.json") {
            irs.push(path);
        }
    }
    irs.sort();
    Ok(irs)
}

/// Every file the IRs render to through `templates` (each model's, then the registry's), and the
/// IRs read.
pub fn render_crate(
    ir_paths: &[PathBuf],
    templates: &Path,
    package: &Package,
) -> Result<(Vec<Ir>, Vec<CrateFile>), RenderError> {
    let registry_templates = load_template_tree(&templates.join("registry"))?;
    let model_templates = load_templates(templates)?;
    let mut irs = Vec::new();
    let mut files = Vec::new();
    for path in ir_paths {
        let ir = read_ir(path)?;
        for file in render(&ir, &model_templates)? {
            files.push(CrateFile {
                path: crate_path(&file.file_name),
                source: path.clone(),
                contents: file.contents,
            });
        }
        irs.push(ir);
    }
    for file in render_registry(&irs, &registry_templates, package)? {
        files.push(CrateFile {
            path: PathBuf::from(&file.file_name),
            source: templates.join("registry"),
            contents: file.contents,
        });
    }
    Ok((irs, files))
}

/// What differs between the crate folder and the rendered `files`: each file that is missing or
/// differs (with its first differing line), and each file in the folder that neither the render
/// nor the derivation (the IRs and their test vectors) makes. Empty when they agree byte for
/// byte. Cargo's own `target/` and `Cargo.lock` are not the crate's sources and are skipped.
pub fn check_crate(folder: &Path, irs: &[Ir], files: &[CrateFile]) -> Vec<String> {
    let shown = |p: &Path| folder.join(p).display().to_string();
    let mut problems = Vec::new();
    for file in files {
        match std::fs::read(folder.join(&file.path)) {
            Err(e) => problems.push(format!(
                "{}: cannot read it ({e}); the render makes it",
                shown(&file.path)
            )),
            Ok(bytes) if bytes != file.contents.as_bytes() => problems.push(format!(
                "{} differs from what the renderer makes of the IR, first at {}",
                shown(&file.path),
                first_difference(&bytes, file.contents.as_bytes())
            )),
            Ok(_) => {}
        }
    }
    let mut expected: Vec<PathBuf> = files.iter().map(|f| f.path.clone()).collect();
    for ir in irs {
        expected.push(PathBuf::from(&ir.generator.ir));
        expected.push(PathBuf::from(&ir.test_vectors.file));
    }
    for path in files_under(folder, Path::new("")) {
        if !expected.contains(&path) {
            problems.push(format!(
                "{}: neither the render nor the derivation makes it (stale)",
                shown(&path)
            ));
        }
    }
    problems
}

/// Every file under `folder/relative`, relative to `folder`, in path order, without cargo's
/// `target/` and `Cargo.lock`.
fn files_under(folder: &Path, relative: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(folder.join(relative)) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for entry in entries.flatten() {
        let path = relative.join(entry.file_name());
        if path == Path::new("target") || path == Path::new("Cargo.lock") {
            continue;
        }
        match entry.file_type() {
            Ok(t) if t.is_dir() => out.extend(files_under(folder, &path)),
            Ok(_) => out.push(path),
            Err(_) => {}
        }
    }
    out.sort();
    out
}

/// "line 12:\n    committed: ...\n    rendered:  ...", or where one file ends.
pub fn first_difference(committed: &[u8], rendered: &[u8]) -> String {
    let a = String::from_utf8_lossy(committed);
    let b = String::from_utf8_lossy(rendered);
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    let cut = |s: &str| s.trim().chars().take(160).collect::<String>();
    for (i, (x, y)) in la.iter().zip(&lb).enumerate() {
        if x != y {
            return format!(
                "line {}:\n    committed: {}\n    rendered:  {}",
                i + 1,
                cut(x),
                cut(y)
            );
        }
    }
    if la.len() == lb.len() {
        return format!(
            "the end: the same {} lines, but not the same line endings or final newline",
            la.len()
        );
    }
    format!(
        "line {}: one file ends there ({} vs {} lines)",
        la.len().min(lb.len()) + 1,
        la.len(),
        lb.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_differing_line_is_named() {
        let d = first_difference(b"a\nb\nc\n", b"a\nB\nc\n");
        assert!(d.starts_with("line 2:"), "{d}");
        assert!(
            d.contains("committed: b") && d.contains("rendered:  B"),
            "{d}"
        );
        let d = first_difference(b"a\nb\n", b"a\nb\nc\n");
        assert!(
            d.starts_with("line 3: one file ends there (2 vs 3 lines)"),
            "{d}"
        );
        let d = first_difference(b"a\nb", b"a\nb\n");
        assert!(d.contains("final newline"), "{d}");
        // A difference in white space at a line's end is a difference.
        let d = first_difference(b"a \n", b"a\n");
        assert!(d.starts_with("line 1:"), "{d}");
    }
}
