//! MPC baseline: the paper's cost J (no confidence term) minimised over a receding horizon on
//! a linear(ised) arm model, solved as a sparse QP with Clarabel.
//!
//! The controller ([`MpcN`]) and its episode ([`simulate_mpc_on`]) are generic over the arm
//! model ([`crate::model::ArmModel`]), like the active-inference runtime; [`Mpc`] and
//! [`simulate_mpc`] are the 2-link façade (the paper's `Arm`, `Task` and run-time `Plant`).
//! The sizes quoted below (6×6 stage blocks, four x_0 rows, the 7×7 exponential) are the 2-link
//! arm's; for an arm with n joints (state 2n) they are 3n×3n, 2n and 3n + 1.
//!
//! # Models ([`MpcModel`])
//!
//! - [`MpcModel::Equilibrium`], the specification: the paper's linearisation
//!   ẋ = A(x − X^e) + Bu at the hanging equilibrium (appendix "Generative model"), fixed.
//! - [`MpcModel::Local`], successive linearisation: at every control step the generative
//!   process f is linearised at the measured state x̄ and the torque ū the plant is believed to
//!   receive (the control returned at the previous call plus the disturbance estimate d̂; 0 at
//!   the first call): A_k = ∂f/∂X, B_k = ∂f/∂U from the generated `dynamics_jacobian`,
//!   c_k = f(x̄, ū) − A_k x̄ − B_k ū, so ẋ = A_k x + B_k u + c_k is exact to first order around
//!   (x̄, ū). The model is frozen over the horizon (LTI within one solve, LTV across solves).
//!   At (X^e, 0) it is the equilibrium model (c = −A X^e, f(X^e, 0) = 0).
//!
//! Either affine model ẋ = Ax + Bu + c is discretised exactly with a zero-order hold at the
//! control period (the paper samples at dt = 0.05 s): x_{k+1} = Ad x_k + Bd u_k + cd
//! ([`discretise`], one 7×7 matrix exponential). The offset cd keeps the model in absolute
//! coordinates, so goals and the measured state are used as is.
//!
//! # Disturbance observer (offset-free MPC)
//!
//! With `disturbance_observer`, the controller estimates a constant input disturbance d̂
//! (N m, on the torque channels, where the perturbation ΔT enters the plant f(X, U + ΔT)).
//! At each call, with the previous call's state x⁻, control u⁻ and discrete model:
//!
//! e = x − (Ad x⁻ + Bd (u⁻ + d̂) + cd),   d̂ ← d̂ + L (BdᵀBd)⁻¹Bdᵀ e,
//!
//! the least-squares input that explains the one-step prediction error through Bd, filtered by
//! the gain L = `observer_gain` ∈ (0, 1]. For a plant that is the model plus a constant ΔT the
//! error after one update is (1 − L)ᵏ times the first; on the nonlinear plant d̂ also absorbs
//! the model's own one-step error (for the equilibrium model: the gravity mismatch). The plan
//! then uses the model with input u + d̂: cd + Bd d̂ in the dynamics and c + B d̂ in the
//! acceleration θ̈ the cost penalises. (The estimate must enter θ̈ as well as the dynamics: the
//! plant's θ̈ carries ΔT, and task 3, which weights only θ̈, would otherwise keep an offset of
//! B₃₄ΔT.)
//!
//! # Formulation
//!
//! Decision variables are z = (x_0, …, x_N, u_0, …, u_{N−1}), N = round(horizon / period). Keeping
//! x_0 as a variable pinned by the equality x_0 = x puts the measured state in the right-hand
//! side b only. The states are kept as variables (sparse, "simultaneous" form) rather than
//! eliminated, so P and A stay banded with O(N) non-zeros instead of a dense N×N condensed
//! Hessian.
//!
//! Cost: Σ_{k<N} T·J(x_k, u_k) + T·J_f(x_N), with J the paper's
//! ½[(θ−θ^g)ᵀP^θ(θ−θ^g) + (θ̇−θ̇^g)ᵀP^θ̇(θ̇−θ̇^g) + (θ̈−θ̈^g)ᵀP^θ̈(θ̈−θ̈^g) + UᵀP^U U] and
//! θ̈ = rows 3–4 of A x_k + B(u_k + d̂) + c, the model's acceleration during stage k. That makes
//! J a quadratic in (x_k, u_k) with cross terms. Weighting by T makes the sum a Riemann sum
//! of the paper's integral cost. The terminal cost J_f is the state-only part of J (the θ and
//! θ̇ terms): θ̈ depends on a control, and there is no u_N. Task 3 therefore has no terminal
//! cost, and its P^U = 0 leaves P only positive semi-definite; the θ̈ term still makes the
//! reduced Hessian in u (B₃₄ᵀP^θ̈B₃₄) definite, so the optimum is unique and Clarabel solves it.
//!
//! Constraints: the dynamics as equalities (Clarabel's zero cone) and, if the torque limit is
//! finite, |u_k,j| ≤ L as 4N rows (2nN for n joints) in the non-negative cone.
//!
//! # One solver, updated in place
//!
//! Clarabel is set up once in [`Mpc::new`] (with the equilibrium model) and never rebuilt. The
//! sparsity pattern is fixed there: every entry a model can fill (each stage's whole 6×6
//! upper-triangular Hessian block, the whole −Ad and −Bd blocks) is stored even when its
//! value is 0. Per call, Clarabel 0.11's data-update API overwrites values only:
//!
//! - always: `update_b` at the four x_0 rows;
//! - [`MpcModel::Local`]: `update_P` and `update_A` with (index, value) pairs at the stage
//!   Hessian and dynamics-block positions (precomputed non-zero positions in the CSC arrays),
//!   `update_q` with the whole q, `update_b` at the cd rows;
//! - equilibrium model with observer: `update_q` and `update_b` (cd rows) only.
//!
//! `presolve_enable = false` and `input_sparse_dropzeros = false` keep updates allowed.
//! Clarabel re-applies the equilibration (scaling) it computed at setup to updated data, so
//! after an update it solves a differently scaled copy of the QP a fresh setup would solve:
//! the same optimum to the solver's accuracy (plans agree to ≈ 2e-9 at the default
//! tolerances, to 1e-10 at tight ones, and bit for bit with equilibration off; tested).
//!
//! Clarabel runs with default tolerances otherwise. Each solve starts from Clarabel's default
//! point, so the original linear MPC's answer depends only on the state; with the local model
//! or the observer it also depends on the previous call (state, control, d̂) until
//! [`MpcN::reset`]. Without the torque bound the QP has only equalities and Clarabel solves it
//! in one KKT solve (0 iterations).
//!
//! Speed: Clarabel's solver is generic, so it is compiled into this crate at this crate's
//! optimisation level. A bounded solve (N = 20, 6–10 iterations) takes ≈ 0.3–0.5 ms in the
//! release profile but ≈ 6–12 ms in the dev profile; time experiments in release. The local
//! model adds ≈ 10 µs (Jacobian and matrix exponential) and the in-place update ≈ 15 µs.
//!
//! # Choice of the defaults (measured)
//!
//! The paper's three tasks on `select::draw_tools(30, 1)`, default episode (5 s, X0 = X^e),
//! ΔT = 0 and −0.8 N m, default timing and 5 N m bound; success = the episode ran without
//! error; medians of task error and ∫J over the successful episodes; time = median over
//! episodes of the median wall time of a control step (release, 2 shared cores, so ±30 %).
//! Reproduce with `cargo test --release --test mpc_episode -- --ignored --nocapture`.
//!
//! | model | observer (L) | ΔT | task | success | median task error | median ∫J | median time per step (µs) |
//! |---|---|---|---|---|---|---|---|
//! | Equilibrium | no | 0 | 1 | 20/30 | 4.9349e9 | 9.4586e10 | 488 |
//! | Equilibrium | no | 0 | 2 | 19/30 | 2.3780e9 | 7.0537e10 | 461 |
//! | Equilibrium | no | 0 | 3 | 30/30 | 6.6633e2 | 1.4370e1 | 347 |
//! | Equilibrium | no | -0.8 | 1 | 18/30 | 4.3423e9 | 3.2113e11 | 512 |
//! | Equilibrium | no | -0.8 | 2 | 16/30 | 4.8144e9 | 4.4278e11 | 516 |
//! | Equilibrium | no | -0.8 | 3 | 12/30 | 1.9418e15 | 3.9906e13 | 474 |
//! | Equilibrium | yes (1) | 0 | 1 | 30/30 | 1.2545e4 | 4.8502e2 | 434 |
//! | Equilibrium | yes (1) | 0 | 2 | 30/30 | 1.1780e4 | 3.2994e2 | 364 |
//! | Equilibrium | yes (1) | 0 | 3 | 30/30 | 1.1311e-2 | 2.7344e-4 | 351 |
//! | Equilibrium | yes (1) | -0.8 | 1 | 30/30 | 1.6435e4 | 8.5557e2 | 557 |
//! | Equilibrium | yes (1) | -0.8 | 2 | 30/30 | 1.3619e4 | 4.5757e2 | 403 |
//! | Equilibrium | yes (1) | -0.8 | 3 | 30/30 | 3.4138e8 | 8.5034e6 | 466 |
//! | Local | no | 0 | 1 | 30/30 | 1.2963e4 | 4.8189e2 | 398 |
//! | Local | no | 0 | 2 | 30/30 | 4.2254e2 | 2.2728e1 | 426 |
//! | Local | no | 0 | 3 | 30/30 | 3.9841e-10 | 9.9601e-12 | 473 |
//! | Local | no | -0.8 | 1 | 28/30 | 9.7920e5 | 2.5760e4 | 609 |
//! | Local | no | -0.8 | 2 | 22/30 | 2.9290e5 | 7.4998e3 | 369 |
//! | Local | no | -0.8 | 3 | 4/30 | 5.4800e7 | 1.3635e6 | 467 |
//! | Local | yes (1) | 0 | 1 | 30/30 | 1.2978e4 | 4.8204e2 | 394 |
//! | Local | yes (1) | 0 | 2 | 30/30 | 4.2291e2 | 2.2622e1 | 351 |
//! | Local | yes (1) | 0 | 3 | 30/30 | 1.1210e-6 | 2.7449e-8 | 349 |
//! | Local | yes (1) | -0.8 | 1 | 30/30 | 1.5400e4 | 7.3639e2 | 418 |
//! | Local | yes (1) | -0.8 | 2 | 30/30 | 3.0658e3 | 1.8939e2 | 399 |
//! | Local | yes (1) | -0.8 | 3 | 30/30 | 6.5955e4 | 8.2475e2 | 428 |
//! | Local | yes (0.5) | 0 | 1 | 30/30 | 1.2977e4 | 4.8203e2 | 387 |
//! | Local | yes (0.5) | 0 | 2 | 30/30 | 4.2286e2 | 2.2627e1 | 346 |
//! | Local | yes (0.5) | 0 | 3 | 30/30 | 1.0752e-6 | 2.6320e-8 | 344 |
//! | Local | yes (0.5) | -0.8 | 1 | 30/30 | 1.7922e4 | 8.7086e2 | 403 |
//! | Local | yes (0.5) | -0.8 | 2 | 30/30 | 6.4339e3 | 2.6611e2 | 393 |
//! | Local | yes (0.5) | -0.8 | 3 | 30/30 | 9.0615e4 | 1.4412e3 | 439 |
//!
//! - The original linear MPC (equilibrium, no observer) fails on a third of the tools on
//!   tasks 1–2 even unperturbed (θ^g is 150° from X^e, where the linear gravity "spring" is
//!   nothing like cos gravity; task 2 rotates joint 2 continuously) and the successful ones
//!   have medians of 1e9 task error: it swings the arm around, not to the goal. With ΔT = −0.8
//!   it fails on 12–18 of 30 on every task.
//! - The observer alone already stabilises the equilibrium model (d̂ absorbs the gravity
//!   mismatch as a disturbance), but its θ̈ predictions stay wrong: 30× the local model's
//!   error on task 2 and 1e8 on task 3 under ΔT.
//! - The local model alone is the best unperturbed (task 3 to 1e-10: f is affine in U, so
//!   the local model's θ̈ is exact at the measured state) but has no integral action: with
//!   ΔT = −0.8 it loses 2–26 tools and spins the light distal links.
//! - Local + observer succeeds on 90/90 in both cases, matches the local model unperturbed
//!   (task 3 to 1e-6 instead of 1e-10: the observer picks up integration and linearisation
//!   error) and has the lowest error under ΔT on every task. Its task-3 error under ΔT is
//!   dominated by the first samples, before any controller can know ΔT (at t = 0 the plant's
//!   θ̈ is off by B₃₄ΔT, e.g. 150 rad/s² on the distal link of 0.3,0.4,0.5,0.2).
//! - L = 1 beats L = 0.5 under ΔT (the state is measured exactly, so there is no noise to
//!   filter, and a slower estimate means a longer uncompensated transient).
//!
//! Hence the default: [`MpcModel::Local`], observer on, L = 1 ([`MpcOptions::default`]); the
//! issue's original linear MPC stays available as [`MpcOptions::original_linear`]
//! (`--mpc-model equilibrium --disturbance-observer false` on the command line). On task 1 the
//! default settles ≈ 0.03–0.05 rad from θ^g: that is J's own optimum (P^U = I prices the
//! torque that holds the arm against gravity), not an offset.

