//! [`ActiveInferenceN`]: the task-based active-inference controller of one tool for one task
//! (the paper's appendix "Task specific controllers"), and [`ActiveInferenceN::tick`], one control
//! period of it on a robot.

use nalgebra::{SMatrix, SVector};

use crate::generated::Term;
use crate::{control_confidence, ArmModel, Error, TaskN, ToolN};

/// The task-based active-inference controller of one tool for one task, U̇ = −γ ∂F/∂U
/// (eq. U_dot_deriv), with every matrix that does not change during an episode precomputed.
///
/// The runtime integrates U̇ with the plant (`toolconf::model::ClosedLoopN`); a robot calls
/// [`ActiveInferenceN::tick`] once per control period instead.
#[derive(Debug, Clone, Copy)]
pub struct ActiveInferenceN<const N: usize> {
    pub task: TaskN<N>,
    /// Learning rate γ of the gradient descent (eq. AIC_gradient_des).
    pub learning_rate: f64,
    /// Sᵀ P for each term (zero for terms the task does not use), so that
    /// ∂F/∂U = K_θ(θ − θ^g) + K_θ̇(θ̇ − θ̇^g) + K_θ̈(θ̈ − θ̈^g) + P^U U.
    gain_theta: SMatrix<f64, N, N>,
    gain_theta_dot: SMatrix<f64, N, N>,
    gain_theta_ddot: SMatrix<f64, N, N>,
    /// ln|Π^U|, constant for the tool and task (eq. control_conf).
    pub logdet: f64,
}

