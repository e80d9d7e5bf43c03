//! Linear MPC baseline: the paper's cost J (no confidence term) minimised over a receding
//! horizon on the linearised arm, solved as a sparse QP with Clarabel.
//!
//! # Formulation
//!
//! The arm model is the paper's linearisation ẋ = A(x − X^e) + Bu (appendix "Generative
//! model"), discretised exactly with a zero-order hold at the control period (the paper
//! samples at dt = 0.05 s): x_{k+1} = Ad x_k + Bd u_k + cd ([`discretise`]). The offset cd
//! keeps the model in absolute coordinates, so goals and the measured state are used as is.
//!
//! Decision variables are z = (x_0, …, x_N, u_0, …, u_{N−1}), N = round(horizon / period). Keeping
//! x_0 as a variable pinned by the equality x_0 = x puts the measured state in the right-hand
//! side b only: each [`Mpc::control`] call overwrites four entries of b in place (Clarabel's
//! `update_b`), and P, q, A and the cones, set up once in [`Mpc::new`], never change. The
//! states are kept as variables (sparse, "simultaneous" form) rather than eliminated, so P and
//! A stay banded with O(N) non-zeros instead of a dense N×N condensed Hessian.
//!
//! Cost: Σ_{k<N} T·J(x_k, u_k) + T·J_f(x_N), with J the paper's
//! ½[(θ−θ^g)ᵀP^θ(θ−θ^g) + (θ̇−θ̇^g)ᵀP^θ̇(θ̇−θ̇^g) + (θ̈−θ̈^g)ᵀP^θ̈(θ̈−θ̈^g) + UᵀP^U U] and
//! θ̈ = rows 3–4 of A(x_k − X^e) + Bu_k, the model's acceleration during stage k. That makes
//! J a quadratic in (x_k, u_k) with cross terms. Weighting by T makes the sum a Riemann sum
//! of the paper's integral cost. The terminal cost J_f is the state-only part of J (the θ and
//! θ̇ terms): θ̈ depends on a control, and there is no u_N. Task 3 therefore has no terminal
//! cost, and its P^U = 0 leaves P only positive semi-definite; the θ̈ term still makes the
//! reduced Hessian in u (B₃₄ᵀP^θ̈B₃₄) definite, so the optimum is unique and Clarabel solves it.
//!
//! Constraints: the dynamics as equalities (Clarabel's zero cone) and, if the torque limit is
//! finite, |u_k,j| ≤ L as 4N rows in the non-negative cone.
//!
//! Clarabel runs with default tolerances; only `verbose = false` and `presolve_enable = false`
//! are set (presolve would forbid the in-place data update). Each solve starts Clarabel from
//! its default point, so a call's result depends only on its inputs. Without the torque bound
//! the QP has only equalities and Clarabel solves it in one KKT solve (0 iterations).
//!
//! Speed: Clarabel's solver is generic, so it is compiled into this crate at this crate's
//! optimisation level. A bounded solve (N = 20, 6–10 iterations) takes ≈ 0.3–0.45 ms in the
//! release profile but ≈ 6–12 ms in the dev profile; time experiments in release.

mod discretise;
mod episode;
#[cfg(test)]
mod lqr;
mod qp;

use std::time::{Duration, Instant};

use clarabel::solver::SolverStatus;
use nalgebra::SVector;

pub use discretise::{discretise, Discretised};
pub use episode::{simulate_mpc, MpcEpisode, MpcEpisodeError, MpcMetrics};
use qp::{QpSolver, StageCost};

use crate::{Arm, Task, Vector2};

/// Timing and horizon of the controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MpcOptions {
    /// Control period T in s: the zero-order-hold interval and the QP's time step.
    pub period: f64,
    /// Prediction horizon in s, rounded to a whole number N of periods.
    pub horizon: f64,
    /// Bound on |T1| and |T2| in Nm; `f64::INFINITY` for no bound.
    pub torque_limit: f64,
}