mod discretise;
mod episode;
#[cfg(test)]
mod lqr;
mod qp;

use std::marker::PhantomData;
use std::ops::{Deref, DerefMut};
use std::time::{Duration, Instant};

use clarabel::solver::SolverStatus;
use nalgebra::{SMatrix, SVector};

pub use discretise::{discretise, Discretised};
pub use episode::{
    simulate_mpc, simulate_mpc_on, MpcEpisode, MpcEpisodeError, MpcEpisodeN, MpcMetrics,
    MpcMetricsN, MpcSimulationError,
};
use qp::{QpSolver, StageCost};

use crate::model::{Arm2, Arm2Tool, ArmModel, TaskN, ToolN};
use crate::{Arm, Task};
// The 2-link names the unit tests below use (through `use super::*`).
#[cfg(test)]
use crate::{generated::arm2, State, Vector2};

/// The linear model the QP plans with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MpcModel {
    /// The paper's linearisation ẋ = A(x − X^e) + Bu at the hanging equilibrium, fixed for the
    /// whole episode: the original linear MPC.
    Equilibrium,
    /// Successive linearisation: at every control step the generative process is linearised
    /// at the measured state and the torque last applied (plus the disturbance estimate),
    /// ZOH-discretised, and frozen over the horizon.
    Local,
}