impl<const N: usize> ActiveInferenceN<N> {
    pub fn new<M, const NX: usize, const NP: usize, const NZ: usize>(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
    ) -> Result<Self, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        if !(learning_rate.is_finite() && learning_rate > 0.0) {
            return Err(Error::InvalidOption {
                name: "learning rate",
                value: learning_rate,
            });
        }
        let confidence = control_confidence(tool, task)?;
        let s = tool.sensitivities(task.kind);
        let zero = SMatrix::<f64, N, N>::zeros();
        let gain = |s: Option<SMatrix<f64, N, N>>, p: &SMatrix<f64, N, N>| {
            s.map_or(zero, |s| s.transpose() * p)
        };
        Ok(Self {
            task: *task,
            learning_rate,
            gain_theta: gain(s.d_theta_du, &task.precision_theta),
            gain_theta_dot: gain(s.d_theta_dot_du, &task.precision_theta_dot),
            gain_theta_ddot: gain(s.d_theta_ddot_du, &task.precision_theta_ddot),
            logdet: confidence.logdet,
        })
    }

    /// U̇ = −γ ∂F/∂U (eq. U_dot_deriv) from the observed θ, θ̇, θ̈ and the current U (η^U = 0).
    #[inline]
    pub fn control_rate(
        &self,
        theta: &SVector<f64, N>,
        theta_dot: &SVector<f64, N>,
        theta_ddot: &SVector<f64, N>,
        u: &SVector<f64, N>,
    ) -> SVector<f64, N> {
        let t = &self.task;
        let gradient = self.gain_theta * (theta - t.goal_theta)
            + self.gain_theta_dot * (theta_dot - t.goal_theta_dot)
            + self.gain_theta_ddot * (theta_ddot - t.goal_theta_ddot)
            + t.precision_u * u;
        -self.learning_rate * gradient
    }

    /// One control period on a robot: U̇ = −γ ∂F/∂U (eq. U_dot_deriv, [`Self::control_rate`])
    /// from the measured θ, θ̇, θ̈ and the torque U applied over the last period, then the torque
    /// for the next one, U + period·U̇: the paper's gradient flow discretised by explicit Euler at
    /// the control rate (first order: the torques differ from the continuous controller's by
    /// O(period)). No allocation, a few N×N products.
    ///
    /// The discrete loop can diverge where the continuous one settles: θ̈ follows U through the
    /// plant's ∂θ̈/∂U, so each tick multiplies a torque error by
    /// I − period·γ(K_θ̈ ∂θ̈/∂U + P^U); [`Self::tick_contraction`] gives that factor's size.
    #[inline]
    pub fn tick(
        &self,
        theta: &SVector<f64, N>,
        theta_dot: &SVector<f64, N>,
        theta_ddot: &SVector<f64, N>,
        u: &SVector<f64, N>,
        period: f64,
    ) -> SVector<f64, N> {
        u + self.control_rate(theta, theta_dot, theta_ddot, u) * period
    }

    /// The spectral radius of I − period·γ(K_θ̈ ∂θ̈/∂U + P^U), with `d_theta_ddot_du` the
    /// plant's ∂θ̈/∂U (the lower N rows of its input matrix B): how much one [`Self::tick`]
    /// multiplies a torque error by, linearised where ∂θ̈/∂U was taken. Below 1 the ticks settle
    /// as the continuous controller does; at 1 or above they oscillate without decaying or
    /// diverge, and the control rate must be raised. Light distal links make ∂θ̈/∂U large
    /// (~3/(m₂l₂²) for the paper's arm), and task 3's P^θ̈ = 10 ten times the others'.
    pub fn tick_contraction(&self, d_theta_ddot_du: &SMatrix<f64, N, N>, period: f64) -> f64 {
        let g = self.learning_rate * period;
        let step = SMatrix::<f64, N, N>::identity()
            - (self.gain_theta_ddot * d_theta_ddot_du + self.task.precision_u) * g;
        crate::linalg::spectral_radius(&step)
    }

    /// The gains γ·(K_θ, K_θ̇, K_θ̈) and γ·P^U of U̇ = −γ ∂F/∂U, for the closed-loop Jacobian.
    pub fn scaled_gains(&self) -> [SMatrix<f64, N, N>; 4] {
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
        theta: &SVector<f64, N>,
        theta_dot: &SVector<f64, N>,
        theta_ddot: &SVector<f64, N>,
        u: &SVector<f64, N>,
    ) -> f64 {
        let t = &self.task;
        let q = |e: SVector<f64, N>, p: &SMatrix<f64, N, N>| e.dot(&(p * e));
        // The terms in a fixed order (θ̈, U, θ̇, θ), each only if the task uses it.
        let mut sum = 0.0;
        if t.kind.uses(Term::ThetaDdot) {
            sum += q(*theta_ddot - t.goal_theta_ddot, &t.precision_theta_ddot);
        }
        if t.kind.uses(Term::U) {
            sum += u.dot(&(t.precision_u * u));
        }
        if t.kind.uses(Term::ThetaDot) {
            sum += q(*theta_dot - t.goal_theta_dot, &t.precision_theta_dot);
        }
        if t.kind.uses(Term::Theta) {
            sum += q(*theta - t.goal_theta, &t.precision_theta);
        }
        0.5 * sum
    }

    /// F = J − ½ ln|Π^U| (eq. free_energy).
    #[inline]
    pub fn free_energy(
        &self,
        theta: &SVector<f64, N>,
        theta_dot: &SVector<f64, N>,
        theta_ddot: &SVector<f64, N>,
        u: &SVector<f64, N>,
    ) -> f64 {
        self.cost_j(theta, theta_dot, theta_ddot, u) - 0.5 * self.logdet
    }

    /// The task's own weighted error at one instant, the summand of the paper's task error:
    /// (e − e^g)ᵀP(e − e^g) on the task's error term e ([`crate::TaskKind::error_term`]): θ in task 1,
    /// θ̇ in task 2, θ̈ in task 3.
    #[inline]
    pub fn task_error(
        &self,
        theta: &SVector<f64, N>,
        theta_dot: &SVector<f64, N>,
        theta_ddot: &SVector<f64, N>,
        u: &SVector<f64, N>,
    ) -> f64 {
        let t = &self.task;
        let (e, p) = match t.kind.error_term() {
            Term::Theta => (theta - t.goal_theta, &t.precision_theta),
            Term::ThetaDot => (theta_dot - t.goal_theta_dot, &t.precision_theta_dot),
            Term::ThetaDdot => (theta_ddot - t.goal_theta_ddot, &t.precision_theta_ddot),
            Term::U => (*u, &t.precision_u),
        };
        e.dot(&(p * e))
    }
}
