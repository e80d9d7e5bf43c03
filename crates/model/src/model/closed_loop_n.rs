//! The closed loop and episode for any [`ArmModel`], around the core's controller
//! ([`ActiveInferenceN`]): the one implementation, which `crate::closed_loop` names for the
//! paper's arm.

use nalgebra::{SMatrix, SVector};

use super::{ActiveInferenceN, ArmModel, TaskN, ToolN};
use crate::Error;
use toolconf_core::{
    observe_tool, reads_tip, tip_parameters, ObservationN, TipKinematics, TipObserver,
};
use toolconf_generated::{Read, Term, TERMS};
use toolconf_integrators::{
    solve_grid_with_jacobian, uniform_grid, IntegrationError, Method, Options as IntegratorOptions,
    Stats,
};

/// A grid state whose magnitude passes this is a diverging simulation, not a result.
pub(crate) const DIVERGENCE_BOUND: f64 = crate::validate::STATE_BOUND;

/// Compile-time check of the sizes: NX = 2N and NZ = NX + N.
struct Dims<const N: usize, const NX: usize, const NZ: usize>;

impl<const N: usize, const NX: usize, const NZ: usize> Dims<N, NX, NZ> {
    const CHECK: () = assert!(
        NX == 2 * N && NZ == NX + N,
        "model sizes must satisfy NX == 2N and NZ == NX + N"
    );
}

/// Ż = [f_P(X, U + ΔT); −γ ∂F/∂U], the object the integrators see: the controller uses model
/// `M`, the simulated world (plant) is model `P` with the same tool parameters (`P = M`
/// normally; `M = Arm2, P = Arm2Exact` is [`crate::closed_loop::Plant::Exact`]). The plant is a
/// type so that the right-hand side, evaluated at every integrator stage, does not branch on it.
#[derive(Debug, Clone, Copy)]
pub struct ClosedLoopN<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
where
    P: ArmModel<N, NX, NP, NZ>,
{
    /// The plant's parameter-only factors, computed once per tool rather than once per call.
    dynamics: P::DynamicsCoefficients,
    jacobian: P::JacobianCoefficients,
    pub controller: ActiveInferenceN<N>,
    perturbation: SVector<f64, N>,
    /// On a task that reads the tool's tip, the tool's parameters for y(q; p): then every
    /// right-hand side evaluates y(q), J(q), and J̇ q̇ on a tip acceleration task
    /// ([`tip_parameters`]).
    tip: Option<TipObserver<NP>>,
}