/// Timing, horizon, model and disturbance handling of the controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MpcOptions {
    /// Control period T in s: the zero-order-hold interval and the QP's time step.
    pub period: f64,
    /// Prediction horizon in s, rounded to a whole number N of periods.
    pub horizon: f64,
    /// Bound on |T1| and |T2| in Nm; `f64::INFINITY` for no bound.
    pub torque_limit: f64,
    /// The prediction model.
    pub model: MpcModel,
    /// Estimate a constant input disturbance and plan with it (offset-free MPC).
    pub disturbance_observer: bool,
    /// Gain L ∈ (0, 1] of the observer, d̂ ← d̂ + L·(BdᵀBd)⁻¹Bdᵀe: 1 takes the last step's
    /// least-squares estimate as is, smaller values low-pass filter it.
    pub observer_gain: f64,
}

impl Default for MpcOptions {
    /// T = 0.05 s (the paper's sampling time), 1 s horizon (N = 20), 5 Nm, successive
    /// linearisation with the disturbance observer (chosen by measurement; module docs).
    fn default() -> Self {
        Self {
            period: 0.05,
            horizon: 1.0,
            torque_limit: 5.0,
            model: MpcModel::Local,
            disturbance_observer: true,
            observer_gain: 1.0,
        }
    }
}

