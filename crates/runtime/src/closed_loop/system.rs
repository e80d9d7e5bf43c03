//! The closed-loop system Ż = [f(X, U + ΔT); −γ ∂F/∂U] of the paper's 2-DOF arm and its
//! Jacobian: a façade over [`ClosedLoopN`], the implementation, with the plant chosen at run
//! time.

use nalgebra::{SMatrix, SVector};

use crate::model::{ActiveInferenceN, Arm2, Arm2Exact, Arm2Tool, ClosedLoopN, TaskN};
use crate::{Arm, Error, Task, Vector2};

/// The closed-loop state Z = [X; U] = [θ1 θ2 θ̇1 θ̇2 T1 T2].
pub type JointState = SVector<f64, 6>;
/// ∂Ż/∂Z.
pub type JointJacobian = SMatrix<f64, 6, 6>;

/// Which equations of motion drive the arm. The agent's model (A, B, sensitivities, Π^U) is
/// always the paper's; only the simulated world changes.
///
/// The generic runtime takes the plant as a type ([`Arm2`] or [`Arm2Exact`]); this is the
/// run-time choice the command line and the experiments need, matched once per episode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Plant {
    /// The paper's generative process, eqs. (theta_1_ddot), (theta_2_ddot) (`generated::arm2`).
    #[default]
    Paper,
    /// The exact 2-link Lagrangian dynamics of the same tool (`generated::arm2_exact`): link 2's
    /// pivot accelerates with link 1, which the paper's generative process ignores.
    Exact,
}

impl Plant {
    pub fn name(self) -> &'static str {
        match self {
            Plant::Paper => "paper",
            Plant::Exact => "exact",
        }
    }
}

/// Plant (the nonlinear arm with a constant torque perturbation ΔT on both joints) and
/// active-inference controller, which observes θ, θ̇ and the plant's θ̈: the generic closed loop
/// of the paper's model on either plant.
///
/// An enum over the two monomorphised loops, so that each method matches the plant once and
/// then runs branch-free generic code (an episode matches once, in [`super::simulate`]).
#[derive(Debug, Clone, Copy)]
pub enum ClosedLoop {
    /// On the paper's generative process.
    Paper(ClosedLoopN<Arm2, 2, 4, 4, 6>),
    /// On the exact 2-link dynamics.
    Exact(ClosedLoopN<Arm2Exact, 2, 4, 4, 6>),
}

/// Runs `$body` with `$loop` bound to the monomorphised closed loop, whichever the plant.
macro_rules! with_loop {
    ($self:expr, $loop:ident => $body:expr) => {
        match $self {
            ClosedLoop::Paper($loop) => $body,
            ClosedLoop::Exact($loop) => $body,
        }
    };
}

impl ClosedLoop {
    /// The closed loop on the paper's generative process.
    pub fn new(
        arm: &Arm,
        task: &Task,
        learning_rate: f64,
        perturbation: f64,
    ) -> Result<Self, Error> {
        Self::with_plant(arm, task, learning_rate, perturbation, Plant::Paper)
    }

    pub fn with_plant(
        arm: &Arm,
        task: &Task,
        learning_rate: f64,
        perturbation: f64,
        plant: Plant,
    ) -> Result<Self, Error> {
        let (tool, task) = (Arm2Tool::from(arm), TaskN::from(task));
        Ok(match plant {
            Plant::Paper => {
                ClosedLoop::Paper(ClosedLoopN::new(&tool, &task, learning_rate, perturbation)?)
            }
            Plant::Exact => {
                ClosedLoop::Exact(ClosedLoopN::new(&tool, &task, learning_rate, perturbation)?)
            }
        })
    }

    pub fn plant(&self) -> Plant {
        match self {
            ClosedLoop::Paper(_) => Plant::Paper,
            ClosedLoop::Exact(_) => Plant::Exact,
        }
    }

    /// The controller.
    pub fn controller(&self) -> &ActiveInferenceN<2> {
        with_loop!(self, l => &l.controller)
    }

    /// Ż and the plant's θ̈ (what the controller observes).
    #[inline]
    pub fn rhs_and_acceleration(&self, z: &JointState) -> (JointState, Vector2) {
        with_loop!(self, l => l.rhs_and_acceleration(z))
    }

    /// Ż = [f(X, U + ΔT); −γ ∂F/∂U].
    #[inline]
    pub fn rhs(&self, z: &JointState) -> JointState {
        with_loop!(self, l => l.rhs(z))
    }

    /// ∂Ż/∂Z ([`ClosedLoopN::jacobian`]).
    #[inline]
    pub fn jacobian(&self, z: &JointState) -> JointJacobian {
        with_loop!(self, l => l.jacobian(z))
    }
}