impl<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    ClosedLoopN<P, N, NX, NP, NZ>
where
    P: ArmModel<N, NX, NP, NZ>,
{
    /// The closed loop of `tool` (controller model `M`) on plant `P`, with the same ΔT on every
    /// joint.
    pub fn new<M>(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
        perturbation: f64,
    ) -> Result<Self, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        Self::with_perturbation(tool, task, learning_rate, &SVector::repeat(perturbation))
    }

    /// The closed loop with a constant torque perturbation ΔT_i of its own on each joint.
    pub fn with_perturbation<M>(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
        perturbation: &SVector<f64, N>,
    ) -> Result<Self, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        #[allow(clippy::let_unit_value)]
        let () = Dims::<N, NX, NZ>::CHECK;
        if let Some(&value) = perturbation.iter().find(|v| !v.is_finite()) {
            return Err(Error::InvalidOption {
                name: "perturbation dT",
                value,
            });
        }
        let params = tool.params();
        // The plant's tip, as the plant is what the controller measures.
        let tip = tip_parameters::<P, N, NX, NP, NZ>(&params, task.kind)?;
        Ok(Self {
            dynamics: P::dynamics_coefficients(&params),
            jacobian: P::jacobian_coefficients(&params),
            controller: ActiveInferenceN::new(tool, task, learning_rate)?,
            perturbation: *perturbation,
            tip,
        })
    }

    /// Ż and the terms the controller observes (the plant's θ̈ among them, and the tip's y, ẏ
    /// on a tip task).
    // Always: LLVM had stopped inlining it into the episode, whose integrator calls it ~1000
    // times; 20 000 task-1 episodes took 1.17× the time they took when it was (perf, 040a3cc).
    #[inline(always)]
    pub fn rhs_and_observation(&self, z: &SVector<f64, NZ>) -> (SVector<f64, NZ>, ObservationN<N>) {
        let x = z.fixed_rows::<NX>(0).into_owned();
        let u = z.fixed_rows::<N>(NX).into_owned();
        let x_dot = P::dynamics_with(&x, &(u + self.perturbation), &self.dynamics);
        let observed = observe_tool::<P, N, NX, NP, NZ>(&x, &x_dot, &u, self.tip.as_ref());
        let u_dot = self.controller.control_rate(&observed);
        let mut z_dot = SVector::<f64, NZ>::zeros();
        z_dot.fixed_rows_mut::<NX>(0).copy_from(&x_dot);
        z_dot.fixed_rows_mut::<N>(NX).copy_from(&u_dot);
        (z_dot, observed)
    }

    /// Ż.
    #[inline]
    pub fn rhs(&self, z: &SVector<f64, NZ>) -> SVector<f64, NZ> {
        self.rhs_and_observation(z).0
    }

    /// ∂Ż/∂Z, from the generated Jacobian of the plant (∂f/∂X, ∂f/∂U) and the controller's
    /// constant gains γK: U̇ = −γ Σ K (term − goal), where a term read from X has ∂/∂X its
    /// selection ([I O] for θ), one read from Ẋ = f(X, U + ΔT) the rows of ∂f/∂X and ∂f/∂U
    /// (θ̈), and U itself ∂/∂U = I.
    #[inline]
    pub fn jacobian(&self, z: &SVector<f64, NZ>) -> SMatrix<f64, NZ, NZ> {
        let x = z.fixed_rows::<NX>(0).into_owned();
        let u = z.fixed_rows::<N>(NX).into_owned();
        let (f_x, f_u) = P::dynamics_jacobian_with(&x, &(u + self.perturbation), &self.jacobian);
        let gains = self.controller.scaled_gains();
        let mut j = SMatrix::<f64, NZ, NZ>::zeros();
        j.fixed_view_mut::<NX, NX>(0, 0).copy_from(&f_x);
        j.fixed_view_mut::<NX, N>(0, NX).copy_from(&f_u);
        // Terms read from Ẋ first, each negated as it is added (no zero to subtract from).
        let (mut du_dx, mut du_du) = (None::<SMatrix<f64, N, NX>>, None::<SMatrix<f64, N, N>>);
        for term in Term::ALL {
            if let Read::StateRate { block } = term.read() {
                let k = gains[term.index()];
                let (kx, ku) = (
                    k * f_x.fixed_rows::<N>(block * N),
                    k * f_u.fixed_rows::<N>(block * N),
                );
                du_dx = Some(du_dx.map_or(-kx, |a| a - kx));
                du_du = Some(du_du.map_or(-ku, |a| a - ku));
            }
        }
        let mut du_dx = du_dx.unwrap_or_else(SMatrix::zeros);
        let mut du_du = du_du.unwrap_or_else(SMatrix::zeros);
        for term in Term::ALL {
            let k = gains[term.index()];
            match term.read() {
                Read::State { block } => {
                    let mut columns = du_dx.fixed_view_mut::<N, N>(0, block * N);
                    columns -= k;
                }
                Read::Control => du_du -= k,
                Read::StateRate { .. } | Read::Tip { .. } => {}
            }
        }
        if let Some(tip) = &self.tip {
            // ÿ reads the plant's q̈ = f(X, U + ΔT), its lower rows.
            let q_ddot = tip.acceleration.then(|| {
                let f = P::dynamics_with(&x, &(u + self.perturbation), &self.dynamics);
                f.fixed_rows::<N>(N).into_owned()
            });
            let plant = (&f_x, &f_u, q_ddot);
            subtract_tip_gains::<P, N, NX, NP, NZ>(tip, &x, plant, &gains, &mut du_dx, &mut du_du);
        }
        j.fixed_view_mut::<N, NX>(NX, 0).copy_from(&du_dx);
        j.fixed_view_mut::<N, N>(NX, NX).copy_from(&du_du);
        j
    }
}