impl MpcOptions {
    /// The original linear MPC: the default timing and bound, the equilibrium model
    /// and no disturbance observer.
    pub fn original_linear() -> Self {
        Self {
            model: MpcModel::Equilibrium,
            disturbance_observer: false,
            ..Self::default()
        }
    }
}

/// Largest N accepted; beyond it the QP is a configuration mistake, not a controller.
const MAX_HORIZON_STEPS: usize = 10_000;

impl MpcOptions {
    /// Checks the options; the number of steps N, or why these options are unusable.
    fn horizon_steps(&self) -> Result<usize, MpcError> {
        let invalid = |reason: String| Err(MpcError::InvalidOptions { reason });
        if !(self.period.is_finite() && self.period > 0.0) {
            return invalid(format!(
                "period = {} s: must be a finite number > 0",
                self.period
            ));
        }
        if !(self.horizon.is_finite() && self.horizon >= self.period) {
            return invalid(format!(
                "horizon = {} s: must be finite and at least the period ({} s)",
                self.horizon, self.period
            ));
        }
        if self.torque_limit.is_nan() || self.torque_limit <= 0.0 {
            return invalid(format!(
                "torque_limit = {} Nm: must be > 0 (or infinite for no bound)",
                self.torque_limit
            ));
        }
        if !(self.observer_gain > 0.0 && self.observer_gain <= 1.0) {
            return invalid(format!(
                "observer_gain = {}: must be in (0, 1]",
                self.observer_gain
            ));
        }
        let steps = (self.horizon / self.period).round();
        if steps > MAX_HORIZON_STEPS as f64 {
            return invalid(format!(
                "horizon / period = {} / {} = {steps} steps: at most {MAX_HORIZON_STEPS}",
                self.horizon, self.period
            ));
        }
        Ok(steps as usize)
    }
}

/// What can go wrong in the MPC.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MpcError {
    /// Options that do not describe a controller; `reason` names the value.
    #[error("invalid MPC options: {reason}")]
    InvalidOptions { reason: String },
    /// The task or the QP could not be set up.
    #[error("MPC setup failed: {reason}")]
    Setup { reason: String },
    /// The solver did not return a solution at the `step`-th call (0-based) of
    /// [`MpcN::control`].
    #[error("MPC solve failed at control step {step}: {status}")]
    Solve { status: String, step: usize },
}

/// Report of the last solve.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveInfo {
    /// Clarabel's status (`Solved`, `AlmostSolved`, …; `Unsolved` before the first call).
    pub status: String,
    pub iterations: u32,
    /// Wall-clock time of the whole control step: observer update, re-linearisation and
    /// discretisation (with [`MpcModel::Local`]), the in-place data update and the solve.
    /// (Clarabel's own `solve_time` is not used: it also counts the one-off setup, on every
    /// solve.)
    pub solve_time: Duration,
}

/// A continuous affine model ẋ = a x + b u + c.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Affine<const N: usize, const NX: usize> {
    a: SMatrix<f64, NX, NX>,
    b: SMatrix<f64, NX, N>,
    c: SVector<f64, NX>,
}

