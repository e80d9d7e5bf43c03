//! Design by the predicted task error against design by confidence and against random feasible
//! tools, all judged by simulation: the measurement of docs/explanation/prediction.md.
//!
//! For one model, task and design file: the design by `confidence` and by
//! `predicted_task_error` (the file's objective overridden, everything else as `toolconf design`
//! runs it), each tool's simulated task error, and the best simulated task error of N random
//! feasible tools (drawn uniformly from the feasible set with the file's seed, every one
//! simulated). Prints one JSON object.
//!
//! ```sh
//! cargo run --release --example design_predicted -- --model panda --task examples/tasks/panda_touch_point.toml --design examples/design/panda_tip_length.toml [--random 10000]
//! ```

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;
use toolconf::design::polytope::{FeasibleSampler, Polytope};
use toolconf::design::{design, parameters_text, Setting};
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::design_file::{DesignObjective, DesignSpec};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::{lookup, AnyTool};

fn value(args: &[String], key: &str) -> Option<String> {
    args.iter()
        .position(|a| a == key)
        .and_then(|i| args.get(i + 1).cloned())
}

/// The design by confidence and by the predicted task error, each as JSON with its simulated
/// task error, and those errors in that order.
fn design_both(
    spec: &DesignSpec,
    setting: &Setting,
    simulated: &dyn Fn(&[f64]) -> Option<f64>,
) -> (serde_json::Map<String, serde_json::Value>, Vec<Option<f64>>) {
    let mut designs = serde_json::Map::new();
    let mut errors = Vec::new();
    for objective in [
        DesignObjective::Confidence,
        DesignObjective::PredictedTaskError,
    ] {
        let spec = DesignSpec {
            objective,
            ..spec.clone()
        };
        let started = Instant::now();
        let r = design(&spec, setting).expect("design");
        let seconds = started.elapsed().as_secs_f64();
        let error = simulated(&r.params);
        errors.push(error);
        designs.insert(
            objective.name().into(),
            json!({
                "params": parameters_text(&spec.names, &r.params),
                "logdet": r.logdet,
                "simulated_task_error": error,
                "seconds_with_verification": seconds,
            }),
        );
    }
    (designs, errors)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let (Some(model), Some(task), Some(file)) = (
        value(&args, "--model"),
        value(&args, "--task"),
        value(&args, "--design"),
    ) else {
        eprintln!("usage: design_predicted --model M --task FILE --design FILE [--random N]");
        return ExitCode::from(2);
    };
    let random: usize = value(&args, "--random").map_or(10_000, |n| n.parse().unwrap_or(10_000));
    let model = match lookup(&model) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("--model {model}: {e}");
            return ExitCode::from(2);
        }
    };
    let spec_task = TaskSpec::from_file(Path::new(&task)).expect("task file");
    let tasks = ModelTasks::new(&spec_task);
    let setting = Setting::new(model, &spec_task, &tasks);
    let spec = DesignSpec::from_file(Path::new(&file), model).expect("design file");
    let simulated = |params: &[f64]| -> Option<f64> {
        let tool = AnyTool::new(model, params).ok()?;
        tasks.simulate(&tool).ok().map(|m| m.task_error)
    };
    let (designs, errors) = design_both(&spec, &setting, &simulated);
    let polytope = Polytope::new(&spec);
    let mut sampler = FeasibleSampler::new(&polytope, spec.search.seed ^ 0x5eed);
    let points: Vec<Vec<f64>> = (0..random)
        .map_while(|_| sampler.next_point(1_000_000))
        .collect();
    let started = Instant::now();
    let random_errors: Vec<(f64, usize)> = points
        .par_iter()
        .enumerate()
        .filter_map(|(i, x)| Some((simulated(&polytope.full(x))?, i)))
        .collect();
    let (best, at) = random_errors
        .iter()
        .copied()
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .expect("some random tool simulated");
    let by_prediction = errors[1].expect("the predicted design simulates");
    let by_confidence = errors[0].expect("the confidence design simulates");
    let out = json!({
        "model": model.name(),
        "task": task,
        "design_file": file,
        "designs": designs,
        "random": {
            "tools": points.len(),
            "simulated": random_errors.len(),
            "best_task_error": best,
            "best_params": parameters_text(&spec.names, &polytope.full(&points[at])),
            "seconds": started.elapsed().as_secs_f64(),
            "share_better_than_predicted_design": random_errors.iter().filter(|e| e.0 < by_prediction).count() as f64 / random_errors.len() as f64,
        },
        "predicted_below_confidence": by_prediction < by_confidence,
        "predicted_over_best_random": by_prediction / best - 1.0,
        "within_5_percent_of_best_random": by_prediction <= 1.05 * best,
    });
    println!("{}", serde_json::to_string_pretty(&out).expect("JSON"));
    ExitCode::SUCCESS
}
