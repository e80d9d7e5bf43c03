//! The receding-horizon controller ([`MpcN`], generic over the arm model; [`Mpc`] for the
//! paper's arm); the formulation is in the module docs of [`crate::mpc`].

use std::marker::PhantomData;
use std::time::{Duration, Instant};

use clarabel::solver::SolverStatus;
use nalgebra::{SMatrix, SVector};

use super::discretise::{discretise, Discretised};
use super::options::{MpcError, MpcModel, MpcOptions, SolveInfo};
use super::qp::{QpSolver, StageCost};
use toolconf_model::model::{Arm2, ArmModel, TaskN, ToolN};

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

/// The MPC of the paper's 2-DOF arm: [`MpcN`] with [`Arm2`] (`Mpc::new(&arm, &task, &options)`).
pub type Mpc = MpcN<Arm2, 2, 4, 4, 6>;