/// A receding-horizon controller for one (tool, task, options) of any [`ArmModel`]; see the
/// module docs. [`Mpc`] is the 2-link one.
///
/// With [`MpcModel::Local`] or the disturbance observer the controller has memory (the last
/// state and control, the estimate d̂): a call's answer depends on the calls before it, until
/// [`MpcN::reset`].
pub struct MpcN<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> {
    qp: QpSolver<N, NX, NZ>,
    horizon: usize,
    options: MpcOptions,
    task: TaskN<N>,
    params: SVector<f64, NP>,
    /// The continuous model of the current plan, without the disturbance estimate.
    model: Affine<N, NX>,
    /// Its zero-order-hold discretisation (also without the estimate).
    discrete: Discretised<NX, N>,
    /// d̂, the estimated constant input disturbance [N m].
    estimate: SVector<f64, N>,
    /// The state measured and the control returned at the last successful call.
    previous: Option<(SVector<f64, NX>, SVector<f64, N>)>,
    plan: Vec<SVector<f64, N>>,
    calls: usize,
    info: SolveInfo,
    /// The prediction model's equations.
    arm_model: PhantomData<M>,
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> MpcN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// Discretises the tool's model at the equilibrium, builds the QP and sets up Clarabel once.
    /// (With [`MpcModel::Local`], the first call re-linearises at its state.)
    pub fn new(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        options: &MpcOptions,
    ) -> Result<Self, MpcError> {
        let horizon = options.horizon_steps()?;
        task.validate().map_err(|e| MpcError::Setup {
            reason: e.to_string(),
        })?;
        let (a, b, xe) = (
            tool.state_matrix(),
            tool.input_matrix(),
            M::equilibrium_state(),
        );
        let model = Affine { a, b, c: -a * xe };
        let discrete = discretise(&a, &b, &model.c, options.period);
        let cost = StageCost::of(&a, &b, &model.c, task, options.period);
        let qp = QpSolver::new(&discrete, &cost, horizon, options.torque_limit)
            .map_err(|reason| MpcError::Setup { reason })?;
        let info = SolveInfo {
            status: format!("{:?}", SolverStatus::Unsolved),
            iterations: 0,
            solve_time: Duration::ZERO,
        };
        Ok(Self {
            qp,
            horizon,
            options: *options,
            task: *task,
            params: tool.params(),
            model,
            discrete,
            estimate: SVector::zeros(),
            previous: None,
            plan: Vec::with_capacity(horizon),
            calls: 0,
            info,
            arm_model: PhantomData,
        })
    }

    /// Solves the QP from the measured state x = [θ; θ̇] and returns the first control move
    /// u_0, which the caller is expected to apply (zero-order hold) until the next call: the
    /// observer and the local model use it. `AlmostSolved` (Clarabel's reduced-accuracy
    /// solution) is accepted and visible in [`MpcN::last_solve`]; any other non-`Solved` status
    /// is an error, clears the plan and forgets the last control (the next call then neither
    /// updates d̂ nor knows the torque to linearise at, and uses d̂ alone).
    pub fn control(&mut self, x: &SVector<f64, NX>) -> Result<SVector<f64, N>, MpcError> {
        let step = self.calls;
        self.calls += 1;
        self.plan.clear();
        let previous = self.previous.take();
        if let Some(bad) = x.iter().find(|v| !v.is_finite()) {
            return Err(MpcError::Solve {
                status: format!("state has a non-finite entry {bad}"),
                step,
            });
        }
        let start = Instant::now();
        if self.options.disturbance_observer {
            if let Some((x_prev, u_prev)) = &previous {
                self.observe(x_prev, u_prev, x);
            }
        }
        let relinearise = self.options.model == MpcModel::Local;
        if relinearise {
            let u_applied = previous.map_or(SVector::zeros(), |(_, u)| u) + self.estimate;
            self.linearise(x, &u_applied);
        }
        if relinearise || self.options.disturbance_observer {
            self.write_model(relinearise)
                .map_err(|status| MpcError::Solve { status, step })?;
        }
        self.qp
            .solve(x)
            .map_err(|status| MpcError::Solve { status, step })?;
        let solve_time = start.elapsed();
        let solution = self.qp.solution();
        self.info = SolveInfo {
            status: format!("{:?}", solution.status),
            iterations: solution.iterations,
            solve_time,
        };
        if !matches!(
            solution.status,
            SolverStatus::Solved | SolverStatus::AlmostSolved
        ) {
            return Err(MpcError::Solve {
                status: self.info.status.clone(),
                step,
            });
        }
        self.plan.extend(self.qp.plan());
        self.previous = Some((*x, self.plan[0]));
        Ok(self.plan[0])
    }

    /// The disturbance observer: e = x − (Ad x_prev + Bd (u_prev + d̂) + cd) with last step's
    /// model, d̂ ← d̂ + L (BdᵀBd)⁻¹Bdᵀ e.
    fn observe(
        &mut self,
        x_prev: &SVector<f64, NX>,
        u_prev: &SVector<f64, N>,
        x: &SVector<f64, NX>,
    ) {
        let d = &self.discrete;
        let error = x - (d.ad * x_prev + d.bd * (u_prev + self.estimate) + d.cd);
        if let Some(gram) = (d.bd.transpose() * d.bd).cholesky() {
            let correction = gram.solve(&(d.bd.transpose() * error));
            if correction.iter().all(|v| v.is_finite()) {
                self.estimate += self.options.observer_gain * correction;
            }
        }
    }

