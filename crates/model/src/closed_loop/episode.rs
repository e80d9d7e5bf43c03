//! One episode of the paper's 2-DOF arm: the generic episode ([`crate::model::episode_on`]) on
//! the plant [`Plant`] picks, its errors naming the arm (`arm m1=…`).

use super::system::Plant;
use crate::model::closed_loop_n::run_episode;
use crate::model::{Arm2, Arm2Exact, EpisodeN, EpisodeOptionsN, ModelSimulationError, TrajectoryN};
use crate::{Arm, Task};

pub use crate::model::Metrics;

/// Options of one episode of the paper's arm; `Default` is the paper's "Implementation details"
/// ([`EpisodeOptionsN::paper`] of [`Arm2`]).
pub type EpisodeOptions = EpisodeOptionsN<2, 4>;

/// The paper's options for its arm: t_end = 5 s, dt = 0.05 s (101 points), X0 = X^e =
/// [−π/2 −π/2 0 0], U0 = [0.1 0.1], ΔT = 0, γ = 1, MATLAB ode45's tolerances (rtol 1e-3,
/// atol 1e-6) and [`toolconf_integrators::Method::Auto`]: DP5 (`ode45`) on tasks 1 and 2, the
/// paper's runs, and the DP5-to-Rodas5P switch on task 3, whose θ̈ feedback (P^θ̈ = 10 acting
/// through ∂θ̈/∂U ~ 3/(m2·l2²)) makes it stiff. Hairer's test would find tasks 1 and 2 stiff
/// for small arms too (their P^θ̈ = 1), and switching there would move the paper's numbers.
impl Default for EpisodeOptionsN<2, 4> {
    fn default() -> Self {
        EpisodeOptionsN::paper::<Arm2, 4, 6>()
    }
}

/// The trajectory on the output grid.
pub type Trajectory = TrajectoryN<2>;

/// One episode's metrics and, if asked for, trajectory.
pub type Episode = EpisodeN<2>;

/// Why an episode failed, with the tool (`arm m1=…` here), the time and the reason.
pub type SimulationError = ModelSimulationError;

/// Runs one episode of `arm` on `task` on the paper's plant ([`Plant::simulate`]).
pub fn simulate(
    arm: &Arm,
    task: &Task,
    options: &EpisodeOptions,
) -> Result<Episode, SimulationError> {
    Plant::Paper.simulate(arm, task, options)
}

impl Plant {
    /// One episode of `arm` (the paper's model as the agent's) on `task`, simulated on this
    /// plant: the generic episode on `Arm2` or `Arm2Exact`, matched here once.
    pub fn simulate(
        self,
        arm: &Arm,
        task: &Task,
        options: &EpisodeOptions,
    ) -> Result<Episode, SimulationError> {
        match self {
            Plant::Paper => run_episode::<Arm2, Arm2, 2, 4, 4, 6>(arm, task, options),
            Plant::Exact => run_episode::<Arm2, Arm2Exact, 2, 4, 4, 6>(arm, task, options),
        }
        .map_err(|failure| ModelSimulationError::named(failure, || format!("arm {arm}")))
    }
}
