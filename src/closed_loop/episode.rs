//! One episode of the paper's 2-DOF arm: a façade over the generic episode
//! ([`crate::model::episode_on`]), keeping the 2-link options (with the run-time [`Plant`]) and
//! errors that name the arm.

use super::system::Plant;
use crate::integrate::{IntegrationError, Options as IntegratorOptions};
use crate::model::runtime::{run_episode, EpisodeFailure, DIVERGENCE_BOUND};
use crate::model::{Arm2, Arm2Exact, Arm2Tool, EpisodeN, EpisodeOptionsN, TaskN, TrajectoryN};
use crate::{Arm, Error, State, Task, Vector2};

pub use crate::model::Metrics;

/// Options of one episode; `Default` is the paper's "Implementation details"
/// ([`EpisodeOptionsN::paper`] for the 2-link arm, on the paper's plant).
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeOptions {
    /// End time (s) (paper: 5).
    pub t_end: f64,
    /// Output grid spacing (s) (paper: 0.05, 101 points).
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
    /// default [`crate::integrate::Method::Auto`] runs DP5 (`ode45`) on tasks 1 and 2, the
    /// paper's runs, and the DP5-to-Rodas5P switch on task 3, whose θ̈ feedback (P^θ̈ = 10
    /// acting through ∂θ̈/∂U ~ 3/(m2·l2²)) makes it stiff. Hairer's test would find tasks 1 and 2
    /// stiff for small arms too (their P^θ̈ = 1), and switching there would move the paper's
    /// numbers.
    pub integrator: IntegratorOptions,
    /// Keep the trajectory on the output grid (the metrics are computed either way).
    pub record_trajectory: bool,
    /// The equations of motion of the simulated arm (default: the paper's generative process).
    pub plant: Plant,
}

impl Default for EpisodeOptions {
    fn default() -> Self {
        let o = EpisodeOptionsN::paper::<Arm2, 4, 6>();
        Self {
            t_end: o.t_end,
            dt: o.dt,
            x0: o.x0,
            u0: o.u0,
            perturbation: o.perturbation,
            learning_rate: o.learning_rate,
            integrator: o.integrator,
            record_trajectory: o.record_trajectory,
            plant: Plant::Paper,
        }
    }
}

/// The trajectory on the output grid.
pub type Trajectory = TrajectoryN<2>;

/// One episode's metrics and, if asked for, trajectory.
pub type Episode = EpisodeN<2>;

/// Why an episode failed, with the tool, time and reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimulationError {
    #[error(transparent)]
    Input(#[from] Error),
    #[error("simulation of arm {arm} failed: {source}")]
    Integration { arm: Arm, source: IntegrationError },
    #[error("simulation of arm {arm} diverged at t = {} s: |state| = {magnitude:e} exceeds {DIVERGENCE_BOUND:e}", crate::display::Short(*t))]
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

    fn named(failure: EpisodeFailure, arm: Arm) -> Self {
        match failure {
            EpisodeFailure::Input(e) => SimulationError::Input(e),
            EpisodeFailure::Integration(source) => SimulationError::Integration { arm, source },
            EpisodeFailure::Diverged { t, magnitude } => {
                SimulationError::Diverged { arm, t, magnitude }
            }
        }
    }
}

/// Runs one episode of `arm` on `task`: the generic episode of the paper's model, on the plant
/// `options.plant` chooses. The plant is matched here, once, so that the integrator runs the
/// monomorphised closed loop of that plant.
pub fn simulate(
    arm: &Arm,
    task: &Task,
    options: &EpisodeOptions,
) -> Result<Episode, SimulationError> {
    let tool = Arm2Tool::from(arm);
    let task = TaskN::from(task);
    let generic = EpisodeOptionsN::from(options);
    match options.plant {
        Plant::Paper => run_episode::<Arm2, Arm2, 2, 4, 4, 6>(&tool, &task, &generic),
        Plant::Exact => run_episode::<Arm2, Arm2Exact, 2, 4, 4, 6>(&tool, &task, &generic),
    }
    .map_err(|failure| SimulationError::named(failure, *arm))
}

impl From<&EpisodeOptions> for EpisodeOptionsN<2, 4> {
    /// The 2-link options as they are (X0 and U0 included); `plant` is not used.
    fn from(o: &EpisodeOptions) -> Self {
        Self {
            t_end: o.t_end,
            dt: o.dt,
            x0: o.x0,
            u0: o.u0,
            perturbation: o.perturbation,
            joint_perturbation: nalgebra::SVector::zeros(),
            learning_rate: o.learning_rate,
            integrator: o.integrator,
            record_trajectory: o.record_trajectory,
        }
    }
}