    /// A = ∂f/∂X, B = ∂f/∂U at (x, u), c = f(x, u) − A x − B u, and its ZOH discretisation.
    fn linearise(&mut self, x: &SVector<f64, NX>, u: &SVector<f64, N>) {
        let (a, b) = M::dynamics_jacobian(x, u, &self.params);
        let c = M::dynamics(x, u, &self.params) - a * x - b * u;
        self.model = Affine { a, b, c };
        self.discrete = discretise(&a, &b, &c, self.options.period);
    }

    /// Writes the current model, with the disturbance estimate as an extra affine term
    /// (c + B d̂ in the cost's θ̈, cd + Bd d̂ in the dynamics), into the QP: P and A only if
    /// `matrices`, q and b always.
    fn write_model(&mut self, matrices: bool) -> Result<(), String> {
        let Affine { a, b, c } = self.model;
        let cost = StageCost::of(
            &a,
            &b,
            &(c + b * self.estimate),
            &self.task,
            self.options.period,
        );
        let discrete = Discretised {
            cd: self.discrete.cd + self.discrete.bd * self.estimate,
            ..self.discrete
        };
        self.qp.update(&discrete, &cost, matrices)
    }

    /// Forgets the last state and control and sets d̂ = 0, as if no call had been made (the
    /// call counter that errors report keeps counting).
    pub fn reset(&mut self) {
        self.previous = None;
        self.estimate = SVector::zeros();
    }

    /// d̂, the current estimate of the constant input disturbance [N m] (zero without the
    /// observer).
    pub fn disturbance_estimate(&self) -> SVector<f64, N> {
        self.estimate
    }

    pub fn last_solve(&self) -> SolveInfo {
        self.info.clone()
    }

    /// N, the number of control moves in the plan.
    pub fn horizon_steps(&self) -> usize {
        self.horizon
    }

    /// The optimal open-loop controls u_0..u_{N−1} of the last successful solve (empty after a
    /// failed one or before the first).
    pub fn last_plan(&self) -> &[SVector<f64, N>] {
        &self.plan
    }
}

/// The MPC of the paper's 2-DOF arm: [`MpcN`] with [`Arm2`], built from an [`Arm`] and a
/// [`Task`]. A newtype only so that [`Mpc::new`] keeps its 2-link signature; `control`,
/// `reset`, `disturbance_estimate`, `last_solve`, `horizon_steps` and `last_plan` are
/// [`MpcN`]'s, through `Deref`/`DerefMut`.
pub struct Mpc(MpcN<Arm2, 2, 4, 4, 6>);

impl Mpc {
    /// Discretises the arm's model at the equilibrium, builds the QP and sets up Clarabel once.
    /// (With [`MpcModel::Local`], the first call re-linearises at its state.)
    pub fn new(arm: &Arm, task: &Task, options: &MpcOptions) -> Result<Self, MpcError> {
        MpcN::new(&Arm2Tool::from(arm), &TaskN::from(task), options).map(Self)
    }
}

