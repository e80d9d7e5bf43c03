//! `toolconf confidence --arm M1,M2,L1,L2 --task T [--json]`, or `--model M --params P1,P2,…`
//! for a tool of any generated model.

use serde_json::{json, Value};
use toolconf::rank::{Linearisation, ModelTasks};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::model::Arm2;
use toolconf_model::registry::ModelKind;
use toolconf_model::validate::finite_output;
use toolconf_model::{control_confidence, Arm, Term};

use super::episode_args::TaskArgs;
use super::output::{matrix_rows, print_matrix, CliError};
use super::tool_args::{ToolArgs, CONFIDENCE_PARAMS_HELP};
use super::tool_from_params;

#[derive(clap::Args)]
// The tool's flags are shared with `simulate`; only --params' help here is this command's own.
#[command(mut_arg("params", |a| a.help(CONFIDENCE_PARAMS_HELP)))]
pub struct Args {
    #[command(flatten)]
    tool: ToolArgs,
    #[command(flatten)]
    task: TaskArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let spec = args.task.spec()?;
    match (args.tool.arm, args.tool.model) {
        (Some(arm), _) => run_arm(args, &arm, &spec),
        (None, Some(model)) => run_model(args, model, &spec),
        (None, None) => Err(CliError::Usage("give --arm or --model".into())),
    }
}

fn run_arm(args: &Args, arm: &Arm, spec: &TaskSpec) -> Result<(), CliError> {
    let kind = spec.kind;
    // Π^U does not depend on the goals, so a relative tip goal needs no tool here.
    let (task, _) = spec.task_and_offset::<Arm2, 2, 4, 4, 6>()?;
    let confidence = control_confidence(arm, &task).map_err(toolconf_model::Error::from)?;
    let s = arm.sensitivities(kind);
    let a = arm.state_matrix();
    let b = arm.input_matrix();
    let label = format!("arm {arm}");
    finite_output(&label, "A", a.iter().copied())?;
    finite_output(&label, "B", b.iter().copied())?;
    for m in s.d_du.iter().flatten() {
        finite_output(&label, "a sensitivity", m.iter().copied())?;
    }
    finite_output(&label, "Π^U", confidence.pi_u.iter().copied())?;
    finite_output(&label, "ln|Π^U|", [confidence.logdet])?;
    if args.json {
        let mut sens = serde_json::Map::new();
        for term in Term::ALL {
            if let Some(m) = s.of(term) {
                sens.insert(term.sensitivity_name().into(), matrix_rows(&m));
            }
        }
        let out = json!({
            "arm": arm,
            "task": kind,
            "a": matrix_rows(&a),
            "b": matrix_rows(&b),
            "sensitivities": sens,
            "pi_u": matrix_rows(&confidence.pi_u),
            "logdet": confidence.logdet,
        });
        print_json(args, out);
        return Ok(());
    }
    outln!("arm: {arm}    task: {}", spec.label());
    print_matrix("A = df/dX at the equilibrium", &a);
    print_matrix("B = df/dU at the equilibrium", &b);
    for term in Term::ALL {
        if let Some(m) = s.of(term) {
            print_matrix(&sensitivity_title(term.sensitivity_name()), &m);
        }
    }
    print_matrix("Pi^U (control confidence)", &confidence.pi_u);
    outln!("ln|Pi^U| = {:.12}", confidence.logdet);
    Ok(())
}

/// A tool of any model, through the model-generic runtime: the numbers `rank` and Python's
/// `toolconf.confidence` give it.
fn run_model(args: &Args, model: ModelKind, spec: &TaskSpec) -> Result<(), CliError> {
    let tool = tool_from_params(model, args.tool.params.as_deref().unwrap_or_default())?;
    let tasks = ModelTasks::new(spec);
    tasks.check(model)?;
    let l: Linearisation = tasks.linearisation(&tool)?;
    l.check_finite(&tool)?;
    if args.json {
        let named: serde_json::Map<String, Value> = tool
            .named_parameters()
            .into_iter()
            .map(|(k, v)| (k.to_string(), json!(v)))
            .collect();
        let sens: serde_json::Map<String, Value> = l
            .sensitivities
            .iter()
            .map(|(name, m)| (name.to_string(), json!(m)))
            .collect();
        let mut out = json!({
            "model": model.name(),
            "params": named,
            "task": spec.kind,
            "a": l.a,
            "b": l.b,
            "sensitivities": sens,
            "pi_u": l.pi_u,
            "logdet": l.logdet,
        });
        super::prediction::add_prediction(&mut out, &tasks.predict(&tool));
        print_json(args, out);
        return Ok(());
    }
    outln!("tool: {tool}    task: {}", spec.label());
    print_rows("A = df/dX at the equilibrium", &l.a);
    print_rows("B = df/dU at the equilibrium", &l.b);
    for (name, m) in &l.sensitivities {
        print_rows(&sensitivity_title(name), m);
    }
    print_rows("Pi^U (control confidence)", &l.pi_u);
    outln!("ln|Pi^U| = {:.12}", l.logdet);
    Ok(())
}

fn print_json(args: &Args, mut out: Value) {
    if let Some(path) = &args.task.task_file {
        out["task_file"] = json!(path);
    }
    outln!(
        "{}",
        serde_json::to_string_pretty(&out).expect("JSON of finite numbers")
    );
}

/// A titled matrix given as rows, as [`print_matrix`] prints one.
fn print_rows(title: &str, m: &[Vec<f64>]) {
    outln!("{title}:");
    for row in m {
        let row: Vec<String> = row.iter().map(|x| format!("{x:>16.9e}")).collect();
        outln!("  [{}]", row.join(" "));
    }
}

/// `dtheta/dU` for the sensitivity named `d_theta_du` ([`Term::sensitivity_name`]).
fn sensitivity_title(name: &str) -> String {
    let term = name.strip_prefix("d_").and_then(|n| n.strip_suffix("_du"));
    format!("d{}/dU", term.unwrap_or(name))
}
