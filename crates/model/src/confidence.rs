//! Control confidence Π^U = ∂²F/∂U² (eq. control_conf) and the task sensitivities it is built
//! from (appendix "Task specific controllers") for the paper's 2-DOF arm: the generic
//! [`crate::model::control_confidence`] with [`crate::model::Arm2`], under the 2-link names.

pub use crate::model::control_confidence;
use crate::model::{ControlConfidenceN, SensitivitiesN};

/// The sensitivities ∂(task variable)/∂U that a task's controller uses (eq. U_dot_deriv), for
/// the 2-DOF arm (`arm.sensitivities(kind)`). A term the task does not use is `None`.
pub type Sensitivities = SensitivitiesN<2>;

/// Π^U (2×2) with its log-determinant ln|Π^U|, the confidence term of the free energy.
pub type ControlConfidence = ControlConfidenceN<2>;
