//! One episode: the closed loop of plant and active-inference controller integrated over the
//! paper's horizon, with the metrics the decision-maker ranks tools by.
//!
//! The joint state is Z = [X; U] = [θ1 θ2 θ̇1 θ̇2 T1 T2]. The plant is the nonlinear generative
//! process Ẋ = f(X, U + ΔT) with a constant torque perturbation ΔT on both joints; the
//! controller observes θ, θ̇ and the plant's θ̈ and updates U̇ = −γ ∂F/∂U (eq. U_dot_deriv).

use super::system::{ClosedLoop, Plant};
use crate::integrate::{
    solve_grid_with_jacobian, uniform_grid, IntegrationError, Method, Options as IntegratorOptions,
};
use crate::{Arm, Error, State, Task, TaskKind, Vector2};

pub use super::system::JointState;

/// A grid state whose magnitude passes this is a diverging simulation, not a result.
const DIVERGENCE_BOUND: f64 = 1e6;

/// Options of one episode; `Default` is the paper's "Implementation details".
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeOptions {
    /// End time [s] (paper: 5).
    pub t_end: f64,
    /// Output grid spacing [s] (paper: 0.05, 101 points).
    pub dt: f64,
    /// Initial state X0 (paper: X^e = [−π/2 −π/2 0 0]).
    pub x0: State,
    /// Initial torque U0 (paper: [0.1 0.1]).
    pub u0: Vector2,
    /// Constant torque perturbation ΔT on both joints [N m] (default 0).
    pub perturbation: f64,
    /// Learning rate γ (default 1).
    pub learning_rate: f64,
    /// Integrator tolerances (defaults: MATLAB ode45's, rtol 1e-3, atol 1e-6) and method. The
    /// default [`Method::Auto`] runs DP5 (`ode45`) on tasks 1 and 2, the paper's runs, and the
    /// DP5-to-Rodas5P switch on task 3, whose θ̈ feedback (P^θ̈ = 10 acting through
    /// ∂θ̈/∂U ~ 3/(m2·l2²)) makes it stiff. Hairer's test would find tasks 1 and 2 stiff for small
    /// arms too (their P^θ̈ = 1), and switching there would move the paper's numbers.
    pub integrator: IntegratorOptions,
    /// Keep the trajectory on the output grid (the metrics are computed either way).
    pub record_trajectory: bool,
    /// The equations of motion of the simulated arm (default: the paper's generative process).
    pub plant: Plant,
}

impl Default for EpisodeOptions {
    fn default() -> Self {
        Self {
            t_end: 5.0,
            dt: 0.05,
            x0: Arm::equilibrium_state(),
            u0: Vector2::new(0.1, 0.1),
            perturbation: 0.0,
            learning_rate: 1.0,
            integrator: IntegratorOptions::default(),
            record_trajectory: false,
            plant: Plant::Paper,
        }
    }
}

/// The trajectory on the output grid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectory {
    pub t: Vec<f64>,
    pub theta: Vec<Vector2>,
    pub theta_dot: Vec<Vector2>,
    /// The plant's θ̈ = f(X, U + ΔT), what the controller observes.
    pub theta_ddot: Vec<Vector2>,
    pub u: Vec<Vector2>,
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
}

#[derive(Debug, Clone, PartialEq)]
pub struct Episode {
    pub metrics: Metrics,
    pub trajectory: Option<Trajectory>,
}

/// Why an episode failed, with the tool, time and reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimulationError {
    #[error(transparent)]
    Input(#[from] Error),
    #[error("simulation of arm {arm} failed: {source}")]
    Integration { arm: Arm, source: IntegrationError },
    #[error("simulation of arm {arm} diverged at t = {t} s: |state| = {magnitude:e} exceeds {DIVERGENCE_BOUND:e}")]
    Diverged { arm: Arm, t: f64, magnitude: f64 },
}

impl SimulationError {
    /// The time the failure happened at, if it is a failure of the simulation itself.
    pub fn time(&self) -> Option<f64> {
        match self {
            SimulationError::Input(_) => None,
            SimulationError::Integration { source, .. } => source.time(),
            SimulationError::Diverged { t, .. } => Some(*t),
        }
    }
}