/// The tip terms' part of ∂U̇/∂X and ∂U̇/∂U for the tool `tip`: y = y(q) has ∂y/∂q = J;
/// ẏ = J(q) q̇ has ∂ẏ/∂q̇ = J and ∂ẏ/∂q = J̇ = Σ_k ∂J/∂q_k q̇_k (column k of ∂(J q̇)/∂q is
/// Σ_j ∂²y/∂q_k∂q_j q̇_j, and the Hessian of y is symmetric), the directional derivative of J
/// along q̇; ÿ = J(q) q̈ + J̇ q̇ with q̈ = f(X, U) has J times f's lower rows, plus ∂(J a +
/// J̇ q̇)/∂q at a = q̈ held, plus ∂(J̇ q̇)/∂q̇. The tip's second derivatives are not generated:
/// they are central differences of the generated J and J̇ q̇, with steps of 1e-5 rad in q (an
/// error ~1e-10 relative) and exact in q̇ (J̇ q̇ is quadratic in q̇). This matrix steers the stiff
/// integrator's stages; the right-hand side itself is exact.
fn subtract_tip_gains<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tip: &TipObserver<NP>,
    x: &SVector<f64, NX>,
    (f_x, f_u, q_ddot): (
        &SMatrix<f64, NX, NX>,
        &SMatrix<f64, NX, N>,
        Option<SVector<f64, N>>,
    ),
    gains: &[SMatrix<f64, N, N>; TERMS],
    du_dx: &mut SMatrix<f64, N, NX>,
    du_du: &mut SMatrix<f64, N, N>,
) where
    P: ArmModel<N, NX, NP, NZ>,
{
    let p = &tip.params;
    let q = x.fixed_rows::<N>(0).into_owned();
    let q_dot = x.fixed_rows::<N>(N).into_owned();
    let Some(j) = TipKinematics::of::<P, NX, NP, NZ>(&q, p).map(|t| t.padded_jacobian()) else {
        return;
    };
    for term in Term::ALL {
        let k = gains[term.index()];
        // A term the task does not use has no gain: no difference quotient to take for it.
        if k.iter().all(|v| *v == 0.0) {
            continue;
        }
        match (term.read(), q_ddot) {
            (Read::Tip { order: 0 }, _) => {
                let mut positions = du_dx.fixed_view_mut::<N, N>(0, 0);
                positions -= k * j;
            }
            (Read::Tip { order: 1 }, _) => {
                let mut rates = du_dx.fixed_view_mut::<N, N>(0, N);
                rates -= k * j;
                let mut positions = du_dx.fixed_view_mut::<N, N>(0, 0);
                positions -= k * jacobian_rate::<P, N, NX, NP, NZ>(p, &q, &q_dot);
            }
            (Read::Tip { .. }, Some(a)) => {
                let kj = k * j;
                *du_dx -= kj * f_x.fixed_rows::<N>(N);
                *du_du -= kj * f_u.fixed_rows::<N>(N);
                let (d_q, d_q_dot) = acceleration_geometry::<P, N, NX, NP, NZ>(p, &q, &q_dot, &a);
                let mut positions = du_dx.fixed_view_mut::<N, N>(0, 0);
                positions -= k * d_q;
                let mut rates = du_dx.fixed_view_mut::<N, N>(0, N);
                rates -= k * d_q_dot;
            }
            _ => {}
        }
    }
}

/// J̇ = ∂(J q̇)/∂q, padded: a central difference of the generated J along q̇ (zero at rest),
/// its step moving q by 1e-5 rad at most.
fn jacobian_rate<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    p: &SVector<f64, NP>,
    q: &SVector<f64, N>,
    q_dot: &SVector<f64, N>,
) -> SMatrix<f64, N, N>
where
    P: ArmModel<N, NX, NP, NZ>,
{
    let jacobian =
        |q: &SVector<f64, N>| TipKinematics::of::<P, NX, NP, NZ>(q, p).map(|t| t.padded_jacobian());
    let speed = q_dot.amax();
    let step = (speed > 0.0).then(|| 1e-5 / speed);
    step.and_then(|h| {
        let (ahead, behind) = (jacobian(&(q + q_dot * h))?, jacobian(&(q - q_dot * h))?);
        Some((ahead - behind) / (2.0 * h))
    })
    .unwrap_or_else(SMatrix::zeros)
}

