//! The design objectives `predicted_task_error` and `predicted_free_energy`: the episode's cost
//! as the closed loop linearised at the equilibrium predicts it ([`toolconf_model::prediction`]), and its
//! gradient over the tool's parameters, for the SQP ([`super::solver`]) to climb.
//!
//! The prediction is a smooth function of the linear system it steps ([`LinearSystem`]: M, c,
//! z_0, each term's C_i, o_i − goal_i and P_i, ln|Π^U|), and that system of the parameters. The
//! gradient is the chain of both:
//!
//! - ∂(system)/∂p_j by central differences of the linearisation (h = ε^{1/3}·max(|p_j|, 10⁻³)):
//!   the generated code has A and B but not their derivatives over the parameters;
//! - the prediction's derivative in the direction ∂(system)/∂p_j exactly, by forward
//!   propagation along the grid ([`toolconf_model::prediction::derivative`]).
//!
//! Checked against central differences of the whole prediction (the tests below).

use super::polytope::Polytope;
use super::solver::{self, Optimum};
use super::{DesignError, Setting};
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::prediction::derivative::{
    costs_and_derivatives, Costs, DenseSystem, PredictedCost,
};
use toolconf_model::registry::AnyTool;

/// The central-difference step of parameter p: ε^{1/3}·max(|p|, 10⁻³), the step that balances
/// the difference's truncation and rounding errors.
pub fn step(p: f64) -> f64 {
    f64::EPSILON.cbrt() * p.abs().max(1e-3)
}

/// What the SQP maximises for `which` at free parameters `x`, and its gradient: −ln(predicted
/// task error) (scale-free, as ln|Π^U| is; the task error is a sum of squares, positive
/// wherever the tool misses the goal somewhere on the grid) or −(predicted ∫F dt). `None` where
/// there is no prediction (an unstable linearised loop) or it is not finite.
pub fn objective(
    setting: &Setting,
    polytope: &Polytope,
    x: &[f64],
    which: PredictedCost,
) -> Option<(f64, Vec<f64>)> {
    let (costs, derivatives) = costs_and_gradient(setting, &polytope.full(x), &polytope.free)?;
    let value = costs.get(which);
    let gradient: Vec<f64> = derivatives.iter().map(|d| d.get(which)).collect();
    let (phi, dphi): (f64, Vec<f64>) = match which {
        PredictedCost::TaskError if value > 0.0 => {
            (-value.ln(), gradient.iter().map(|g| -g / value).collect())
        }
        PredictedCost::TaskError => return None,
        PredictedCost::FreeEnergy => (-value, gradient.iter().map(|g| -g).collect()),
    };
    (phi.is_finite() && dphi.iter().all(|g| g.is_finite())).then_some((phi, dphi))
}

/// The predicted costs of the tool with full parameters `params` and their derivatives over the
/// parameters `free` (indices into `params`); `None` without a prediction.
pub fn costs_and_gradient(
    setting: &Setting,
    params: &[f64],
    free: &[usize],
) -> Option<(Costs, Vec<Costs>)> {
    let system = |p: &[f64]| -> Option<DenseSystem> {
        let tool = AnyTool::new(setting.model, p).ok()?;
        Some(DenseSystem::new(&setting.tasks.linear_system(&tool).ok()?))
    };
    // The prediction's own checks (stability above all) decide whether there is one.
    let tool = AnyTool::new(setting.model, params).ok()?;
    setting.tasks.predict(&tool).ok()?;
    let at = system(params)?;
    let directions: Vec<DenseSystem> = free
        .iter()
        .map(|&k| {
            let h = step(params[k]);
            let mut plus = params.to_vec();
            let mut minus = params.to_vec();
            plus[k] += h;
            minus[k] -= h;
            Some(DenseSystem::difference(
                &system(&plus)?,
                &system(&minus)?,
                2.0 * h,
            ))
        })
        .collect::<Option<_>>()?;
    Some(costs_and_derivatives(&at, &directions))
}