/// Runs one episode of `arm` on `task`.
pub fn simulate(
    arm: &Arm,
    task: &Task,
    options: &EpisodeOptions,
) -> Result<Episode, SimulationError> {
    check_options(options)?;
    let system = ClosedLoop::with_plant(
        arm,
        task,
        options.learning_rate,
        options.perturbation,
        options.plant,
    )?;
    let controller = &system.controller;
    let grid = uniform_grid(0.0, options.t_end, options.dt);
    let mut z0 = JointState::zeros();
    z0.fixed_rows_mut::<4>(0).copy_from(&options.x0);
    z0.fixed_rows_mut::<2>(4).copy_from(&options.u0);

    let mut trajectory = options.record_trajectory.then(|| Trajectory {
        t: Vec::with_capacity(grid.len()),
        ..Trajectory::default()
    });
    let mut task_error = 0.0;
    let (mut int_f, mut int_j, mut effort) = (0.0, 0.0, 0.0);
    // (t, F, J, |U|²) at the previous grid point, for the trapezoidal rule.
    let mut previous: Option<(f64, f64, f64, f64)> = None;
    let mut divergence: Option<(f64, f64)> = None;

    let rhs = |_t: f64, z: &JointState| system.rhs(z);
    // The closed loop is autonomous: ∂Ż/∂t = 0.
    let jacobian = |_t: f64, z: &JointState| (system.jacobian(z), JointState::zeros());
    let mut integrator = options.integrator;
    if integrator.method == Method::Auto && task.kind != TaskKind::Acceleration {
        integrator.method = Method::Explicit;
    }
    let stats = solve_grid_with_jacobian(rhs, jacobian, &z0, &grid, &integrator, |_, t, z| {
        let (_, theta_ddot) = system.rhs_and_acceleration(z);
        let theta = z.fixed_rows::<2>(0).into_owned();
        let theta_dot = z.fixed_rows::<2>(2).into_owned();
        let u = z.fixed_rows::<2>(4).into_owned();
        let magnitude = z.amax();
        if divergence.is_none() && magnitude > DIVERGENCE_BOUND {
            divergence = Some((t, magnitude));
        }
        task_error += controller.task_error(&theta, &theta_dot, &theta_ddot);
        let j = controller.cost_j(&theta, &theta_dot, &theta_ddot, &u);
        let f = j - 0.5 * controller.logdet;
        let e = u.norm_squared();
        if let Some((t_prev, f_prev, j_prev, e_prev)) = previous {
            let h = t - t_prev;
            int_f += 0.5 * h * (f + f_prev);
            int_j += 0.5 * h * (j + j_prev);
            effort += 0.5 * h * (e + e_prev);
        }
        previous = Some((t, f, j, e));
        if let Some(tr) = trajectory.as_mut() {
            tr.t.push(t);
            tr.theta.push(theta);
            tr.theta_dot.push(theta_dot);
            tr.theta_ddot.push(theta_ddot);
            tr.u.push(u);
        }
    })
    .map_err(|source| SimulationError::Integration { arm: *arm, source })?;

    if let Some((t, magnitude)) = divergence {
        return Err(SimulationError::Diverged {
            arm: *arm,
            t,
            magnitude,
        });
    }
    let metrics = Metrics {
        task_error,
        free_energy: int_f,
        cost_j: int_j,
        logdet: controller.logdet,
        rhs_evals: stats.rhs_evals,
        steps: stats.steps,
        rejected_steps: stats.rejected,
        control_effort: effort,
        jacobian_evals: stats.jacobian_evals,
        factorisations: stats.factorisations,
    };
    if ![metrics.task_error, metrics.free_energy, metrics.cost_j]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(SimulationError::Diverged {
            arm: *arm,
            t: options.t_end,
            magnitude: f64::INFINITY,
        });
    }
    Ok(Episode {
        metrics,
        trajectory,
    })
}

fn check_options(o: &EpisodeOptions) -> Result<(), Error> {
    crate::model::runtime::check_options(&crate::model::runtime::EpisodeOptionsN::<2, 4>::from(o))
}