/// The geometric part of ∂ÿ/∂X, padded: ∂(J(q) a + J̇ q̇)/∂q at the joint acceleration `a` held,
/// by central differences of 1e-5 rad per joint, and ∂(J̇ q̇)/∂q̇, by central differences that are
/// exact up to rounding (J̇ q̇ is a quadratic form in q̇).
fn acceleration_geometry<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    p: &SVector<f64, NP>,
    q: &SVector<f64, N>,
    q_dot: &SVector<f64, N>,
    a: &SVector<f64, N>,
) -> (SMatrix<f64, N, N>, SMatrix<f64, N, N>)
where
    P: ArmModel<N, NX, NP, NZ>,
{
    let tip = |q: &SVector<f64, N>, q_dot: &SVector<f64, N>| {
        let t =
            TipKinematics::of::<P, NX, NP, NZ>(q, p)?.with_bias::<P, NX, NP, NZ>(q, q_dot, p)?;
        Some((t.pad(&(t.jacobian * a)), t.pad(&t.bias?)))
    };
    let difference = |column: &dyn Fn(usize, f64) -> Option<SVector<f64, N>>, h: f64| {
        let mut d = SMatrix::<f64, N, N>::zeros();
        for k in 0..N {
            if let (Some(ahead), Some(behind)) = (column(k, h), column(k, -h)) {
                d.set_column(k, &((ahead - behind) / (2.0 * h)));
            }
        }
        d
    };
    let unit = |k: usize, h: f64| SVector::<f64, N>::from_fn(|i, _| if i == k { h } else { 0.0 });
    let d_q = difference(
        &|k, h| tip(&(q + unit(k, h)), q_dot).map(|(ja, bias)| ja + bias),
        1e-5,
    );
    let d_q_dot = difference(
        &|k, h| tip(q, &(q_dot + unit(k, h))).map(|(_, bias)| bias),
        q_dot.amax().max(1.0),
    );
    (d_q, d_q_dot)
}

/// Options of one episode for N joints ([`crate::closed_loop::EpisodeOptions`] for the paper's
/// arm). The plant is not among them: it is a type parameter of [`simulate_on`]/[`episode_on`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeOptionsN<const N: usize, const NX: usize> {
    pub t_end: f64,
    pub dt: f64,
    /// Initial state X0.
    pub x0: SVector<f64, NX>,
    /// Initial torque U0.
    pub u0: SVector<f64, N>,
    /// Constant torque perturbation ΔT on every joint [N m].
    pub perturbation: f64,
    /// A constant torque perturbation of each joint's own, added to `perturbation` [N m]
    /// (zero unless a task file gives one per joint).
    pub joint_perturbation: SVector<f64, N>,
    pub learning_rate: f64,
    /// Integrator options; [`Method::Auto`] runs DP5 on tasks 1–2 and the DP5-to-Rodas5P
    /// switch on task 3, any task whose error term is θ̈ (why: the paper's options,
    /// `EpisodeOptions::default()` in [`crate::closed_loop`]).
    pub integrator: IntegratorOptions,
    /// Keep the trajectory on the output grid ([`episode_on`]; [`simulate_on`] never keeps it).
    pub record_trajectory: bool,
}

impl<const N: usize, const NX: usize> EpisodeOptionsN<N, NX> {
    /// The paper's options ("Implementation details") for model `M`: t_end = 5 s, dt = 0.05 s,
    /// X0 = M's equilibrium, U0 = 0.1 on every joint, ΔT = 0, γ = 1, MATLAB ode45's tolerances.
    /// `EpisodeOptions::default()` ([`crate::closed_loop::EpisodeOptions`]) is this for the
    /// paper's arm.
    pub fn paper<M, const NP: usize, const NZ: usize>() -> Self
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        Self {
            t_end: 5.0,
            dt: 0.05,
            x0: M::equilibrium_state(),
            u0: SVector::repeat(0.1),
            perturbation: 0.0,
            joint_perturbation: SVector::zeros(),
            learning_rate: 1.0,
            integrator: IntegratorOptions::default(),
            record_trajectory: false,
        }
    }
}

impl<const N: usize, const NX: usize> EpisodeOptionsN<N, NX> {
    /// ΔT on each joint: `perturbation` on all of them plus `joint_perturbation`.
    pub fn total_perturbation(&self) -> SVector<f64, N> {
        SVector::repeat(self.perturbation) + self.joint_perturbation
    }
}

