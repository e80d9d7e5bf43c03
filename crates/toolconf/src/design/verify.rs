//! The design beside the best of N random feasible tools: every random tool's ln|Π^U| in closed
//! form, the most confident few simulated, and for each simulated tool the task error, ∫F dt and
//! the sensitivity to a constant torque ΔT, |task error under ΔT − task error| (as Fig. 4).

use rayon::prelude::*;

use crate::rank::ModelTasks;
use toolconf_model::inputs::task_file::{PerJoint, TaskSpec};
use toolconf_model::registry::{AnyTool, ModelKind};

use super::polytope::{FeasibleSampler, Polytope};

/// One tool's row of the comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolCheck {
    /// "design" or "random #k" (k-th most confident of the random tools).
    pub label: String,
    pub params: Vec<f64>,
    pub logdet: f64,
    /// Task error, ∫F dt, task error under ΔT and the sensitivity, or the episode's error.
    pub simulated: Result<Simulated, String>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Simulated {
    pub task_error: f64,
    pub free_energy: f64,
    pub task_error_perturbed: f64,
    pub sensitivity: f64,
}

/// The random comparison: how many were drawn and kept, and the most confident tools.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomTools {
    pub requested: usize,
    pub feasible: usize,
    pub drawn: u64,
    /// (free parameters, ln|Π^U|), most confident first (ties: the earlier draw).
    pub top: Vec<(Vec<f64>, f64)>,
    /// The first feasible tools with a confidence, in draw order: a uniform sample of the
    /// feasible set, simulated to check claim (a) there ([`crate::evaluation::check`]).
    pub sample: Vec<(Vec<f64>, f64)>,
}

/// The most draws from the box the random comparison makes (about 2 s): a thin feasible set
/// with `samples = 10⁷` stops there, with the tools found, instead of drawing for minutes.
pub const MAX_DRAWS: u64 = 100_000_000;

/// How far the random comparison has got, as [`random_tools`] reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    pub feasible: usize,
    pub requested: usize,
    pub drawn: u64,
    pub max_draws: u64,
}

/// Draws up to `n` feasible tools (rejection from the box, at most 1000·n and [`MAX_DRAWS`]
/// draws) and keeps the `keep` most confident, telling `progress` every 2¹⁶ draws. Sequential
/// and seeded: the same tools on every machine.
pub fn random_tools(
    polytope: &Polytope,
    model: ModelKind,
    tasks: &ModelTasks,
    (n, keep, sample): (usize, usize, usize),
    seed: u64,
    progress: &mut dyn FnMut(&Sampling),
) -> RandomTools {
    let max_draws = (1000 * n.max(1) as u64).min(MAX_DRAWS);
    let mut r = random_tools_within(
        polytope,
        model,
        tasks,
        (n, keep.max(sample)),
        seed,
        max_draws,
        progress,
    );
    r.top.truncate(keep.max(1));
    r.sample.truncate(sample);
    r
}

/// [`random_tools`] with at most `max_draws` draws; `(n, keep)` as there.
fn random_tools_within(
    polytope: &Polytope,
    model: ModelKind,
    tasks: &ModelTasks,
    (n, keep): (usize, usize),
    seed: u64,
    max_draws: u64,
    progress: &mut dyn FnMut(&Sampling),
) -> RandomTools {
    let mut sampler = FeasibleSampler::new(polytope, seed);
    let mut top: Vec<(Vec<f64>, f64)> = Vec::with_capacity(keep + 1);
    let mut sample: Vec<(Vec<f64>, f64)> = Vec::with_capacity(keep);
    let mut feasible = 0;
    let mut next_report = 0;
    while feasible < n {
        let batch_end = (next_report + (1 << 16)).min(max_draws);
        let Some(x) = sampler.next_point(batch_end) else {
            if sampler.drawn >= max_draws {
                break;
            }
            next_report = sampler.drawn;
            progress(&Sampling {
                feasible,
                requested: n,
                drawn: sampler.drawn,
                max_draws,
            });
            continue;
        };
        feasible += 1;
        let Ok(tool) = AnyTool::new(model, &polytope.full(&x)) else {
            continue;
        };
        let Ok(logdet) = tasks.logdet(&tool) else {
            continue;
        };
        if sample.len() < keep {
            sample.push((x.clone(), logdet));
        }
        let at = top.partition_point(|(_, v)| *v >= logdet);
        if at < keep.max(1) {
            top.insert(at, (x, logdet));
            top.truncate(keep.max(1));
        }
    }
    RandomTools {
        requested: n,
        feasible,
        drawn: sampler.drawn,
        top,
        sample,
    }
}

