//! Episode options shared by the commands that simulate (defaults: the paper's).

use toolconf::closed_loop::{EpisodeOptions, Plant};
use toolconf::Error;

#[derive(clap::Args, Debug, Clone)]
pub struct EpisodeArgs {
    /// Constant torque perturbation ΔT on both joints [N m].
    #[arg(long = "perturb", default_value_t = 0.0, allow_hyphen_values = true)]
    pub perturbation: f64,
    /// End time of the episode [s].
    #[arg(long, default_value_t = 5.0, allow_hyphen_values = true)]
    pub t_end: f64,
    /// Output grid spacing [s].
    #[arg(long, default_value_t = 0.05, allow_hyphen_values = true)]
    pub dt: f64,
    /// Learning rate γ of the controller.
    #[arg(long = "gamma", default_value_t = 1.0, allow_hyphen_values = true)]
    pub learning_rate: f64,
    /// Integrator relative tolerance (ode45 default 1e-3).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    pub rtol: f64,
    /// Integrator absolute tolerance (ode45 default 1e-6).
    #[arg(long, default_value_t = 1e-6, allow_hyphen_values = true)]
    pub atol: f64,
    /// Plant: the paper's generative process, or the exact Lagrangian 2-link dynamics.
    #[arg(long, value_enum, default_value_t = PlantArg::Paper)]
    pub plant: PlantArg,
}

/// The simulated arm's equations of motion (the agent always uses the paper's model).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PlantArg {
    /// The paper's generative process (appendix "Tool Dynamics").
    #[default]
    Paper,
    /// The exact 2-link Lagrangian dynamics of the same arm.
    Exact,
}

impl From<PlantArg> for Plant {
    fn from(p: PlantArg) -> Self {
        match p {
            PlantArg::Paper => Plant::Paper,
            PlantArg::Exact => Plant::Exact,
        }
    }
}

impl EpisodeArgs {
    pub fn options(&self, record_trajectory: bool) -> Result<EpisodeOptions, Error> {
        for (name, value) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::InvalidOption { name, value });
            }
        }
        let mut o = EpisodeOptions {
            t_end: self.t_end,
            dt: self.dt,
            perturbation: self.perturbation,
            learning_rate: self.learning_rate,
            record_trajectory,
            plant: self.plant.into(),
            ..EpisodeOptions::default()
        };
        o.integrator.rtol = self.rtol;
        o.integrator.atol = self.atol;
        Ok(o)
    }
}
