//! `toolconf tool --urdf FILE --root LINK --tip LINK [--flange LINK] [--opening V]
//! [--joint NAME=V]... [--name N] [--model M] [--out FILE]`: a tool's row of a tools file from
//! the tool's own URDF (mass, centre of mass, full inertia and tip in the flange frame;
//! the crate toolconf-tool-urdf says how).
//!
//! The `#` line, the header and the row go to standard output, or with `--out` to a new tools
//! file by the project's one output rule (`toolconf_files`: a temporary file renamed into
//! place; never the URDF itself, checked by device and inode).

use std::path::PathBuf;

use toolconf_messages::Clip;
use toolconf_tool_urdf::{tool_from_urdf_file, Request};

use super::output::{check_files, write_atomically, CliError, RunFiles};

#[derive(clap::Args)]
pub struct Args {
    /// The tool's (or gripper's) URDF file.
    #[arg(long)]
    urdf: PathBuf,
    /// The tool's root link: it and every link below it are merged into one rigid body.
    #[arg(long, allow_hyphen_values = true)]
    root: String,
    /// The link whose origin is the tool-centre point (the root or a link below it).
    #[arg(long, allow_hyphen_values = true)]
    tip: String,
    /// An ancestor link of the root, joined to it by fixed joints, whose frame is the flange
    /// frame (default: the root's frame), e.g. panda_link8 for the Franka Hand.
    #[arg(long, allow_hyphen_values = true)]
    flange: Option<String>,
    /// The position (m or rad) of every movable joint below the root that is not a <mimic>
    /// (mimics follow the joint they mimic), e.g. 0.04 for an open Franka Hand's fingers.
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    opening: Option<f64>,
    /// The position of one joint, NAME=VALUE (m or rad), over --opening; repeatable.
    #[arg(long = "joint", value_name = "NAME=VALUE", value_parser = parse_joint,
          allow_hyphen_values = true)]
    joints: Vec<(String, f64)>,
    /// The tool's name in the row (default: the root link's name).
    #[arg(long, allow_hyphen_values = true)]
    name: Option<String>,
    /// The row's model: a generated model with a tool at a URDF flange (panda, ur5); the cell
    /// is left empty without it.
    #[arg(long, value_parser = parse_flange_model)]
    model: Option<String>,
    /// Write the tools file here instead of to standard output.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn parse_number(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("'{}' is not finite", Clip(s))),
        Err(_) => Err(format!("'{}' is not a number", Clip(s))),
    }
}

fn parse_joint(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s
        .rsplit_once('=')
        .ok_or_else(|| format!("'{}' is not NAME=VALUE", Clip(s)))?;
    if name.is_empty() {
        return Err(format!("'{}' has no joint name before '='", Clip(s)));
    }
    let value = parse_number(value).map_err(|e| format!("{}: {e}", Clip(name)))?;
    Ok((name.to_string(), value))
}

fn parse_flange_model(s: &str) -> Result<String, String> {
    toolconf_model::registry::flange_model(s).map(str::to_string)
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let mut files = RunFiles::new();
    files.input("--urdf", &args.urdf);
    if let Some(out) = &args.out {
        files.output_file("--out", out);
    }
    check_files(&files)?;
    let request = Request {
        root: args.root.clone(),
        tip: args.tip.clone(),
        flange: args.flange.clone(),
        opening: args.opening,
        joints: args.joints.clone(),
    };
    let tool =
        tool_from_urdf_file(&args.urdf, &request).map_err(|e| CliError::Usage(e.to_string()))?;
    let file = args.urdf.to_string_lossy();
    let name = args.name.as_deref().unwrap_or(&args.root);
    let text = tool.tools_file(&file, &request, name, args.model.as_deref());
    match &args.out {
        Some(out) => write_atomically(out, &text),
        None => {
            outln!("{}", text.trim_end());
            Ok(())
        }
    }
}