/// The task with a constant torque ΔT added on every joint.
pub fn perturbed(spec: &TaskSpec, delta: f64) -> TaskSpec {
    let mut s = spec.clone();
    s.episode.perturbation = Some(match &spec.episode.perturbation {
        None => PerJoint::All(delta),
        Some(PerJoint::All(v)) => PerJoint::All(v + delta),
        Some(PerJoint::Each(v)) => PerJoint::Each(v.iter().map(|x| x + delta).collect()),
    });
    s
}

/// Simulates each tool on the task and under ΔT, in parallel, results in input order.
pub fn check_tools(
    tools: &[(String, Vec<f64>, f64)],
    model: ModelKind,
    nominal: &ModelTasks,
    under_perturbation: &ModelTasks,
) -> Vec<ToolCheck> {
    tools
        .par_iter()
        .map(|(label, params, logdet)| ToolCheck {
            label: label.clone(),
            params: params.clone(),
            logdet: *logdet,
            simulated: simulate(model, params, nominal, under_perturbation),
        })
        .collect()
}

/// Claim (a) on the random feasible tools `sample` (free parameters, ln|Π^U|): each simulated
/// on the task, in parallel.
pub fn confidence_check(
    polytope: &Polytope,
    model: ModelKind,
    tasks: &ModelTasks,
    sample: &[(Vec<f64>, f64)],
) -> crate::evaluation::ConfidenceCheck {
    let points: Vec<(f64, f64)> = sample
        .par_iter()
        .filter_map(|(x, logdet)| {
            let tool = AnyTool::new(model, &polytope.full(x)).ok()?;
            Some((*logdet, tasks.simulate(&tool).ok()?.task_error))
        })
        .collect();
    crate::evaluation::ConfidenceCheck::compute(
        &points,
        sample.len(),
        sample.len(),
        "from the design's feasible set",
    )
}

fn simulate(
    model: ModelKind,
    params: &[f64],
    nominal: &ModelTasks,
    under_perturbation: &ModelTasks,
) -> Result<Simulated, String> {
    let tool = AnyTool::new(model, params).map_err(|e| e.to_string())?;
    let m = nominal.simulate(&tool).map_err(|e| e.to_string())?;
    let p = under_perturbation
        .simulate(&tool)
        .map_err(|e| format!("under ΔT: {e}"))?;
    Ok(Simulated {
        task_error: m.task_error,
        free_energy: m.free_energy,
        task_error_perturbed: p.task_error,
        sensitivity: (p.task_error - m.task_error).abs(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use toolconf_model::inputs::design_file::DesignSpec;
    use toolconf_model::inputs::task_file::TaskSpec;
    use toolconf_model::TaskKind;

    /// A feasible set of about 10⁻¹⁴ of its box: the draws stop at their budget, with what
    /// they found, and progress heard of them every 2¹⁶ draws.
    #[test]
    fn a_thin_feasible_set_stops_at_the_draw_budget() {
        let text = "constraints = [\"m1 + m2 <= 0.2000001\", \"m1 + m2 >= 0.2\", \
                    \"l1 - l2 <= 0.0000001\", \"l1 - l2 >= 0\"]\n[bounds]\nm1 = [0.1, 0.6]\n\
                    m2 = [0.1, 0.6]\nl1 = [0.1, 0.6]\nl2 = [0.1, 0.6]\n";
        let spec = DesignSpec::parse(text, "thin.toml", ModelKind::Arm2).unwrap();
        let polytope = Polytope::new(&spec);
        let tasks = ModelTasks::new(&TaskSpec::builtin(TaskKind::Velocity));
        let mut heard = Vec::new();
        let r = random_tools_within(
            &polytope,
            ModelKind::Arm2,
            &tasks,
            (10_000_000, 5),
            1,
            300_000,
            &mut |s| heard.push(s.drawn),
        );
        assert_eq!((r.requested, r.feasible, r.drawn), (10_000_000, 0, 300_000));
        assert_eq!(heard, [65_536, 131_072, 196_608, 262_144]);
    }
}