/// What one episode measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// Σ over all grid samples (t = 0 included) of the task's weighted error.
    pub task_error: f64,
    /// ∫F dt (eq. free_energy with the task's terms and −ln|Π^U|), trapezoidal on the grid.
    pub free_energy: f64,
    /// ∫J dt: the same without the confidence term.
    pub cost_j: f64,
    /// ln|Π^U|.
    pub logdet: f64,
    /// Right-hand-side evaluations of the closed loop.
    pub rhs_evals: usize,
    /// Accepted and rejected integrator steps.
    pub steps: usize,
    pub rejected_steps: usize,
    /// Jacobian evaluations and LU factorisations (0 unless the stiff method ran).
    pub jacobian_evals: usize,
    pub factorisations: usize,
    /// ∫|U|² dt, trapezoidal on the grid (the controller's torque, without ΔT).
    pub control_effort: f64,
    /// On a position task (joint or tip: the error term is a position, θ or y), how far the
    /// episode went towards the goal: 1 − e(T)/e(0), with e = |term − goal| the Euclidean
    /// distance (rad, or m for the tip). 1 is the goal reached, 0 no progress, negative moved
    /// away. `None` on the other tasks, or when the episode starts at its goal (e(0) = 0).
    pub progress: Option<f64>,
}

impl Metrics {
    /// The last line of defence before the metrics are printed ([`crate::validate::finite_output`]):
    /// the task error, ∫F dt, ∫J dt, ln|Π^U| and ∫|U|² dt of `tool` all finite.
    pub fn check_finite(&self, tool: &dyn std::fmt::Display) -> Result<(), Error> {
        let values = [
            self.task_error,
            self.free_energy,
            self.cost_j,
            self.logdet,
            self.control_effort,
            self.progress.unwrap_or(0.0),
        ];
        crate::validate::finite_output(tool, "the episode's metrics", values)
    }
}

/// The trajectory on the output grid: every term the controller observes at each time, by
/// [`Term::index`] (θ̈ is the plant's, f(X, U + ΔT)).
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryN<const N: usize> {
    pub t: Vec<f64>,
    pub terms: [Vec<SVector<f64, N>>; TERMS],
    /// On a task that reads the tool's tip, how many components its tip terms have (their
    /// first rows, padded: [`toolconf_core::TaskN`]); `None` otherwise, where they are zero
    /// and not part of the trajectory ([`Self::components`]).
    pub tip_dim: Option<usize>,
}

impl<const N: usize> Default for TrajectoryN<N> {
    fn default() -> Self {
        Self {
            t: Vec::new(),
            terms: core::array::from_fn(|_| Vec::new()),
            tip_dim: None,
        }
    }
}

impl<const N: usize> TrajectoryN<N> {
    /// The values of `term` on the grid.
    pub fn of(&self, term: Term) -> &[SVector<f64, N>] {
        &self.terms[term.index()]
    }

    /// How many of `term`'s rows are its own: N for a joint term, the tip's components for a
    /// tip term on a tip task, 0 for a tip term otherwise.
    pub fn components(&self, term: Term) -> usize {
        toolconf_core::term_components(term, N, self.tip_dim.unwrap_or(0))
    }

    /// Appends the observation at time `t`.
    pub fn push(&mut self, t: f64, observed: ObservationN<N>) {
        self.t.push(t);
        for (series, value) in self.terms.iter_mut().zip(observed) {
            series.push(value);
        }
    }
}

/// One episode's metrics and, if [`EpisodeOptionsN::record_trajectory`], its trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeN<const N: usize> {
    pub metrics: Metrics,
    pub trajectory: Option<TrajectoryN<N>>,
}

/// Why an episode failed, before the tool is named: the generic entry points name it
/// `model(m1=… …)`, the paper's arm's ([`crate::closed_loop`]) `arm m1=… …`, with the same time
/// and reason.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum EpisodeFailure {
    Input(Error),
    Integration(IntegrationError),
    Diverged { t: f64, magnitude: f64 },
}

impl From<Error> for EpisodeFailure {
    fn from(e: Error) -> Self {
        EpisodeFailure::Input(e)
    }
}

/// Why an episode failed: bad input, or the simulation of the named tool failed at a time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelSimulationError {
    #[error(transparent)]
    Input(#[from] Error),
    #[error("simulation of {tool} failed: {source}")]
    Integration {
        tool: String,
        source: IntegrationError,
    },
    #[error("simulation of {tool} diverged at t = {} s: |state| = {magnitude:e} exceeds {DIVERGENCE_BOUND:e}", toolconf_messages::Short(*t))]
    Diverged {
        tool: String,
        t: f64,
        magnitude: f64,
    },
}

impl ModelSimulationError {
    /// The time the failure happened at, if it is a failure of the simulation itself.
    pub fn time(&self) -> Option<f64> {
        match self {
            ModelSimulationError::Input(_) => None,
            ModelSimulationError::Integration { source, .. } => source.time(),
            ModelSimulationError::Diverged { t, .. } => Some(*t),
        }
    }

