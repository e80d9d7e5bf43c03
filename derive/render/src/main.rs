//! `toolconf-render [IR.json...] [--crate DIR] [--templates templates] [--out generated]
//! [--crate-name NAME] [--standalone] [--check]`: renders each IR through every template, then
//! all of them through `templates/registry/` (the crate around the models), and writes the
//! results into the crate folder `--out` (see the library docs for the naming rule).
//!
//! `--crate DIR` renders the IRs already in the crate folder DIR (every `*.json` but the test
//! vectors) back into it: `make render`, after a change to the templates or the renderer, with no
//! derivation. `--check` writes nothing: it compares what it would write with the folder, byte for
//! byte, names each file that differs and its first differing line, and fails (status 1).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use toolconf_render::{check_crate, crate_irs, render_crate, CrateFile, Package, RenderError};

fn write(out: &Path, file: &CrateFile) -> Result<(), RenderError> {
    let target = out.join(&file.path);
    let io = |source| RenderError::Io {
        path: target.clone(),
        source,
    };
    if let Some(parent) = target.parent() {
        std::fs::create_dir_all(parent).map_err(io)?;
    }
    std::fs::write(&target, &file.contents).map_err(io)?;
    println!("render: {} -> {}", file.source.display(), target.display());
    Ok(())
}

struct Args {
    irs: Vec<PathBuf>,
    templates: PathBuf,
    out: PathBuf,
    package: Package,
    from_crate: bool,
    check: bool,
}

fn parse(args: &[String]) -> Args {
    let mut a = Args {
        irs: Vec::new(),
        templates: PathBuf::from("templates"),
        out: PathBuf::from("generated"),
        package: Package::in_repository(),
        from_crate: false,
        check: false,
    };
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--templates" => a.templates = it.next().map(PathBuf::from).unwrap_or(a.templates),
            "--out" => a.out = it.next().map(PathBuf::from).unwrap_or(a.out),
            "--crate" => {
                a.out = it.next().map(PathBuf::from).unwrap_or(a.out);
                a.from_crate = true;
            }
            "--crate-name" => a.package.name = it.next().cloned().unwrap_or(a.package.name),
            "--standalone" => a.package.standalone = true,
            "--check" => a.check = true,
            _ => a.irs.push(PathBuf::from(arg)),
        }
    }
    a
}

/// Renders; with `--check`, the differences found (none when the folder is up to date).
fn run(a: &Args) -> Result<Vec<String>, RenderError> {
    let irs = if a.from_crate && a.irs.is_empty() {
        crate_irs(&a.out)?
    } else {
        a.irs.clone()
    };
    let (read, files) = render_crate(&irs, &a.templates, &a.package)?;
    if a.check {
        return Ok(check_crate(&a.out, &read, &files));
    }
    for file in &files {
        write(&a.out, file)?;
    }
    Ok(Vec::new())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() || args.iter().any(|a| a == "--help" || a == "-h") {
        eprintln!(
            "usage: toolconf-render [IR.json...] [--crate DIR] [--templates DIR] [--out DIR] [--crate-name NAME] [--standalone] [--check]"
        );
        return ExitCode::from(2);
    }
    let a = parse(&args);
    match run(&a) {
        Ok(problems) if problems.is_empty() => {
            if a.check {
                println!(
                    "render: {} is byte for byte what its IR renders to",
                    a.out.display()
                );
            }
            ExitCode::SUCCESS
        }
        Ok(problems) => {
            for p in &problems {
                eprintln!("toolconf-render: {p}");
            }
            let again: Vec<&str> = args
                .iter()
                .map(String::as_str)
                .filter(|a| *a != "--check")
                .collect();
            eprintln!(
                "toolconf-render: run `toolconf-render {}` (for generated/: `make render`), review the diff and commit it; `make derive` if the IR itself is stale",
                again.join(" ")
            );
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("toolconf-render: {e}");
            ExitCode::FAILURE
        }
    }
}