/// The predicted cost's optimum over the feasible set: the SQP on [`objective`] from `starts`.
pub fn optimum(
    spec: &DesignSpec,
    setting: &Setting,
    polytope: &Polytope,
    starts: &[Vec<f64>],
    which: PredictedCost,
) -> Result<Optimum, DesignError> {
    let mut objective = |x: &[f64]| objective(setting, polytope, x, which);
    let what = match which {
        PredictedCost::TaskError => "the predicted task error",
        PredictedCost::FreeEnergy => "the predicted ∫F dt",
    };
    solver::maximise(polytope, starts, &mut objective)
        .map_err(|f| {
            polytope.solver_failed(
                &spec.file,
                &format!("descending {what}"),
                &f.reason,
                &f.tight,
            )
        })?
        .ok_or_else(|| {
            DesignError::Input(format!(
                "{}: {what} is undefined at every start: the closed loop linearised at the \
                 equilibrium is unstable for the tools there",
                spec.file
            ))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::polytope::Polytope;
    use crate::rank::ModelTasks;
    use toolconf_model::inputs::design_file::DesignSpec;
    use toolconf_model::inputs::task_file::TaskSpec;
    use toolconf_model::registry::ModelKind;

    /// The gradient of both predicted costs equals central differences of the whole prediction
    /// (`predict`, the library's own code path) within 1e-5 relative, on the Panda's touch task
    /// at three tools of its design file's box.
    #[test]
    fn the_gradient_equals_central_differences_of_the_prediction() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
        let task = TaskSpec::from_file(std::path::Path::new(&format!(
            "{root}/tasks/panda_touch_point.toml"
        )))
        .unwrap();
        let tasks = ModelTasks::new(&task);
        let setting = Setting::new(ModelKind::Panda, &task, &tasks);
        let spec = DesignSpec::from_file(
            std::path::Path::new(&format!("{root}/design/panda_tip_length.toml")),
            ModelKind::Panda,
        )
        .unwrap();
        let polytope = Polytope::new(&spec);
        let predict = |p: &[f64]| {
            let tool = AnyTool::new(ModelKind::Panda, p).unwrap();
            let v = tasks.predict(&tool).unwrap();
            Costs {
                task_error: v.task_error,
                free_energy: v.free_energy,
            }
        };
        for x in [[1.0, 0.05, 0.2], [0.6, 0.0, 0.35], [1.8, 0.15, 0.31]] {
            let params = polytope.full(&x);
            let (costs, gradient) = costs_and_gradient(&setting, &params, &polytope.free).unwrap();
            let direct = predict(&params);
            assert!((costs.task_error / direct.task_error - 1.0).abs() < 1e-10);
            assert!((costs.free_energy / direct.free_energy - 1.0).abs() < 1e-10);
            for (j, &k) in polytope.free.iter().enumerate() {
                // Fourth-order central differences with a wide step: the prediction's own
                // rounding (its Padé exponential's degree switches with |M h|) makes narrow
                // differences noisy at 1e-5.
                let h = 1e-3 * params[k].abs().max(1e-2);
                let at = |delta: f64| {
                    let mut p = params.clone();
                    p[k] += delta;
                    predict(&p)
                };
                let (p1, m1, p2, m2) = (at(h), at(-h), at(2.0 * h), at(-2.0 * h));
                for which in [PredictedCost::TaskError, PredictedCost::FreeEnergy] {
                    let v = |c: &Costs| c.get(which);
                    let fd = (8.0 * (v(&p1) - v(&m1)) - (v(&p2) - v(&m2))) / (12.0 * h);
                    let g = gradient[j].get(which);
                    let scale = fd.abs().max(1e-6 * costs.get(which).abs());
                    assert!(
                        (g - fd).abs() <= 1e-5 * scale,
                        "{which:?} p{k} at {x:?}: gradient {g:e}, central differences {fd:e}"
                    );
                }
            }
        }
    }
}