    pub(crate) fn named(failure: EpisodeFailure, tool: impl FnOnce() -> String) -> Self {
        match failure {
            EpisodeFailure::Input(e) => ModelSimulationError::Input(e),
            EpisodeFailure::Integration(source) => ModelSimulationError::Integration {
                tool: tool(),
                source,
            },
            EpisodeFailure::Diverged { t, magnitude } => ModelSimulationError::Diverged {
                tool: tool(),
                t,
                magnitude,
            },
        }
    }
}

/// The metrics of one episode of `tool` on `task`, the plant being the tool's own model.
pub fn simulate<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<Metrics, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    simulate_on::<M, M, N, NX, NP, NZ>(tool, task, options)
}

/// The metrics of one episode of `tool` (controller model `M`) on `task`, simulated on plant
/// model `P`; the trajectory is not kept whatever `options.record_trajectory` says.
pub fn simulate_on<M, P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<Metrics, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
    P: ArmModel<N, NX, NP, NZ>,
{
    let options = EpisodeOptionsN {
        record_trajectory: false,
        ..*options
    };
    episode_on::<M, P, N, NX, NP, NZ>(tool, task, &options).map(|e| e.metrics)
}

/// One episode of `tool` on `task` (metrics and, if asked for, the trajectory), the plant being
/// the tool's own model.
pub fn episode<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<EpisodeN<N>, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    episode_on::<M, M, N, NX, NP, NZ>(tool, task, options)
}

/// One episode of `tool` (controller model `M`) on `task`, simulated on plant model `P`.
pub fn episode_on<M, P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<EpisodeN<N>, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
    P: ArmModel<N, NX, NP, NZ>,
{
    run_episode::<M, P, N, NX, NP, NZ>(tool, task, options)
        .map_err(|f| ModelSimulationError::named(f, || format!("{}({tool})", M::name())))
}

/// The episode: the closed loop integrated on the output grid, the metrics accumulated (and the
/// trajectory kept) at every grid point.
///
/// The joint state is Z = [X; U]. The plant is the nonlinear Ẋ = f_P(X, U + ΔT) with a constant
/// torque perturbation ΔT on every joint; the controller observes θ, θ̇ and the plant's θ̈ and
/// updates U̇ = −γ ∂F/∂U (eq. U_dot_deriv).
pub(crate) fn run_episode<M, P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<EpisodeN<N>, EpisodeFailure>
where
    M: ArmModel<N, NX, NP, NZ>,
    P: ArmModel<N, NX, NP, NZ>,
{
    check_options(options)?;
    let system = ClosedLoopN::<P, N, NX, NP, NZ>::with_perturbation(
        tool,
        task,
        options.learning_rate,
        &options.total_perturbation(),
    )?;
    let controller = &system.controller;
    let grid = uniform_grid(0.0, options.t_end, options.dt);
    let mut z0 = SVector::<f64, NZ>::zeros();
    z0.fixed_rows_mut::<NX>(0).copy_from(&options.x0);
    z0.fixed_rows_mut::<N>(NX).copy_from(&options.u0);

    let trajectory = options.record_trajectory.then(|| TrajectoryN {
        t: Vec::with_capacity(grid.len()),
        tip_dim: reads_tip(task.kind).then_some(P::tip_dim()),
        ..TrajectoryN::default()
    });
    let mut sums = GridSums::new(task, trajectory);
    let rhs = |_t: f64, z: &SVector<f64, NZ>| system.rhs(z);
    // The closed loop is autonomous: ∂Ż/∂t = 0.
    let jacobian = |_t: f64, z: &SVector<f64, NZ>| (system.jacobian(z), SVector::zeros());
    let integrator = episode_integrator(task, &options.integrator, grid.len() - 1);
    let cap = options.integrator.max_steps;
    let stats = solve_grid_with_jacobian(rhs, jacobian, &z0, &grid, &integrator, |_, t, z| {
        let (_, observed) = system.rhs_and_observation(z);
        sums.add::<NX, NZ>(controller, task, t, z, observed);
    })
    .map_err(|e| EpisodeFailure::Integration(out_of_work::<N>(e, cap, options.dt)))?;
    sums.episode(controller.logdet, &stats, options.t_end)
}

