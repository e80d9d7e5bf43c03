//! `toolconf reproduce [--out DIR] [--seed S] [--quick] [--only IDS]`: every experiment of the
//! paper's Results section, with CSVs, SVG figures and a report (Markdown and HTML); with
//! `--model`, the same experiments on any model, task and tool population ([`super::evaluate`]).

use std::io::IsTerminal;
use std::path::PathBuf;

use toolconf_report::experiments::{
    experiment_ids, output_files, reproduce, Config, Plan, ReproduceError,
};

use super::output::{check_files, CliError, RunFiles};

#[derive(clap::Args)]
pub struct Args {
    /// Directory for the CSVs, figures and report (created if missing).
    #[arg(long, default_value = "results")]
    out: PathBuf,
    /// Master seed; each experiment derives its own sub-seed from it.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Small counts instead of the paper's (for tests: seconds, not statistics).
    #[arg(long)]
    quick: bool,
    /// Run only these experiments (comma-separated: fig2,fig3,fig4,fig5,fig6,fig7).
    #[arg(long, value_delimiter = ',', value_parser = parse_experiment, conflicts_with = "model")]
    only: Option<Vec<String>>,
    /// Also run the MPC baseline: J* in Fig. 7 and the active-inference-against-MPC section
    /// (about ten times the run time of the paper's experiments).
    #[arg(long, conflicts_with = "model")]
    mpc: bool,
    #[command(flatten)]
    method: super::episode_args::MethodArgs,
    #[command(flatten)]
    model: super::evaluate::ModelArgs,
}

/// What the paper's reproduction and an evaluation with `--model` share.
pub struct Common {
    pub out: PathBuf,
    pub seed: u64,
    pub quick: bool,
    pub method: toolconf_integrators::Method,
    /// The command line, quoted in the report.
    pub command: String,
}

fn parse_experiment(s: &str) -> Result<String, String> {
    let ids = experiment_ids();
    if ids.contains(&s) {
        Ok(s.to_string())
    } else {
        Err(format!(
            "unknown experiment {s:?}; known: {}",
            ids.join(", ")
        ))
    }
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let method = toolconf_integrators::Method::from(args.method.method);
    if let Some(model) = args.model.model {
        let command: Vec<String> = std::env::args().collect();
        let common = Common {
            out: args.out.clone(),
            seed: args.seed,
            quick: args.quick,
            method,
            command: command.join(" "),
        };
        return super::evaluate::run(&args.model, model, &common);
    }
    if let Some(flag) = args.model.stray_flag() {
        return Err(CliError::Usage(format!(
            "{flag} is for an evaluation on a model: give --model too (without it, reproduce \
             runs the paper's own experiments)"
        )));
    }
    paper(args, method)
}

/// The paper's Results section on its planar arm, as before `--model` existed.
fn paper(args: &Args, method: toolconf_integrators::Method) -> Result<(), CliError> {
    let mut command = format!(
        "toolconf reproduce --out {} --seed {}",
        args.out.display(),
        args.seed
    );
    if args.quick {
        command.push_str(" --quick");
    }
    if let Some(only) = &args.only {
        command.push_str(&format!(" --only {}", only.join(",")));
    }
    if args.mpc {
        command.push_str(" --mpc");
    }
    if method != toolconf_integrators::Method::Fast {
        command.push_str(&format!(
            " --method {}",
            format!("{method:?}").to_lowercase()
        ));
    }
    let config = Config {
        out_dir: args.out.clone(),
        seed: args.seed,
        plan: Plan {
            mpc: args.mpc,
            ..if args.quick {
                Plan::quick()
            } else {
                Plan::paper()
            }
        },
        only: args.only.clone(),
        progress: std::io::stderr().is_terminal(),
        command,
        method,
    };
    let planned = output_files(&config).map_err(|e| CliError::Usage(e.to_string()))?;
    check_files(RunFiles::new().output_folder("--out", &args.out, &planned))?;
    let summary = reproduce(&config).map_err(|e| match e {
        ReproduceError::Io { path, source } => CliError::Io { path, source },
        other => CliError::Io {
            path: args.out.clone(),
            source: std::io::Error::other(other.to_string()),
        },
    })?;
    for section in &summary.sections {
        for v in section.verdicts() {
            outln!("{:<34} {}", v.claim, v.outcome.words());
        }
    }
    let secs = summary.wall.as_secs_f64();
    outln!(
        "{} episodes in {:.2} s on {} thread(s) ({:.0} episodes/s)",
        summary.episodes(),
        secs,
        summary.threads,
        if secs > 0.0 {
            summary.episodes() as f64 / secs
        } else {
            0.0
        }
    );
    outln!("report: {}", summary.report_md.display());
    outln!(
        "report (HTML, figures inline): {}",
        summary.report_html.display()
    );
    Ok(())
}
