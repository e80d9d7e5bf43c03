//! Tool design by control confidence (`toolconf design`): which tool to build for a task, under
//! bounds, linear constraints and fixed parameters from a design file
//! ([`toolconf_model::inputs::design_file`]).
//!
//! Flow: the design file → the feasible polytope over the free parameters ([`polytope`]) → a
//! multi-start SQP on ln|Π^U| with the derived gradient ∂ln|Π^U|/∂p = tr((Π^U)⁻¹ ∂Π^U/∂p)
//! (generated `<task>_logdet_gradient`; [`solver`], QPs by Clarabel) → optionally ∫F dt by
//! simulation from there ([`free_energy`]) → the design beside the best of N random feasible
//! tools, simulated with and without a torque perturbation ΔT ([`verify`]). [`sweep`] traces
//! the confidence–budget trade-off; the report (`toolconf_report::design`) writes it down.
//!
//! Determinism: starts and random tools come from seeded ChaCha8 streams drawn sequentially;
//! the multi-start runs in start order; simulations run in parallel but are collected in input
//! order. The same file and seed give the same design on any number of threads.

pub mod free_energy;
pub mod json;
pub mod polytope;
pub mod predicted;
pub mod qp;
pub mod solver;
pub mod sweep;
pub mod verify;

use crate::rank::ModelTasks;
use toolconf_model::inputs::design_file::{DesignFileError, DesignObjective, DesignSpec};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::prediction::derivative::PredictedCost;
use toolconf_model::registry::{AnyTool, ModelKind};

use polytope::{FeasibleSampler, Polytope, Spread};
use solver::Optimum;
use verify::{RandomTools, ToolCheck};

/// Why a design could not be made: bad input (exit status 2, infeasible constraints included)
/// or a failed run (1).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DesignError {
    #[error("{0}")]
    Input(String),
    #[error("{0}")]
    Infeasible(String),
    #[error("{0}")]
    Failed(String),
}

impl From<DesignFileError> for DesignError {
    fn from(e: DesignFileError) -> Self {
        DesignError::Input(e.to_string())
    }
}

/// The model and task a design is for.
pub struct Setting<'a> {
    pub model: ModelKind,
    pub task: &'a TaskSpec,
    pub tasks: &'a ModelTasks,
}

impl<'a> Setting<'a> {
    /// A design of a `model` tool for `task`, bound to every model as `tasks`.
    pub fn new(model: ModelKind, task: &'a TaskSpec, tasks: &'a ModelTasks) -> Self {
        Self { model, task, tasks }
    }

    /// ln|Π^U| and its gradient over the free parameters at free parameters `x`.
    /// None where ln|Π^U| is undefined, or where its gradient is not finite (Π^U so nearly
    /// singular that the generated tr((Π^U)⁻¹ ∂Π^U/∂p) overflows): the search treats both alike.
    pub fn confidence(&self, polytope: &Polytope, x: &[f64]) -> Option<(f64, Vec<f64>)> {
        let tool = AnyTool::new(self.model, &polytope.full(x)).ok()?;
        let (value, gradient) = self.tasks.logdet_and_gradient(&tool).ok()?;
        let gradient: Vec<f64> = polytope.free.iter().map(|&k| gradient[k]).collect();
        (value.is_finite() && gradient.iter().all(|g| g.is_finite())).then_some((value, gradient))
    }
}

/// The confidence optimum over the feasible set, from the centre, `search.starts` seeded
/// random feasible starts, drawn uniformly in ln p ([`Spread::LogUniform`]) so that every
/// decade of a wide box is started from, and the box's feasible corners (ln|Π^U| grows as a tool
/// gets lighter and shorter, so its maxima are often there; where it is flat over decades, a
/// start inside never reaches them).
pub fn confidence_optimum(
    spec: &DesignSpec,
    setting: &Setting,
) -> Result<(Polytope, Optimum), DesignError> {
    let polytope = Polytope::new(spec);
    let starts = starts(spec, &polytope)?;
    let mut objective = |x: &[f64]| setting.confidence(&polytope, x);
    let optimum = solver::maximise(&polytope, &starts, &mut objective)
        .map_err(|f| polytope.solver_failed(&spec.file, "climbing ln|Π^U|", &f.reason, &f.tight))?
        .ok_or_else(|| {
            DesignError::Input(format!(
                "{}: ln|Π^U| is undefined at every start: for the tools there, the task's \
                 precisions leave Π^U not positive definite",
                spec.file
            ))
        })?;
    Ok((polytope, optimum))
}

