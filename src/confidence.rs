//! Control confidence Π^U = ∂²F/∂U² (eq. control_conf) and the task sensitivities it is built
//! from (appendix "Task specific controllers"), both from the generated closed forms.

use crate::generated::arm2;
use crate::{Arm, Error, Matrix2, Task, TaskKind};

/// The sensitivities ∂(task variable)/∂U that a task's controller uses (eq. U_dot_deriv).
/// A term the task does not use is `None`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensitivities {
    /// ∂θ/∂U (task 1 only): [I O]A⁻¹(∂Ẋ/∂U − B) with ∂Ẋ/∂U = [I; I].
    pub d_theta_du: Option<Matrix2>,
    /// ∂θ̇/∂U: [O I]A⁻¹(∂Ẋ/∂U − B) = I in task 1; −[I O]A⁻¹B in task 2, as the paper prints it.
    pub d_theta_dot_du: Option<Matrix2>,
    /// ∂θ̈/∂U: I in tasks 1–2 (zero jerk); [I O](A²∂X/∂U + AB) in task 3, which is I too.
    pub d_theta_ddot_du: Matrix2,
}

/// The task sensitivities of an arm, from the generated closed forms.
pub fn sensitivities(arm: &Arm, kind: TaskKind) -> Sensitivities {
    let p = arm.params();
    match kind {
        TaskKind::Position => {
            let (d_theta, d_theta_dot, d_theta_ddot) = arm2::position_sensitivity(&p);
            Sensitivities {
                d_theta_du: Some(d_theta),
                d_theta_dot_du: Some(d_theta_dot),
                d_theta_ddot_du: d_theta_ddot,
            }
        }
        TaskKind::Velocity => {
            let (d_theta_dot, d_theta_ddot) = arm2::velocity_sensitivity(&p);
            Sensitivities {
                d_theta_du: None,
                d_theta_dot_du: Some(d_theta_dot),
                d_theta_ddot_du: d_theta_ddot,
            }
        }
        TaskKind::Acceleration => Sensitivities {
            d_theta_du: None,
            d_theta_dot_du: None,
            d_theta_ddot_du: arm2::acceleration_sensitivity(&p),
        },
    }
}

/// Π^U with its log-determinant ln|Π^U|, the confidence term of the free energy (eq. FE_components).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlConfidence {
    /// Π^U, symmetric positive definite.
    pub pi_u: Matrix2,
    /// ln|Π^U|.
    pub logdet: f64,
}

/// The closed-form control confidence of `arm` for `task` (eq. control_conf and the closed
/// forms after it): Π^U = Σ Sᵀ P S over the task's terms, plus P^U.
///
/// It depends only on the arm and the task's precisions, so it can be computed before the tool
/// is used. Errors if the task is invalid or Π^U is not positive definite (possible only with
/// user precisions, e.g. all zero).
pub fn control_confidence(arm: &Arm, task: &Task) -> Result<ControlConfidence, Error> {
    task.validate()?;
    let pi_u = pi_u(arm, task);
    // Π^U is 2×2 symmetric: positive definite iff its (0,0) entry and determinant are > 0, and
    // ln|Π^U| is then one logarithm. This is exact and cheaper than a general Cholesky.
    let determinant = pi_u[(0, 0)] * pi_u[(1, 1)] - pi_u[(0, 1)] * pi_u[(1, 0)];
    if !(pi_u[(0, 0)] > 0.0 && determinant > 0.0 && determinant.is_finite()) {
        return Err(Error::NotPositiveDefinite { determinant });
    }
    Ok(ControlConfidence {
        pi_u,
        logdet: determinant.ln(),
    })
}

/// Π^U without validation; the hot path for ranking many tools with one validated task.
pub fn pi_u(arm: &Arm, task: &Task) -> Matrix2 {
    let p = arm.params();
    match task.kind {
        TaskKind::Position => arm2::position_control_confidence(
            &p,
            &task.precision_theta,
            &task.precision_theta_dot,
            &task.precision_theta_ddot,
            &task.precision_u,
        ),
        TaskKind::Velocity => arm2::velocity_control_confidence(
            &p,
            &task.precision_theta_dot,
            &task.precision_theta_ddot,
            &task.precision_u,
        ),
        TaskKind::Acceleration => {
            arm2::acceleration_control_confidence(&p, &task.precision_theta_ddot, &task.precision_u)
        }
    }
}
