//! `toolconf-render [IR.json...] [--crate DIR] [--templates templates] [--out generated]
//! [--crate-name NAME] [--standalone] [--check]`: renders each IR through every template, then
//! all of them through `templates/registry/` (the crate around the models), and writes the
//! results into the crate folder `--out` (see the library docs for the naming rule).
//!
//! `--crate DIR` renders the IRs already in the crate folder DIR (every `*.json` but the test
//! vectors) back into it: `make render`, after a change to the templates or the renderer, with no
//! derivation. `--check` writes nothing: it compares what it would write with the folder, byte for
//! byte, names each file that differs and its first differing line, and fails (status 1).
//!
//! `make crate`'s folder rule ([`toolconf_files::folder`]), with no rendering:
//! `--check-crate-out OUT --repository DIR [--input LABEL PATH]...` checks, before anything is
//! derived, that OUT may become the crate; `--install-crate STAGING --out OUT --repository DIR
//! [--input LABEL PATH]...` checks again, writes the ownership manifest into the crate made in
//! STAGING and moves it into place; `--command NAME` names another command as the folder's maker
//! (`make model`: a folder of one command is not the other's to replace). A refusal is one line, status 2; a failure to write, status 1.
//!
//! `--check-ir IR.json...` reads and checks each IR (its shape, and each field of its kind:
//! text, names, file names, code) and renders nothing: `make model IR=...` asks it before
//! anything else, so that a bad IR is one line, status 2.
//!
//! `--ir-schema` prints the JSON Schema of the IR this renderer reads, which the derivation builds
//! its types from (`derive/ir_schema.json`: [`toolconf_render::ir_schema`]).
//!
//! `make model`'s library crate: `IR.json --model-library DIR --repository REPO [--templates
//! templates]` renders templates/cabi/ for the one model into DIR (its generated crate, rendered
//! as usual, goes into DIR/generated), on the repository REPO's toolconf-cabi.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use toolconf_files::file::create_folder;
use toolconf_files::folder::{CrateFolder, FolderError};
use toolconf_files::{write_atomically, WriteError};
use toolconf_render::cabi::{render_library, LibraryPackage};
use toolconf_render::{check_crate, crate_irs, render_crate, CrateFile, Package, RenderError};

/// Writes one rendered file whole, or leaves what was there (toolconf_files' rule).
fn write(out: &Path, file: &CrateFile) -> Result<(), RenderError> {
    let target = out.join(&file.path);
    let folder = target.parent().unwrap_or(out);
    create_folder(folder).map_err(WriteError::at(folder))?;
    write_atomically(&target, &file.contents)?;
    println!("render: {} -> {}", file.source.display(), target.display());
    Ok(())
}

/// `make crate`'s folder rule, asked for instead of a render.
enum CrateRule {
    Check(PathBuf),
    Install(PathBuf),
}

struct Args {
    irs: Vec<PathBuf>,
    templates: PathBuf,
    out: PathBuf,
    out_given: bool,
    package: Package,
    from_crate: bool,
    check: bool,
    crate_rule: Option<CrateRule>,
    repository: Option<PathBuf>,
    inputs: Vec<(String, PathBuf)>,
    model_library: Option<PathBuf>,
    check_ir: bool,
    ir_schema: bool,
    /// The command the folder rule names as the folder's maker (`make crate`, `make model`).
    command: String,
}

/// The value after `flag`, which the folder rule cannot do without.
fn value<'a>(it: &mut impl Iterator<Item = &'a String>, flag: &str) -> Result<&'a String, String> {
    it.next().ok_or_else(|| format!("{flag} needs a value"))
}

fn parse(args: &[String]) -> Result<Args, String> {
    let mut a = Args {
        irs: Vec::new(),
        templates: PathBuf::from("templates"),
        out: PathBuf::from("generated"),
        out_given: false,
        package: Package::in_repository(),
        from_crate: false,
        check: false,
        crate_rule: None,
        repository: None,
        inputs: Vec::new(),
        model_library: None,
        check_ir: false,
        ir_schema: false,
        command: "make crate".into(),
    };
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--templates" => a.templates = it.next().map(PathBuf::from).unwrap_or(a.templates),
            "--out" => {
                a.out = it.next().map(PathBuf::from).unwrap_or(a.out);
                a.out_given = true;
            }
            "--crate" => {
                a.out = it.next().map(PathBuf::from).unwrap_or(a.out);
                a.from_crate = true;
            }
            "--crate-name" => a.package.name = it.next().cloned().unwrap_or(a.package.name),
            "--standalone" => a.package.standalone = true,
            "--check" => a.check = true,
            "--check-ir" => a.check_ir = true,
            "--ir-schema" => a.ir_schema = true,
            "--check-crate-out" => {
                a.crate_rule = Some(CrateRule::Check(value(&mut it, arg)?.into()));
            }
            "--install-crate" => {
                a.crate_rule = Some(CrateRule::Install(value(&mut it, arg)?.into()));
            }
            "--repository" => a.repository = Some(value(&mut it, arg)?.into()),
            "--model-library" => a.model_library = Some(value(&mut it, arg)?.into()),
            "--command" => a.command = value(&mut it, arg)?.clone(),
            "--input" => {
                let label = value(&mut it, arg)?.clone();
                let path = value(&mut it, "--input LABEL")?.into();
                a.inputs.push((label, path));
            }
            _ => a.irs.push(PathBuf::from(arg)),
        }
    }
    if matches!(a.crate_rule, Some(CrateRule::Install(_))) && !a.out_given {
        return Err("--install-crate needs --out OUT".into());
    }
    if a.model_library.is_some() && (a.irs.len() != 1 || a.repository.is_none()) {
        return Err("--model-library DIR needs one IR and --repository REPO".into());
    }
    Ok(a)
}

