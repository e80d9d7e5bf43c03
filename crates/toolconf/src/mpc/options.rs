//! What the MPC baseline is asked to do ([`MpcOptions`], [`MpcModel`]) and what it reports
//! ([`SolveInfo`], [`MpcError`]).

use std::time::Duration;

use toolconf_messages::Short;

/// The linear model the QP plans with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MpcModel {
    /// The paper's linearisation ẋ = A(x − X^e) + Bu at the hanging equilibrium, fixed for the
    /// whole episode: the original linear MPC baseline.
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
    /// The original linear MPC baseline: the default timing and bound, the equilibrium model
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
pub(super) const MAX_HORIZON_STEPS: usize = 10_000;

impl MpcOptions {
    /// Checks the options; the number of steps N, or why these options are unusable.
    pub(super) fn horizon_steps(&self) -> Result<usize, MpcError> {
        let invalid = |reason: String| Err(MpcError::InvalidOptions { reason });
        if !(self.period.is_finite() && self.period > 0.0) {
            return invalid(format!(
                "period = {} s: must be a finite number > 0",
                Short(self.period)
            ));
        }
        if !(self.horizon.is_finite() && self.horizon >= self.period) {
            return invalid(format!(
                "horizon = {} s: must be finite and at least the period ({} s)",
                Short(self.horizon),
                Short(self.period)
            ));
        }
        if self.torque_limit.is_nan() || self.torque_limit <= 0.0 {
            return invalid(format!(
                "torque_limit = {} Nm: must be > 0 (or infinite for no bound)",
                Short(self.torque_limit)
            ));
        }
        if !(self.observer_gain > 0.0 && self.observer_gain <= 1.0) {
            return invalid(format!(
                "observer_gain = {}: must be in (0, 1]",
                Short(self.observer_gain)
            ));
        }
        let steps = (self.horizon / self.period).round();
        if steps > MAX_HORIZON_STEPS as f64 {
            return invalid(format!(
                "horizon / period = {} / {} = {} steps: at most {MAX_HORIZON_STEPS}",
                Short(self.horizon),
                Short(self.period),
                Short(steps)
            ));
        }
        Ok(steps as usize)
    }

    /// What an episode of `t_end` s output every `dt` s checks of these options, before it runs:
    /// the horizon's steps ([`MAX_HORIZON_STEPS`] at most), and t_end and dt whole numbers of
    /// periods; the reason in words. The front ends call it before any episode starts.
    pub fn check_grid(&self, t_end: f64, dt: f64) -> Result<(), String> {
        self.horizon_steps().map_err(|e| match e {
            MpcError::InvalidOptions { reason } => reason,
            other => other.to_string(),
        })?;
        for (name, total) in [("t_end", t_end), ("dt", dt)] {
            if super::episode::whole_ratio(total, self.period).is_none() {
                return Err(format!(
                    "{name} = {} s is not a whole number of MPC periods ({} s)",
                    Short(total),
                    Short(self.period)
                ));
            }
        }
        Ok(())
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
    /// [`super::MpcN::control`].
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