/// The multi-start's starts: the centre, `search.starts` seeded random feasible starts (uniform
/// in ln p) and the box's feasible corners ([`confidence_optimum`] says why).
pub fn starts(spec: &DesignSpec, polytope: &Polytope) -> Result<Vec<Vec<f64>>, DesignError> {
    let mut starts = vec![polytope.centre(&spec.file)?];
    let mut sampler = FeasibleSampler::with_spread(polytope, spec.search.seed, Spread::LogUniform);
    while starts.len() <= spec.search.starts {
        match sampler.next_point(100_000) {
            Some(x) => starts.push(x),
            None => break,
        }
    }
    starts.extend(polytope.feasible_corners());
    Ok(starts)
}

/// Finite differences of ln|Π^U| at the optimum, for the report's gradient check: the largest
/// |derived − difference| / max(|derived|, 1) over the free parameters.
///
/// The step is h = 10⁻⁶·s with s the parameter's scale: |x| where its box excludes 0 (then
/// |x| ≥ the nearer bound > 0), else max(|x|, the box's width), so that a centre of mass at or
/// a rounding error away from 0 is not stepped by nothing. Inside the box the difference is
/// central; where x ± h leaves it (a parameter at its bound, where the model may not be
/// defined beyond) it is one-sided into the box, of the same second order:
/// f′(x) ≈ (−3f(x) + 4f(x + σh) − f(x + 2σh)) / (2σh), σ = ±1.
pub fn gradient_check(setting: &Setting, polytope: &Polytope, optimum: &Optimum) -> f64 {
    let mut worst = 0.0_f64;
    for j in 0..optimum.x.len() {
        let (x, lo, hi) = (optimum.x[j], polytope.lo[j], polytope.hi[j]);
        let scale = if lo > 0.0 || hi < 0.0 {
            x.abs()
        } else {
            x.abs().max(hi - lo)
        };
        let h = 1e-6 * scale;
        let at = |delta: f64| {
            let mut x = optimum.x.clone();
            x[j] += delta;
            setting.confidence(polytope, &x).map(|v| v.0)
        };
        let difference = if x - h >= lo && x + h <= hi || x - 2.0 * h < lo && x + 2.0 * h > hi {
            at(h)
                .zip(at(-h))
                .map(|(plus, minus)| (plus - minus) / (2.0 * h))
        } else {
            let sigma = if x - h < lo { 1.0 } else { -1.0 };
            let one_sided =
                |f0: f64, f1: f64, f2: f64| (-3.0 * f0 + 4.0 * f1 - f2) / (2.0 * sigma * h);
            at(0.0)
                .zip(at(sigma * h))
                .zip(at(2.0 * sigma * h))
                .map(|((f0, f1), f2)| one_sided(f0, f1, f2))
        };
        if let Some(fd) = difference {
            let derived = optimum.gradient[j];
            worst = worst.max((derived - fd).abs() / derived.abs().max(1.0));
        }
    }
    worst
}

/// Everything `toolconf design` shows.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignResult {
    pub objective: DesignObjective,
    /// The designed tool's full parameters, in the model's order.
    pub params: Vec<f64>,
    pub logdet: f64,
    /// The confidence optimum (the design itself when the objective is confidence).
    pub confidence_optimum: Optimum,
    pub gradient_check: f64,
    /// Simulations of the ∫F search (0 for the confidence objective).
    pub free_energy_evaluations: usize,
    /// The predicted cost's optimum (the design) for a predicted objective: its value is
    /// −ln(predicted task error) or −(predicted ∫F dt) ([`predicted::objective`]).
    pub predicted_optimum: Option<Optimum>,
    pub random: RandomTools,
    /// The design first, then the most confident random tools.
    pub checks: Vec<ToolCheck>,
    /// Claim (a) on the feasible set: does confidence predict the task error there?
    pub confidence_check: Option<crate::evaluation::ConfidenceCheck>,
}

impl DesignResult {
    /// The line `design` prints when confidence does not predict the task error here.
    pub fn confidence_note(&self) -> Option<String> {
        self.confidence_check.as_ref()?.note(
            "the most confident design need not do the task best; compare by simulation \
             (objective = \"free_energy\", or the verification's task errors)",
        )
    }
}

