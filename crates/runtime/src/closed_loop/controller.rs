//! The task-based active-inference controller (eq. U_dot_deriv) for the paper's 2-DOF arm: a
//! façade over [`ActiveInferenceN<2>`], the implementation.

use std::ops::Deref;

use crate::model::{ActiveInferenceN, Arm2Tool, TaskN};
use crate::{Arm, Error, Task};

/// The controller of one arm for one task: U̇ = −γ ∂F/∂U.
///
/// A newtype rather than an alias only so that [`ActiveInference::new`] keeps taking an [`Arm`]
/// and a [`Task`]; everything else (`control_rate`, `cost_j`, `free_energy`, `task_error`,
/// `scaled_gains` and the fields `task`, `learning_rate`, `logdet`) is [`ActiveInferenceN<2>`]'s,
/// through `Deref`.
#[derive(Debug, Clone, Copy)]
pub struct ActiveInference(ActiveInferenceN<2>);

impl ActiveInference {
    pub fn new(arm: &Arm, task: &Task, learning_rate: f64) -> Result<Self, Error> {
        ActiveInferenceN::new(&Arm2Tool::from(arm), &TaskN::from(task), learning_rate).map(Self)
    }

    /// The generic controller this is.
    pub fn generic(&self) -> &ActiveInferenceN<2> {
        &self.0
    }
}

impl Deref for ActiveInference {
    type Target = ActiveInferenceN<2>;

    fn deref(&self) -> &ActiveInferenceN<2> {
        &self.0
    }
}

impl From<ActiveInferenceN<2>> for ActiveInference {
    fn from(controller: ActiveInferenceN<2>) -> Self {
        Self(controller)
    }
}
