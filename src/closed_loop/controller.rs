//! The task-based active-inference controller (eq. U_dot_deriv) and the free energy it descends
//! (eq. free_energy), with every matrix that does not change during an episode precomputed.

use crate::confidence::{control_confidence, sensitivities};
use crate::{Arm, Error, Matrix2, Task, TaskKind, Vector2};

/// The controller of one arm for one task: U̇ = −γ ∂F/∂U.
#[derive(Debug, Clone, Copy)]
pub struct ActiveInference {
    pub task: Task,
    /// Learning rate γ of the gradient descent (eq. AIC_gradient_des).
    pub learning_rate: f64,
    /// Sᵀ P for each term (zero for terms the task does not use), so that
    /// ∂F/∂U = K_θ(θ − θ^g) + K_θ̇(θ̇ − θ̇^g) + K_θ̈(θ̈ − θ̈^g) + P^U U.
    gain_theta: Matrix2,
    gain_theta_dot: Matrix2,
    gain_theta_ddot: Matrix2,
    /// ln|Π^U|, constant for the arm and task (eq. control_conf).
    pub logdet: f64,
}

impl ActiveInference {
    pub fn new(arm: &Arm, task: &Task, learning_rate: f64) -> Result<Self, Error> {
        if !(learning_rate.is_finite() && learning_rate > 0.0) {
            return Err(Error::InvalidOption {
                name: "learning rate",
                value: learning_rate,
            });
        }
        let confidence = control_confidence(arm, task)?;
        let s = sensitivities(arm, task.kind);
        let zero = Matrix2::zeros();
        let gain = |s: Option<Matrix2>, p: &Matrix2| s.map_or(zero, |s| s.transpose() * p);
        Ok(Self {
            task: *task,
            learning_rate,
            gain_theta: gain(s.d_theta_du, &task.precision_theta),
            gain_theta_dot: gain(s.d_theta_dot_du, &task.precision_theta_dot),
            gain_theta_ddot: gain(Some(s.d_theta_ddot_du), &task.precision_theta_ddot),
            logdet: confidence.logdet,
        })
    }

    /// U̇ = −γ ∂F/∂U (eq. U_dot_deriv) from the observed θ, θ̇, θ̈ and the current U (η^U = 0).
    #[inline]
    pub fn control_rate(
        &self,
        theta: &Vector2,
        theta_dot: &Vector2,
        theta_ddot: &Vector2,
        u: &Vector2,
    ) -> Vector2 {
        let t = &self.task;
        let gradient = self.gain_theta * (theta - t.goal_theta)
            + self.gain_theta_dot * (theta_dot - t.goal_theta_dot)
            + self.gain_theta_ddot * (theta_ddot - t.goal_theta_ddot)
            + t.precision_u * u;
        -self.learning_rate * gradient
    }

    /// The gains γ·(K_θ, K_θ̇, K_θ̈) and γ·P^U of U̇ = −γ ∂F/∂U, for the closed-loop Jacobian.
    pub fn scaled_gains(&self) -> [Matrix2; 4] {
        let g = self.learning_rate;
        [
            g * self.gain_theta,
            g * self.gain_theta_dot,
            g * self.gain_theta_ddot,
            g * self.task.precision_u,
        ]
    }

    /// The performance and control-cost part of F, ½[Σ eᵀPe + UᵀP^U U] over the task's terms:
    /// the optimal-control cost J of the paper (F without the confidence term).
    #[inline]
    pub fn cost_j(
        &self,
        theta: &Vector2,
        theta_dot: &Vector2,
        theta_ddot: &Vector2,
        u: &Vector2,
    ) -> f64 {
        let t = &self.task;
        let q = |e: Vector2, p: &Matrix2| e.dot(&(p * e));
        let mut sum = q(*theta_ddot - t.goal_theta_ddot, &t.precision_theta_ddot)
            + u.dot(&(t.precision_u * u));
        if t.kind != TaskKind::Acceleration {
            sum += q(*theta_dot - t.goal_theta_dot, &t.precision_theta_dot);
        }
        if t.kind == TaskKind::Position {
            sum += q(*theta - t.goal_theta, &t.precision_theta);
        }
        0.5 * sum
    }

    /// F = J − ½ ln|Π^U| (eq. free_energy).
    #[inline]
    pub fn free_energy(
        &self,
        theta: &Vector2,
        theta_dot: &Vector2,
        theta_ddot: &Vector2,
        u: &Vector2,
    ) -> f64 {
        self.cost_j(theta, theta_dot, theta_ddot, u) - 0.5 * self.logdet
    }

    /// The task's own weighted error at one instant, the summand of the paper's task error:
    /// task 1 (θ−θ^g)ᵀP^θ(θ−θ^g), task 2 on θ̇, task 3 on θ̈.
    #[inline]
    pub fn task_error(&self, theta: &Vector2, theta_dot: &Vector2, theta_ddot: &Vector2) -> f64 {
        let t = &self.task;
        let (e, p) = match t.kind {
            TaskKind::Position => (theta - t.goal_theta, &t.precision_theta),
            TaskKind::Velocity => (theta_dot - t.goal_theta_dot, &t.precision_theta_dot),
            TaskKind::Acceleration => (theta_ddot - t.goal_theta_ddot, &t.precision_theta_ddot),
        };
        e.dot(&(p * e))
    }
}
