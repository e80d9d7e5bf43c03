//! The closed-loop system Ż = [f(X, U + ΔT); −γ ∂F/∂U] and its Jacobian, the object the
//! integrators see.

use nalgebra::{SMatrix, SVector};

use super::controller::ActiveInference;
use crate::generated::arm2;
use crate::{Arm, Error, Task, Vector2};

/// The closed-loop state Z = [X; U] = [θ1 θ2 θ̇1 θ̇2 T1 T2].
pub type JointState = SVector<f64, 6>;
/// ∂Ż/∂Z.
pub type JointJacobian = SMatrix<f64, 6, 6>;

/// Plant (the nonlinear generative process with a constant torque perturbation ΔT on both
/// joints) and active-inference controller, which observes θ, θ̇ and the plant's θ̈.
#[derive(Debug, Clone, Copy)]
pub struct ClosedLoop {
    params: SVector<f64, 4>,
    pub controller: ActiveInference,
    perturbation: Vector2,
}

impl ClosedLoop {
    pub fn new(
        arm: &Arm,
        task: &Task,
        learning_rate: f64,
        perturbation: f64,
    ) -> Result<Self, Error> {
        if !perturbation.is_finite() {
            return Err(Error::InvalidOption {
                name: "perturbation dT",
                value: perturbation,
            });
        }
        Ok(Self {
            params: arm.params(),
            controller: ActiveInference::new(arm, task, learning_rate)?,
            perturbation: Vector2::repeat(perturbation),
        })
    }

    /// Ż and the plant's θ̈ (what the controller observes).
    #[inline]
    pub fn rhs_and_acceleration(&self, z: &JointState) -> (JointState, Vector2) {
        let x = z.fixed_rows::<4>(0).into_owned();
        let u = z.fixed_rows::<2>(4).into_owned();
        let x_dot = arm2::dynamics(&x, &(u + self.perturbation), &self.params);
        let theta = x.fixed_rows::<2>(0).into_owned();
        let theta_dot = x.fixed_rows::<2>(2).into_owned();
        let theta_ddot = x_dot.fixed_rows::<2>(2).into_owned();
        let u_dot = self
            .controller
            .control_rate(&theta, &theta_dot, &theta_ddot, &u);
        let mut z_dot = JointState::zeros();
        z_dot.fixed_rows_mut::<4>(0).copy_from(&x_dot);
        z_dot.fixed_rows_mut::<2>(4).copy_from(&u_dot);
        (z_dot, theta_ddot)
    }

    /// Ż = [f(X, U + ΔT); −γ ∂F/∂U].
    #[inline]
    pub fn rhs(&self, z: &JointState) -> JointState {
        self.rhs_and_acceleration(z).0
    }

    /// ∂Ż/∂Z, from the generated Jacobian of the generative process (∂f/∂X, ∂f/∂U) and the
    /// controller's constant gains: with θ̈ = f₃,₄(X, U + ΔT),
    /// ∂U̇/∂X = −γ(K_θ[I O] + K_θ̇[O I] + K_θ̈ ∂f₃,₄/∂X) and ∂U̇/∂U = −γ(K_θ̈ ∂f₃,₄/∂U + P^U).
    #[inline]
    pub fn jacobian(&self, z: &JointState) -> JointJacobian {
        let x = z.fixed_rows::<4>(0).into_owned();
        let u = z.fixed_rows::<2>(4).into_owned();
        let (f_x, f_u) = arm2::dynamics_jacobian(&x, &(u + self.perturbation), &self.params);
        let [k_theta, k_theta_dot, k_theta_ddot, p_u] = self.controller.scaled_gains();
        let accel_x = f_x.fixed_view::<2, 4>(2, 0);
        let accel_u = f_u.fixed_view::<2, 2>(2, 0);
        let mut j = JointJacobian::zeros();
        j.fixed_view_mut::<4, 4>(0, 0).copy_from(&f_x);
        j.fixed_view_mut::<4, 2>(0, 4).copy_from(&f_u);
        let mut du_dx = -(k_theta_ddot * accel_x);
        let mut block = du_dx.fixed_view_mut::<2, 2>(0, 0);
        block -= k_theta;
        let mut block = du_dx.fixed_view_mut::<2, 2>(0, 2);
        block -= k_theta_dot;
        j.fixed_view_mut::<2, 4>(4, 0).copy_from(&du_dx);
        j.fixed_view_mut::<2, 2>(4, 4)
            .copy_from(&(-(k_theta_ddot * accel_u) - p_u));
        j
    }
}
