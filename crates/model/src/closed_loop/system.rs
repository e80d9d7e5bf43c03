//! The closed-loop system Ż = [f(X, U + ΔT); −γ ∂F/∂U] of the paper's 2-DOF arm and its
//! Jacobian ([`ClosedLoopN`]), and the plant chosen at run time.

use nalgebra::{SMatrix, SVector};

use crate::model::{Arm2, ClosedLoopN};

/// The closed-loop state Z = [X; U] = [θ1 θ2 θ̇1 θ̇2 T1 T2].
pub type JointState = SVector<f64, 6>;
/// ∂Ż/∂Z.
pub type JointJacobian = SMatrix<f64, 6, 6>;

/// The closed loop of the paper's arm on its generative process, [`ClosedLoopN`] with [`Arm2`]
/// (on the exact dynamics it is `ClosedLoopN<Arm2Exact, 2, 4, 4, 6>`; [`Plant`] names the two
/// at run time).
pub type ClosedLoop = ClosedLoopN<Arm2, 2, 4, 4, 6>;

/// Which equations of motion drive the arm. The agent's model (A, B, sensitivities, Π^U) is
/// always the paper's; only the simulated world changes.
///
/// The generic runtime takes the plant as a type ([`Arm2`] or [`crate::model::Arm2Exact`]);
/// this is the run-time choice the command line and the experiments need, matched once per
/// episode ([`Plant::simulate`]) so that the integrator runs the monomorphised closed loop.
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
