//! `toolconf simulate --arm M1,M2,L1,L2 --task T [--perturb DT] [--json] [--csv FILE]`.

use std::path::PathBuf;

use serde_json::json;
use toolconf::closed_loop::{simulate, Trajectory};
use toolconf::{Arm, Task, TaskKind};

use super::episode_args::EpisodeArgs;
use super::output::{write_atomically, CliError};
use super::{parse_arm, parse_task};

#[derive(clap::Args)]
pub struct Args {
    /// The tool: link masses and lengths M1,M2,L1,L2 (kg, m), all > 0.
    #[arg(long, value_parser = parse_arm, allow_hyphen_values = true)]
    arm: Arm,
    /// The task: position, velocity or acceleration (or 1, 2, 3).
    #[arg(long, value_parser = parse_task)]
    task: TaskKind,
    #[command(flatten)]
    episode: EpisodeArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Write the trajectory on the output grid to this CSV file.
    #[arg(long)]
    csv: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let task = Task::paper(args.task);
    let options = args.episode.options(args.csv.is_some())?;
    let episode = simulate(&args.arm, &task, &options)?;
    let m = episode.metrics;
    if let (Some(path), Some(tr)) = (&args.csv, &episode.trajectory) {
        write_atomically(path, &trajectory_csv(tr))?;
    }
    if args.json {
        let out = json!({
            "arm": args.arm,
            "task": args.task,
            "perturb": args.episode.perturbation,
            "task_error": m.task_error,
            "free_energy": m.free_energy,
            "cost_j": m.cost_j,
            "logdet": m.logdet,
            "rhs_evals": m.rhs_evals,
            "steps": m.steps,
            "rejected_steps": m.rejected_steps,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&out).expect("finite numbers")
        );
    } else {
        println!(
            "arm: {}    task: {} (task {})    perturbation: {} N m",
            args.arm,
            args.task,
            args.task.paper_index(),
            args.episode.perturbation
        );
        println!("task error     {:.9e}", m.task_error);
        println!("integral F dt  {:.9e}", m.free_energy);
        println!("integral J dt  {:.9e}", m.cost_j);
        println!("ln|Pi^U|       {:.9e}", m.logdet);
        println!(
            "rhs evals      {} ({} steps, {} rejected)",
            m.rhs_evals, m.steps, m.rejected_steps
        );
        if let Some(path) = &args.csv {
            println!("trajectory     {}", path.display());
        }
    }
    Ok(())
}

/// The trajectory as CSV, one row per grid point.
pub fn trajectory_csv(tr: &Trajectory) -> String {
    let mut out =
        String::from("t,theta1,theta2,theta1_dot,theta2_dot,theta1_ddot,theta2_ddot,u1,u2\n");
    for i in 0..tr.t.len() {
        out += &format!(
            "{},{},{},{},{},{},{},{},{}\n",
            tr.t[i],
            tr.theta[i][0],
            tr.theta[i][1],
            tr.theta_dot[i][0],
            tr.theta_dot[i][1],
            tr.theta_ddot[i][0],
            tr.theta_ddot[i][1],
            tr.u[i][0],
            tr.u[i][1]
        );
    }
    out
}