/// Checks OUT, or installs the staged crate there, by `make crate`'s folder rule.
fn crate_folder(a: &Args, rule: &CrateRule) -> Result<(), FolderError> {
    let out = match rule {
        CrateRule::Check(out) => out,
        CrateRule::Install(_) => &a.out,
    };
    let mut folder = CrateFolder::new("OUT", out, &a.command)?;
    if let Some(repository) = &a.repository {
        folder.repository(repository);
    }
    for (label, path) in &a.inputs {
        folder.input(label, path);
    }
    match rule {
        CrateRule::Check(_) => folder.check().map(drop),
        CrateRule::Install(staging) => folder.install(staging),
    }
}

/// `--model-library DIR`: the library's crate around the one model.
fn run_model_library(a: &Args, dir: &Path) -> Result<(), RenderError> {
    let ir = toolconf_render::read_ir(&a.irs[0])?;
    let repository = a.repository.as_deref().unwrap_or(Path::new("."));
    let repository = std::path::absolute(repository).map_err(|source| RenderError::Io {
        path: repository.into(),
        source,
    })?;
    let package = LibraryPackage::for_model(&ir.model.name, &repository);
    for file in render_library(&ir, &a.templates.join("cabi"), &package)? {
        write(dir, &file)?;
    }
    Ok(())
}

/// Renders; with `--check`, the differences found (none when the folder is up to date).
fn run(a: &Args) -> Result<Vec<String>, RenderError> {
    if let Some(dir) = &a.model_library {
        return run_model_library(a, dir).map(|()| Vec::new());
    }
    if a.check_ir {
        for ir in &a.irs {
            toolconf_render::read_ir(ir)?;
        }
        return Ok(Vec::new());
    }
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

/// `make crate`'s folder rule: a refusal is status 2, a failure to write status 1.
fn run_crate_rule(a: &Args, rule: &CrateRule) -> ExitCode {
    match crate_folder(a, rule) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("toolconf-render: {e}");
            let refused = matches!(e, FolderError::Refused(_));
            ExitCode::from(if refused { 2 } else { 1 })
        }
    }
}

/// `--ir-schema`: the IR's JSON Schema on standard output (status 1 if the types cannot be
/// described, which is a fault of this renderer, not of any input).
fn print_ir_schema() -> ExitCode {
    match toolconf_render::ir_schema::ir_schema() {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("toolconf-render: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The arguments, each of which must be UTF-8 (a path that is not cannot be told apart here).
fn arguments() -> Result<Vec<String>, String> {
    std::env::args_os()
        .skip(1)
        .map(|a| {
            a.into_string()
                .map_err(|a| format!("{}: not UTF-8", a.to_string_lossy()))
        })
        .collect()
}

fn main() -> ExitCode {
    let parsed = arguments().and_then(|args| parse(&args).map(|a| (args, a)));
    let (args, a) = match parsed {
        Ok(parsed) => parsed,
        Err(message) => {
            eprintln!("toolconf-render: {message}");
            return ExitCode::from(2);
        }
    };
    if args.is_empty() || args.iter().any(|a| a == "--help" || a == "-h") {
        eprintln!(
            "usage: toolconf-render [IR.json...] [--crate DIR] [--templates DIR] [--out DIR] [--crate-name NAME] [--standalone] [--check]\n       toolconf-render --check-ir IR.json...\n       toolconf-render --ir-schema\n       toolconf-render IR.json --model-library DIR --repository REPO [--templates DIR]\n       toolconf-render --check-crate-out OUT --repository DIR [--command NAME] [--input LABEL PATH]...\n       toolconf-render --install-crate STAGING --out OUT --repository DIR [--command NAME] [--input LABEL PATH]..."
        );
        return ExitCode::from(2);
    }
    if let Some(rule) = &a.crate_rule {
        return run_crate_rule(&a, rule);
    }
    if a.ir_schema {
        return print_ir_schema();
    }
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
            ExitCode::from(if e.is_refusal() { 2 } else { 1 })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(words: &[&str]) -> Result<Args, String> {
        parse(&words.iter().map(|w| w.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn the_folder_rules_flags_need_their_values() {
        let a = args(&["--check-crate-out", "/o", "--input", "TASKS=t", "/t"]).unwrap();
        assert!(matches!(&a.crate_rule, Some(CrateRule::Check(out)) if out == Path::new("/o")));
        assert_eq!(a.inputs, [("TASKS=t".to_string(), PathBuf::from("/t"))]);
        assert!(a.irs.is_empty());
        let e = args(&["--check-crate-out", "/o", "--input", "TASKS=t"]).err();
        assert_eq!(e.as_deref(), Some("--input LABEL needs a value"));
        let e = args(&["--repository"]).err();
        assert_eq!(e.as_deref(), Some("--repository needs a value"));
        // Without --out, the install would aim at generated/: refused.
        let e = args(&["--install-crate", "/s"]).err();
        assert_eq!(e.as_deref(), Some("--install-crate needs --out OUT"));
        assert!(args(&["--install-crate", "/s", "--out", "/o"]).is_ok());
    }
}