/// The integrator's options for an episode of `task` over `intervals` output steps: the
/// method Auto resolved where it must not switch, and the work budget of the whole episode.
fn episode_integrator<const N: usize>(
    task: &TaskN<N>,
    options: &IntegratorOptions,
    intervals: usize,
) -> IntegratorOptions {
    let mut integrator = *options;
    // Auto switches only on acceleration-control tasks (θ̈ feedback makes them stiff); elsewhere
    // it stays DP5 so the paper's ode45 runs keep their numbers (see EpisodeOptions::integrator).
    let fed_back_through_the_plant = matches!(
        task.kind.error_term().read(),
        Read::StateRate { .. } | Read::Tip { order: 2.. }
    );
    if integrator.method == Method::Auto && !fed_back_through_the_plant {
        integrator.method = Method::Explicit;
    }
    let cap = integrator.max_steps;
    integrator.max_steps =
        super::budget::episode_budget(intervals as f64, integrator.rtol, integrator.atol, cap);
    integrator
}

/// What an episode accumulates at each output grid point: the sums of [`Metrics`] (Σ task
/// error; ∫F dt, ∫J dt and ∫|U|² dt by the trapezoidal rule), the first divergence, the
/// distance to the goal for `progress`, and the trajectory if kept. A struct the grid's output
/// closure borrows mutably, as it did the locals: nothing allocated per point.
struct GridSums<const N: usize> {
    task_error: f64,
    int_f: f64,
    int_j: f64,
    effort: f64,
    /// (t, F, J, |U|²) at the previous grid point, for the trapezoidal rule.
    previous: Option<(f64, f64, f64, f64)>,
    /// (t, |Z|∞) at the first grid point past [`DIVERGENCE_BOUND`].
    divergence: Option<(f64, f64)>,
    /// The task's error term, on a position task (the only ones `progress` measures).
    position: Option<Term>,
    /// The distance to the goal at the first and the latest grid point, for `progress`.
    first_distance: Option<f64>,
    distance: f64,
    trajectory: Option<TrajectoryN<N>>,
}

impl<const N: usize> GridSums<N> {
    fn new(task: &TaskN<N>, trajectory: Option<TrajectoryN<N>>) -> Self {
        let error_term = task.kind.error_term();
        GridSums {
            task_error: 0.0,
            int_f: 0.0,
            int_j: 0.0,
            effort: 0.0,
            previous: None,
            divergence: None,
            position: is_position(error_term).then_some(error_term),
            first_distance: None,
            distance: 0.0,
            trajectory,
        }
    }

    /// Adds the grid point at `t`, joint state `z` = [X; U], where the controller observes
    /// `observed`.
    // Always: called once per grid point from the integrator's output closure, which LLVM
    // otherwise compiles as a call (as for `rhs_and_observation`).
    #[inline(always)]
    fn add<const NX: usize, const NZ: usize>(
        &mut self,
        controller: &ActiveInferenceN<N>,
        task: &TaskN<N>,
        t: f64,
        z: &SVector<f64, NZ>,
        observed: ObservationN<N>,
    ) {
        let u = z.fixed_rows::<N>(NX).into_owned();
        let magnitude = z.amax();
        if self.divergence.is_none() && magnitude > DIVERGENCE_BOUND {
            self.divergence = Some((t, magnitude));
        }
        self.task_error += controller.task_error(&observed);
        if let Some(error_term) = self.position {
            self.distance = (observed[error_term.index()] - task.goal(error_term)).norm();
            self.first_distance.get_or_insert(self.distance);
        }
        let j = controller.cost_j(&observed);
        let f = j - 0.5 * controller.logdet;
        let e = u.norm_squared();
        if let Some((t_prev, f_prev, j_prev, e_prev)) = self.previous {
            let h = t - t_prev;
            self.int_f += 0.5 * h * (f + f_prev);
            self.int_j += 0.5 * h * (j + j_prev);
            self.effort += 0.5 * h * (e + e_prev);
        }
        self.previous = Some((t, f, j, e));
        if let Some(tr) = self.trajectory.as_mut() {
            tr.push(t, observed);
        }
    }