/// Designs a tool: the optimum, then the verification against random feasible tools.
pub fn design(spec: &DesignSpec, setting: &Setting) -> Result<DesignResult, DesignError> {
    design_with_progress(spec, setting, &mut |_| {})
}

/// [`design`], telling `sampling` how the random comparison goes as it draws
/// ([`verify::random_tools`]).
pub fn design_with_progress(
    spec: &DesignSpec,
    setting: &Setting,
    sampling: &mut dyn FnMut(&verify::Sampling),
) -> Result<DesignResult, DesignError> {
    let (polytope, optimum) = confidence_optimum(spec, setting)?;
    let check = gradient_check(setting, &polytope, &optimum);
    let mut predicted_optimum = None;
    let (x, logdet, evaluations) = match spec.objective {
        DesignObjective::Confidence => (optimum.x.clone(), optimum.value, 0),
        DesignObjective::PredictedTaskError | DesignObjective::PredictedFreeEnergy => {
            let which = match spec.objective {
                DesignObjective::PredictedTaskError => PredictedCost::TaskError,
                _ => PredictedCost::FreeEnergy,
            };
            // The confidence optimum is one more start: the design is never worse by the
            // prediction than the confidence design.
            let mut from = starts(spec, &polytope)?;
            from.push(optimum.x.clone());
            let found = predicted::optimum(spec, setting, &polytope, &from, which)?;
            let Some((logdet, _)) = setting.confidence(&polytope, &found.x) else {
                return Err(DesignError::Failed(format!(
                    "{}: ln|Π^U| is undefined at the predicted optimum {}",
                    spec.file,
                    parameters_text(&spec.names, &polytope.full(&found.x))
                )));
            };
            let x = found.x.clone();
            predicted_optimum = Some(found);
            (x, logdet, 0)
        }
        DesignObjective::FreeEnergy => {
            let found = free_energy::minimise(&polytope, setting, &optimum.x)?;
            let Some((logdet, _)) = setting.confidence(&polytope, &found.x) else {
                return Err(DesignError::Failed(format!(
                    "{}: ln|Π^U| is undefined at the ∫F dt optimum {}",
                    spec.file,
                    parameters_text(&spec.names, &polytope.full(&found.x))
                )));
            };
            (found.x, logdet, found.simulations)
        }
    };
    let s = &spec.search;
    let random = verify::random_tools(
        &polytope,
        setting.model,
        setting.tasks,
        (s.samples, s.simulate, s.validation),
        s.seed ^ 0x9e37_79b9_7f4a_7c15,
        sampling,
    );
    let mut tools = vec![("design".to_string(), polytope.full(&x), logdet)];
    for (k, (xr, l)) in random.top.iter().enumerate().take(s.simulate) {
        tools.push((format!("random #{}", k + 1), polytope.full(xr), *l));
    }
    let perturbed = ModelTasks::new(&verify::perturbed(setting.task, s.perturbation));
    let checks = verify::check_tools(&tools, setting.model, setting.tasks, &perturbed);
    let confidence_check = (!random.sample.is_empty())
        .then(|| verify::confidence_check(&polytope, setting.model, setting.tasks, &random.sample));
    Ok(DesignResult {
        objective: spec.objective,
        params: polytope.full(&x),
        logdet,
        confidence_optimum: optimum,
        gradient_check: check,
        free_energy_evaluations: evaluations,
        predicted_optimum,
        random,
        checks,
        confidence_check,
    })
}

/// `m1=0.1 m2=0.4 …`.
pub fn parameters_text(names: &[&str], params: &[f64]) -> String {
    names
        .iter()
        .zip(params)
        .map(|(n, v)| format!("{n}={v:.6}"))
        .collect::<Vec<_>>()
        .join(" ")
}

impl DesignResult {
    /// Every number the design reports finite ([`toolconf_model::validate::finite_output`]), for the
    /// command line and the Python package alike.
    pub fn check_finite(&self, names: &[&str]) -> Result<(), toolconf_model::Error> {
        let o = &self.confidence_optimum;
        toolconf_model::validate::finite_output(
            &format!("the design {}", parameters_text(names, &self.params)),
            "ln|Π^U|, the KKT residual or the gradient check",
            [self.logdet, o.value, o.kkt_residual, self.gradient_check],
        )
    }
}
