//! Control confidence Π^U = ∂²F/∂U² (eq. control_conf) and the task sensitivities it is built
//! from (appendix "Task specific controllers") for the paper's 2-DOF arm.
//!
//! A façade: the implementation is the model-generic [`crate::model::control_confidence`] and
//! [`crate::model::ArmModel`] with [`Arm2`]; this keeps the paper's `Arm`/`Task` API.

use crate::model::{self, Arm2, Arm2Tool, ArmModel, ControlConfidenceN, SensitivitiesN, TaskN};
use crate::{Arm, Error, Matrix2, Task, TaskKind};

/// The sensitivities ∂(task variable)/∂U that a task's controller uses (eq. U_dot_deriv), for
/// the 2-DOF arm. A term the task does not use is `None`.
pub type Sensitivities = SensitivitiesN<2>;

/// Π^U (2×2) with its log-determinant ln|Π^U|, the confidence term of the free energy.
pub type ControlConfidence = ControlConfidenceN<2>;

/// The task sensitivities of an arm, from the generated closed forms.
pub fn sensitivities(arm: &Arm, kind: TaskKind) -> Sensitivities {
    Arm2::sensitivities(kind, &arm.params())
}

/// The closed-form control confidence of `arm` for `task`
/// ([`crate::model::control_confidence`]; ln|Π^U| is the 2×2 determinant's logarithm).
///
/// Errors if the task is invalid or Π^U is not positive definite (possible only with user
/// precisions, e.g. all zero).
pub fn control_confidence(arm: &Arm, task: &Task) -> Result<ControlConfidence, Error> {
    model::control_confidence(&Arm2Tool::from(arm), &TaskN::from(task))
}

/// Π^U without validating the task. To rank many tools, check the task once with
/// [`Task::validated`] and use [`crate::model::ValidatedTaskN::pi_u`] or `control_confidence`.
pub fn pi_u(arm: &Arm, task: &Task) -> Matrix2 {
    Arm2::pi_u(&TaskN::from(task), &arm.params())
}