impl Default for MpcOptions {
    /// T = 0.05 s (the paper's sampling time), 1 s horizon (N = 20), 5 Nm.
    fn default() -> Self {
        Self {
            period: 0.05,
            horizon: 1.0,
            torque_limit: 5.0,
        }
    }
}

/// Largest N accepted; beyond it the QP is a configuration mistake, not a controller.
const MAX_HORIZON_STEPS: usize = 10_000;

impl MpcOptions {
    /// The number of steps N, or why these options are unusable.
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
    /// The solver did not return a solution at the `step`-th call (0-based) of [`Mpc::control`].
    #[error("MPC solve failed at control step {step}: {status}")]
    Solve { status: String, step: usize },
}

/// Report of the last solve.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveInfo {
    /// Clarabel's status (`Solved`, `AlmostSolved`, …; `Unsolved` before the first call).
    pub status: String,
    pub iterations: u32,
    /// Wall-clock time of the in-place update and the solve. (Clarabel's own `solve_time`
    /// is not used: it also counts the one-off setup, on every solve.)
    pub solve_time: Duration,
}

/// A receding-horizon controller for one (arm, task, options); see the module docs.
pub struct Mpc {
    qp: QpSolver,
    horizon: usize,
    plan: Vec<Vector2>,
    calls: usize,
    info: SolveInfo,
}

impl Mpc {
    /// Discretises the arm's model, builds the QP and sets up Clarabel once.
    pub fn new(arm: &Arm, task: &Task, options: &MpcOptions) -> Result<Self, MpcError> {
        let horizon = options.horizon_steps()?;
        task.validate().map_err(|e| MpcError::Setup {
            reason: e.to_string(),
        })?;
        let (a, b, xe) = (
            arm.state_matrix(),
            arm.input_matrix(),
            Arm::equilibrium_state(),
        );
        let model = discretise(&a, &b, &(-a * xe), options.period);
        let cost = StageCost::new(&a, &b, &xe, task, options.period);
        let qp = QpSolver::new(&model, &cost, horizon, options.torque_limit)
            .map_err(|reason| MpcError::Setup { reason })?;
        let info = SolveInfo {
            status: format!("{:?}", SolverStatus::Unsolved),
            iterations: 0,
            solve_time: Duration::ZERO,
        };
        Ok(Self {
            qp,
            horizon,
            plan: Vec::with_capacity(horizon),
            calls: 0,
            info,
        })
    }

    /// Solves the QP from the measured state x = [θ1 θ2 θ̇1 θ̇2] and returns the first control
    /// move u_0. `AlmostSolved` (Clarabel's reduced-accuracy solution) is accepted and visible
    /// in [`Mpc::last_solve`]; any other non-`Solved` status is an error and clears the plan.
    pub fn control(&mut self, x: &SVector<f64, 4>) -> Result<Vector2, MpcError> {
        let step = self.calls;
        self.calls += 1;
        self.plan.clear();
        if let Some(bad) = x.iter().find(|v| !v.is_finite()) {
            return Err(MpcError::Solve {
                status: format!("state has a non-finite entry {bad}"),
                step,
            });
        }
        let start = Instant::now();
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
        Ok(self.plan[0])
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
    pub fn last_plan(&self) -> &[Vector2] {
        &self.plan
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{State, TaskKind};

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

    fn unconstrained() -> MpcOptions {
        MpcOptions {
            torque_limit: f64::INFINITY,
            ..MpcOptions::default()
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
                let cost = StageCost::new(&a, &b, &xe, &task, options.period);
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
        let arm = arms()[1];
        let task = Task::paper(TaskKind::Velocity);
        let [x1, x2, _] = states();
        let mut first = Mpc::new(&arm, &task, &MpcOptions::default()).unwrap();
        let mut second = Mpc::new(&arm, &task, &MpcOptions::default()).unwrap();
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
    fn mpc_can_move_to_worker_threads() {
        // Experiments run one controller per arm on rayon's pool.
        fn send_and_sync<T: Send + Sync>() {}
        send_and_sync::<Mpc>();
    }
}