impl Deref for Mpc {
    type Target = MpcN<Arm2, 2, 4, 4, 6>;

    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl DerefMut for Mpc {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TaskKind;

    fn arms() -> [Arm; 3] {
        [
            Arm::new(0.3, 0.3, 0.3, 0.3).unwrap(),
            Arm::new(0.1, 0.6, 0.5, 0.2).unwrap(),
            Arm::new(0.6, 0.1, 0.1, 0.6).unwrap(),
        ]
    }

    fn states() -> [State; 3] {
        let xe = Arm::equilibrium_state();
        [
            xe,
            xe + State::new(0.3, -0.2, 0.5, -1.0),
            State::new(1.0, 0.5, 0.0, 2.0),
        ]
    }

    /// The equilibrium model without observer and without the bound: the linear-quadratic
    /// problem the Riccati reference solves.
    fn unconstrained() -> MpcOptions {
        MpcOptions {
            torque_limit: f64::INFINITY,
            ..MpcOptions::original_linear()
        }
    }

    #[test]
    fn unconstrained_mpc_equals_finite_horizon_lqr() {
        let options = unconstrained();
        for arm in arms() {
            let (a, b, xe) = (
                arm.state_matrix(),
                arm.input_matrix(),
                Arm::equilibrium_state(),
            );
            let model = discretise(&a, &b, &(-a * xe), options.period);
            for kind in TaskKind::ALL {
                let task = Task::paper(kind);
                let cost = StageCost::new(&a, &b, &(-a * xe), &task, options.period);
                let mut mpc = Mpc::new(&arm, &task, &options).unwrap();
                assert_eq!(mpc.horizon_steps(), 20);
                for x in states() {
                    let u0 = mpc.control(&x).unwrap();
                    let reference = lqr::plan(&model, &cost, mpc.horizon_steps(), &x);
                    let scale = reference.iter().map(|u| u.amax()).fold(1.0, f64::max);
                    assert_eq!(mpc.last_solve().status, "Solved");
                    assert_eq!(mpc.last_plan().len(), reference.len());
                    assert_eq!(u0, mpc.last_plan()[0]);
                    for (k, (got, want)) in mpc.last_plan().iter().zip(&reference).enumerate() {
                        let error = (got - want).amax();
                        assert!(
                            error < 1e-6 * scale,
                            "{arm} {kind} x={x:?} k={k}: {got:?} vs LQR {want:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn torque_bound_holds_and_is_active_far_from_goal() {
        for arm in arms() {
            for kind in TaskKind::ALL {
                let mut mpc = Mpc::new(&arm, &Task::paper(kind), &MpcOptions::default()).unwrap();
                for x in states() {
                    mpc.control(&x).unwrap();
                    assert_eq!(mpc.last_plan().len(), 20);
                    for u in mpc.last_plan() {
                        assert!(u.amax() <= 5.0 + 1e-7, "{arm} {kind}: {u:?} exceeds 5 Nm");
                    }
                }
            }
        }
        // θ = [3, 2] is 2 and 1.5 rad past θ^g of task 1: the unconstrained optimum asks for
        // more than 5 Nm on these arms, so the bounded one must saturate.
        let task = Task::paper(TaskKind::Position);
        let x = State::new(3.0, 2.0, 0.0, 0.0);
        for arm in [Arm::new(0.6, 0.6, 0.6, 0.6).unwrap(), arms()[1]] {
            let free = Mpc::new(&arm, &task, &unconstrained())
                .unwrap()
                .control(&x)
                .unwrap();
            assert!(
                free.amax() > 5.0,
                "{arm}: unconstrained u0 {free:?} would not test the bound"
            );
            let bounded = Mpc::new(&arm, &task, &MpcOptions::default())
                .unwrap()
                .control(&x)
                .unwrap();
            assert!(
                (bounded.amax() - 5.0).abs() < 1e-6,
                "{arm}: u0 {bounded:?} not at the bound"
            );
        }
    }

    #[test]
    fn same_inputs_give_bitwise_identical_controls() {
        // The original linear MPC is memoryless: a call depends on its state only.
        let arm = arms()[1];
        let task = Task::paper(TaskKind::Velocity);
        let [x1, x2, _] = states();
        let options = MpcOptions::original_linear();
        let mut first = Mpc::new(&arm, &task, &options).unwrap();
        let mut second = Mpc::new(&arm, &task, &options).unwrap();
        let u = first.control(&x1).unwrap();
        let plan = first.last_plan().to_vec();
        assert_eq!(
            second.control(&x1).unwrap().map(f64::to_bits),
            u.map(f64::to_bits)
        );
        // The in-place update leaves no trace: re-solving x1 after x2 is the same computation.
        first.control(&x2).unwrap();
        assert_eq!(
            first.control(&x1).unwrap().map(f64::to_bits),
            u.map(f64::to_bits)
        );
        let bits = |p: &[Vector2]| {
            p.iter()
                .flat_map(|u| u.iter().map(|v| v.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(first.last_plan()), bits(&plan));
    }

    #[test]
    fn invalid_options_name_the_value() {
        let arm = arms()[0];
        let task = Task::paper(TaskKind::Position);
        let d = MpcOptions::default();
        let cases = [
            (MpcOptions { period: 0.0, ..d }, "period = 0"),
            (MpcOptions { period: -0.05, ..d }, "period = -0.05"),
            (
                MpcOptions {
                    period: f64::NAN,
                    ..d
                },
                "period = NaN",
            ),
            (MpcOptions { horizon: 0.01, ..d }, "horizon = 0.01"),
            (
                MpcOptions {
                    horizon: f64::NAN,
                    ..d
                },
                "horizon = NaN",
            ),
            (
                MpcOptions {
                    horizon: f64::INFINITY,
                    ..d
                },
                "horizon = inf",
            ),
            (
                MpcOptions {
                    torque_limit: f64::NAN,
                    ..d
                },
                "torque_limit = NaN",
            ),
            (
                MpcOptions {
                    torque_limit: 0.0,
                    ..d
                },
                "torque_limit = 0",
            ),
            (
                MpcOptions { horizon: 1e6, ..d },
                "horizon / period = 1000000",
            ),
            (
                MpcOptions {
                    observer_gain: 0.0,
                    ..d
                },
                "observer_gain = 0",
            ),
            (
                MpcOptions {
                    observer_gain: 1.5,
                    ..d
                },
                "observer_gain = 1.5",
            ),
            (
                MpcOptions {
                    observer_gain: f64::NAN,
                    ..d
                },
                "observer_gain = NaN",
            ),
        ];
        for (options, named) in cases {
            match Mpc::new(&arm, &task, &options) {
                Err(MpcError::InvalidOptions { reason }) => {
                    assert!(reason.contains(named), "{reason:?} lacks {named:?}")
                }
                other => panic!(
                    "{options:?}: expected InvalidOptions, got {:?}",
                    other.map(|_| ())
                ),
            }
        }
    }

    #[test]
    fn non_finite_state_is_a_solve_error_with_its_step() {
        let mut mpc = Mpc::new(
            &arms()[0],
            &Task::paper(TaskKind::Position),
            &MpcOptions::default(),
        )
        .unwrap();
        mpc.control(&Arm::equilibrium_state()).unwrap();
        let err = mpc
            .control(&State::new(f64::NAN, 0.0, 0.0, 0.0))
            .unwrap_err();
        assert!(matches!(err, MpcError::Solve { step: 1, .. }), "{err:?}");
        assert!(mpc.last_plan().is_empty());
    }

    #[test]
    fn local_model_at_the_equilibrium_is_the_equilibrium_model() {
        let xe = Arm::equilibrium_state();
        for arm in arms() {
            // The generated Jacobian at (X^e, 0) is the paper's A, B, and f(X^e, 0) = 0.
            let (a, b) = arm2::dynamics_jacobian(&xe, &Vector2::zeros(), &arm.params());
            assert!((a - arm.state_matrix()).amax() < 1e-12 * arm.state_matrix().amax());
            assert!((b - arm.input_matrix()).amax() < 1e-12 * arm.input_matrix().amax());
            assert!(arm.dynamics(&xe, &Vector2::zeros()).amax() < 1e-12);
            for kind in TaskKind::ALL {
                let task = Task::paper(kind);
                let mut reference = Mpc::new(&arm, &task, &MpcOptions::original_linear()).unwrap();
                let want = reference.control(&xe).unwrap();
                let scale = want.amax().max(1.0);
                for observer in [false, true] {
                    let options = MpcOptions {
                        model: MpcModel::Local,
                        disturbance_observer: observer,
                        ..MpcOptions::default()
                    };
                    // First call: u_prev = 0, d̂ = 0, so the QP is re-linearised at (X^e, 0).
                    let mut local = Mpc::new(&arm, &task, &options).unwrap();
                    let got = local.control(&xe).unwrap();
                    assert!(
                        (got - want).amax() < 1e-9 * scale,
                        "{arm} {kind} observer={observer}: {got:?} vs {want:?}"
                    );
                    for (g, w) in local.last_plan().iter().zip(reference.last_plan()) {
                        assert!((g - w).amax() < 1e-9 * scale, "{arm} {kind}: plan differs");
                    }
                }
            }
        }
    }

    #[test]
    fn observer_recovers_a_constant_disturbance_on_the_linear_model() {
        // Plant = the equilibrium model with ΔT added at its input: with L = 1 the first
        // update is exact (the model's one-step prediction error is Bd·ΔT), with L = ½ the
        // error halves every step.
        let arm = arms()[1];
        let task = Task::paper(TaskKind::Position);
        let (a, b, xe) = (
            arm.state_matrix(),
            arm.input_matrix(),
            Arm::equilibrium_state(),
        );
        let plant = discretise(&a, &b, &(-a * xe), 0.05);
        let disturbance = Vector2::new(-0.3, 0.7);
        for gain in [1.0, 0.5] {
            let options = MpcOptions {
                observer_gain: gain,
                ..MpcOptions::original_linear()
            };
            let options = MpcOptions {
                disturbance_observer: true,
                ..options
            };
            let mut mpc = Mpc::new(&arm, &task, &options).unwrap();
            let mut x = xe;
            for step in 1..=40 {
                let u = mpc.control(&x).unwrap();
                x = plant.ad * x + plant.bd * (u + disturbance) + plant.cd;
                let expected = (1.0 - (1.0 - gain).powi(step - 1)) * disturbance;
                let got = mpc.disturbance_estimate();
                assert!(
                    (got - expected).amax() < 1e-9,
                    "L={gain}, step {step}: {got:?} vs {expected:?}"
                );
            }
            mpc.control(&x).unwrap();
            assert!((mpc.disturbance_estimate() - disturbance).amax() < 1e-9);
            mpc.reset();
            assert_eq!(mpc.disturbance_estimate(), Vector2::zeros());
        }
    }

    #[test]
    fn local_mpc_is_reproducible_after_reset() {
        let arm = arms()[2];
        let task = Task::paper(TaskKind::Velocity);
        let mut mpc = Mpc::new(&arm, &task, &MpcOptions::default()).unwrap();
        let [_, x1, x2] = states();
        let first = [mpc.control(&x1).unwrap(), mpc.control(&x2).unwrap()];
        assert_ne!(mpc.disturbance_estimate(), Vector2::zeros());
        mpc.reset();
        let again = [mpc.control(&x1).unwrap(), mpc.control(&x2).unwrap()];
        assert_eq!(
            first.map(|u| u.map(f64::to_bits)),
            again.map(|u| u.map(f64::to_bits))
        );
    }

    #[test]
    fn mpc_can_move_to_worker_threads() {
        // Experiments run one controller per arm on rayon's pool.
        fn send_and_sync<T: Send + Sync>() {}
        send_and_sync::<Mpc>();
    }
}
