//! `toolconf confidence --arm M1,M2,L1,L2 --task T [--json]`.

use serde_json::json;
use toolconf::model::Arm2;
use toolconf::validate::finite_output;
use toolconf::{control_confidence, Arm};

use super::episode_args::TaskArgs;
use super::output::{matrix_rows, print_matrix, CliError};
use super::parse_arm;

#[derive(clap::Args)]
pub struct Args {
    /// The tool: link masses and lengths M1,M2,L1,L2 (kg, m), all > 0.
    #[arg(long, value_parser = parse_arm, allow_hyphen_values = true)]
    arm: Arm,
    #[command(flatten)]
    task: TaskArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let spec = args.task.spec()?;
    let kind = spec.kind;
    let task = spec.task::<Arm2, 2, 4, 4, 6>()?;
    let confidence = control_confidence(&args.arm, &task).map_err(toolconf::Error::from)?;
    let s = args.arm.sensitivities(kind);
    let a = args.arm.state_matrix();
    let b = args.arm.input_matrix();
    let arm = format!("arm {}", args.arm);
    finite_output(&arm, "A", a.iter().copied())?;
    finite_output(&arm, "B", b.iter().copied())?;
    for m in [s.d_theta_du, s.d_theta_dot_du, s.d_theta_ddot_du]
        .iter()
        .flatten()
    {
        finite_output(&arm, "a sensitivity", m.iter().copied())?;
    }
    finite_output(&arm, "Π^U", confidence.pi_u.iter().copied())?;
    finite_output(&arm, "ln|Π^U|", [confidence.logdet])?;
    if args.json {
        let mut sens = serde_json::Map::new();
        for (name, m) in [
            ("d_theta_du", s.d_theta_du),
            ("d_theta_dot_du", s.d_theta_dot_du),
            ("d_theta_ddot_du", s.d_theta_ddot_du),
        ] {
            if let Some(m) = m {
                sens.insert(name.into(), matrix_rows(&m));
            }
        }
        let mut out = json!({
            "arm": args.arm,
            "task": kind,
            "a": matrix_rows(&a),
            "b": matrix_rows(&b),
            "sensitivities": sens,
            "pi_u": matrix_rows(&confidence.pi_u),
            "logdet": confidence.logdet,
        });
        if let Some(path) = &args.task.task_file {
            out["task_file"] = json!(path);
        }
        outln!(
            "{}",
            serde_json::to_string_pretty(&out).expect("JSON of finite numbers")
        );
        return Ok(());
    }
    outln!("arm: {}    task: {}", args.arm, spec.label());
    print_matrix("A = df/dX at the equilibrium", &a);
    print_matrix("B = df/dU at the equilibrium", &b);
    for (name, m) in [
        ("dtheta/dU", s.d_theta_du),
        ("dtheta_dot/dU", s.d_theta_dot_du),
        ("dtheta_ddot/dU", s.d_theta_ddot_du),
    ] {
        if let Some(m) = m {
            print_matrix(name, &m);
        }
    }
    print_matrix("Pi^U (control confidence)", &confidence.pi_u);
    outln!("ln|Pi^U| = {:.12}", confidence.logdet);
    Ok(())
}