    /// The episode from the sums and the integrator's counts, or why it diverged: a state past
    /// the bound on the grid, or metrics that are not finite (at `t_end`).
    fn episode(
        self,
        logdet: f64,
        stats: &Stats,
        t_end: f64,
    ) -> Result<EpisodeN<N>, EpisodeFailure> {
        if let Some((t, magnitude)) = self.divergence {
            return Err(EpisodeFailure::Diverged { t, magnitude });
        }
        let distance = self.distance;
        let metrics = Metrics {
            task_error: self.task_error,
            free_energy: self.int_f,
            cost_j: self.int_j,
            logdet,
            rhs_evals: stats.rhs_evals,
            steps: stats.steps,
            rejected_steps: stats.rejected,
            control_effort: self.effort,
            jacobian_evals: stats.jacobian_evals,
            factorisations: stats.factorisations,
            progress: self
                .first_distance
                .filter(|&d0| d0 > 0.0)
                .map(|d0| 1.0 - distance / d0),
        };
        if ![metrics.task_error, metrics.free_energy, metrics.cost_j]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(EpisodeFailure::Diverged {
                t: t_end,
                magnitude: f64::INFINITY,
            });
        }
        Ok(EpisodeN {
            metrics,
            trajectory: self.trajectory,
        })
    }
}

/// Whether `term` is a position, joint or tip (θ, y): what [`Metrics::progress`] measures.
pub fn is_position(term: Term) -> bool {
    matches!(
        term.read(),
        Read::State { block: 0 } | Read::Tip { order: 0 }
    )
}

/// [`IntegrationError::TooManySteps`] at the episode's budget (below the integrator's own limit
/// `cap`) as [`IntegrationError::OutOfWork`], with the reason read from where it stopped.
pub(crate) fn out_of_work<const N: usize>(
    e: IntegrationError,
    cap: usize,
    dt: f64,
) -> IntegrationError {
    match e {
        IntegrationError::TooManySteps {
            t,
            max_steps,
            h,
            state,
        } if max_steps < cap => IntegrationError::OutOfWork {
            t,
            attempts: max_steps,
            why: super::budget::diagnosis::<N>(&state, h, dt),
        },
        e => e,
    }
}

/// The episode's options against their documented ranges ([`crate::validate`]): what every
/// front end also checks up front, checked again here for the library's own callers.
pub(crate) fn check_options<const N: usize, const NX: usize>(
    o: &EpisodeOptionsN<N, NX>,
) -> Result<(), Error> {
    use crate::validate::{ATOL, DT, JOINT_ANGLE, JOINT_RATE, LEARNING_RATE, RTOL, TORQUE, T_END};
    let within = |name, value: f64, range: crate::validate::Range| {
        if range.contains(value) {
            Ok(())
        } else {
            Err(Error::OutOfRange { name, value, range })
        }
    };
    within("end time t_end", o.t_end, T_END)?;
    within("output step dt", o.dt, DT)?;
    if o.dt > o.t_end {
        return Err(Error::InvalidOption {
            name: "output step dt (larger than t_end)",
            value: o.dt,
        });
    }
    check_grid(o.t_end, o.dt)?;
    within("learning rate", o.learning_rate, LEARNING_RATE)?;
    within("integrator rtol", o.integrator.rtol, RTOL)?;
    within("integrator atol", o.integrator.atol, ATOL)?;
    // X0 = [θ0; θ̇0].
    for (i, &v) in o.x0.iter().enumerate() {
        if i < N {
            within("initial angle θ0", v, JOINT_ANGLE)?;
        } else {
            within("initial rate θ̇0", v, JOINT_RATE)?;
        }
    }
    for &v in o.u0.iter() {
        within("initial torque U0", v, TORQUE)?;
    }
    for &v in o.total_perturbation().iter() {
        within("perturbation dT", v, TORQUE)?;
    }
    Ok(())
}

/// The most points an episode's output grid may have. Each point is kept in memory (the grid,
/// and the trajectory when it is recorded), so a horizon like t_end = 1e9 s at dt = 0.05 s
/// (2·10¹⁰ points, 160 GB for the grid alone) is refused here rather than aborting the process.
pub const MAX_GRID_POINTS: usize = 1_000_000;

/// [`Error::GridTooLarge`] when t_end/dt + 1 exceeds [`MAX_GRID_POINTS`].
pub fn check_grid(t_end: f64, dt: f64) -> Result<(), Error> {
    let points = (t_end / dt).floor() + 1.0;
    if points > MAX_GRID_POINTS as f64 {
        return Err(Error::GridTooLarge {
            t_end,
            dt,
            points,
            max: MAX_GRID_POINTS,
        });
    }
    Ok(())
}
