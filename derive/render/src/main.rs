//! `toolconf-render IR.json... --templates templates --out generated`: renders each IR through
//! every template, then all of them through `templates/registry/` (the model registry), and
//! writes the results (see the library docs for the naming rule).

use std::path::PathBuf;
use std::process::ExitCode;

use toolconf_render::{load_templates, read_ir, render, render_registry, RenderError, Rendered};

fn write(
    out: &std::path::Path,
    source: &std::path::Path,
    file: Rendered,
) -> Result<(), RenderError> {
    let target = out.join(&file.file_name);
    std::fs::write(&target, file.contents).map_err(|source| RenderError::Io {
        path: target.clone(),
        source,
    })?;
    println!("render: {} -> {}", source.display(), target.display());
    Ok(())
}

fn run(args: &[String]) -> Result<(), RenderError> {
    let mut irs = Vec::new();
    let mut templates = PathBuf::from("templates");
    let mut out = PathBuf::from("generated");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--templates" => templates = it.next().map(PathBuf::from).unwrap_or(templates),
            "--out" => out = it.next().map(PathBuf::from).unwrap_or(out),
            _ => irs.push(PathBuf::from(a)),
        }
    }
    let registry_templates = load_templates(&templates.join("registry"))?;
    let templates = load_templates(&templates)?;
    let mut all = Vec::new();
    for path in &irs {
        let ir = read_ir(path)?;
        for file in render(&ir, &templates)? {
            write(&out, path, file)?;
        }
        all.push(ir);
    }
    for file in render_registry(&all, &registry_templates)? {
        write(&out, std::path::Path::new("templates/registry"), file)?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() || args.iter().any(|a| a == "--help" || a == "-h") {
        eprintln!("usage: toolconf-render IR.json... [--templates DIR] [--out DIR]");
        return ExitCode::from(2);
    }
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("toolconf-render: {e}");
            ExitCode::FAILURE
        }
    }
}
