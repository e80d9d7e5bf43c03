//! A design as one JSON object: what `toolconf design --json` prints and `toolconf.design`
//! returns (one builder, so the two cannot drift apart).

use serde_json::{json, Map, Value};

use super::polytope::Polytope;
use super::sweep::SweepPoint;
use super::DesignResult;
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::registry::ModelKind;

/// The design `r` of `model` on the task named `task` (as the user gave it), with the sweep's
/// front if there was one. Keys: `objective`, `params` (by name), `logdet`,
/// `confidence_optimum`, `gradient` (over the free parameters), `gradient_check`,
/// `kkt_residual`, `converged`, `iterations`, `start`, `free_energy_simulations`, `perturbation`, `random`,
/// `verification` (one object per simulated tool), `model`, `task` and, after a sweep, `sweep`.
pub fn design_json(
    spec: &DesignSpec,
    r: &DesignResult,
    model: ModelKind,
    task: &str,
    front: Option<&[SweepPoint]>,
) -> Value {
    let mut v = result_json(spec, r);
    v["model"] = Value::from(model.name());
    v["task"] = Value::from(task);
    if let Some(points) = front {
        v["sweep"] = points
            .iter()
            .map(|p| match &p.outcome {
                Ok((params, logdet, _)) => json!({"budget": p.value, "logdet": logdet, "params": named(&spec.names, params)}),
                Err(e) => json!({"budget": p.value, "error": e}),
            })
            .collect();
    }
    v
}

fn named(names: &[&str], values: &[f64]) -> Value {
    Value::Object(
        names
            .iter()
            .zip(values)
            .map(|(n, v)| (n.to_string(), Value::from(*v)))
            .collect::<Map<_, _>>(),
    )
}

fn result_json(spec: &DesignSpec, r: &DesignResult) -> Value {
    let free: Vec<&str> = spec
        .names
        .iter()
        .zip(&spec.fixed)
        .filter(|(_, f)| f.is_none())
        .map(|(n, _)| *n)
        .collect();
    let o = &r.confidence_optimum;
    let verification: Vec<Value> = r
        .checks
        .iter()
        .map(|c| {
            let mut v = json!({"tool": c.label, "params": named(&spec.names, &c.params), "logdet": c.logdet});
            match &c.simulated {
                Ok(m) => {
                    v["task_error"] = Value::from(m.task_error);
                    v["free_energy"] = Value::from(m.free_energy);
                    v["task_error_perturbed"] = Value::from(m.task_error_perturbed);
                    v["sensitivity"] = Value::from(m.sensitivity);
                }
                Err(e) => v["error"] = Value::from(e.as_str()),
            }
            v
        })
        .collect();
    let mut random = json!({
        "requested": r.random.requested,
        "feasible": r.random.feasible,
        "drawn": r.random.drawn,
    });
    // No best at all is a missing key, not a null.
    if let Some(best) = r.random.top.first() {
        random["best_logdet"] = Value::from(best.1);
    }
    let optimum = Polytope::new(spec).full(&o.x);
    let mut v = json!({
        "objective": r.objective.name(),
        "params": named(&spec.names, &r.params),
        "logdet": r.logdet,
        "confidence_optimum": {"params": named(&spec.names, &optimum), "logdet": o.value},
        "gradient": named(&free, &o.gradient),
        "gradient_check": r.gradient_check,
        "kkt_residual": o.kkt_residual,
        "converged": o.converged(),
        "iterations": o.iterations,
        "start": o.start,
        "free_energy_simulations": r.free_energy_evaluations,
        "perturbation": spec.search.perturbation,
        "random": random,
        "verification": verification,
        "notes": r.confidence_note().into_iter().collect::<Vec<_>>(),
    });
    // Only for a predicted objective, so that the other objectives' output is unchanged.
    if let Some(p) = &r.predicted_optimum {
        let value = match r.objective {
            toolconf_model::inputs::design_file::DesignObjective::PredictedTaskError => {
                (-p.value).exp()
            }
            _ => -p.value,
        };
        v["predicted_optimum"] = json!({
            "value": value,
            "kkt_residual": p.kkt_residual,
            "converged": p.converged(),
            "iterations": p.iterations,
            "start": p.start,
        });
    }
    // No check at all (no random feasible tool to sample) is a missing key, not a null.
    if let Some(check) = &r.confidence_check {
        v["confidence_check"] = check.json();
    }
    v
}
