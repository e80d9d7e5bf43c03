//! `toolconf-render IR.json... --templates templates --out generated [--crate-name NAME]
//! [--standalone]`: renders each IR through every template, then all of them through
//! `templates/registry/` (the crate around the models), and writes the results into the crate
//! folder `--out` (see the library docs for the naming rule).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use toolconf_render::{
    crate_path, load_template_tree, load_templates, read_ir, render, render_registry, Package,
    RenderError, Rendered,
};

fn write(out: &Path, source: &Path, relative: &Path, file: Rendered) -> Result<(), RenderError> {
    let target = out.join(relative);
    let io = |source| RenderError::Io {
        path: target.clone(),
        source,
    };
    if let Some(parent) = target.parent() {
        std::fs::create_dir_all(parent).map_err(io)?;
    }
    std::fs::write(&target, file.contents).map_err(io)?;
    println!("render: {} -> {}", source.display(), target.display());
    Ok(())
}

fn run(args: &[String]) -> Result<(), RenderError> {
    let mut irs = Vec::new();
    let mut templates = PathBuf::from("templates");
    let mut out = PathBuf::from("generated");
    let mut package = Package::in_repository();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--templates" => templates = it.next().map(PathBuf::from).unwrap_or(templates),
            "--out" => out = it.next().map(PathBuf::from).unwrap_or(out),
            "--crate-name" => package.name = it.next().cloned().unwrap_or(package.name),
            "--standalone" => package.standalone = true,
            _ => irs.push(PathBuf::from(a)),
        }
    }
    let registry_templates = load_template_tree(&templates.join("registry"))?;
    let templates = load_templates(&templates)?;
    let mut all = Vec::new();
    for path in &irs {
        let ir = read_ir(path)?;
        for file in render(&ir, &templates)? {
            let relative = crate_path(&file.file_name);
            write(&out, path, &relative, file)?;
        }
        all.push(ir);
    }
    for file in render_registry(&all, &registry_templates, &package)? {
        let relative = PathBuf::from(&file.file_name);
        write(&out, Path::new("templates/registry"), &relative, file)?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() || args.iter().any(|a| a == "--help" || a == "-h") {
        eprintln!(
            "usage: toolconf-render IR.json... [--templates DIR] [--out DIR] [--crate-name NAME] [--standalone]"
        );
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
