//! [`TaskN`]: a task's goals and precisions for N joints, and their checks.

use nalgebra::{SMatrix, SVector};

use crate::generated;
use crate::generated::{TaskKind, Term};
use crate::{Error, PrecisionProblem};

use super::{ArmModel, ValidatedTaskN};

/// A task for N joints: goals θ^g, θ̇^g, θ̈^g and prior precisions P^θ, P^θ̇, P^θ̈, P^U
/// (eq. free_energy). A term the task's controller does not use has precision zero: task 2
/// ignores θ, task 3 ignores θ and θ̇.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskN<const N: usize> {
    pub kind: TaskKind,
    pub goal_theta: SVector<f64, N>,
    pub goal_theta_dot: SVector<f64, N>,
    pub goal_theta_ddot: SVector<f64, N>,
    pub precision_theta: SMatrix<f64, N, N>,
    pub precision_theta_dot: SMatrix<f64, N, N>,
    pub precision_theta_ddot: SMatrix<f64, N, N>,
    pub precision_u: SMatrix<f64, N, N>,
}

impl<const N: usize> TaskN<N> {
    /// Checks the task once for ranking many tools ([`ValidatedTaskN::control_confidence`]).
    pub fn validated(&self) -> Result<ValidatedTaskN<N>, Error> {
        self.validate()?;
        Ok(ValidatedTaskN(*self))
    }

    /// The task with a model's generated defaults (goals; precisions P = value · I).
    pub fn from_defaults(kind: TaskKind, d: &generated::TaskDefaults<N>) -> Self {
        let eye = SMatrix::<f64, N, N>::identity();
        TaskN {
            kind,
            goal_theta: SVector::from(d.goal_theta),
            goal_theta_dot: SVector::from(d.goal_theta_dot),
            goal_theta_ddot: SVector::from(d.goal_theta_ddot),
            precision_theta: eye * d.precision_theta,
            precision_theta_dot: eye * d.precision_theta_dot,
            precision_theta_ddot: eye * d.precision_theta_ddot,
            precision_u: eye * d.precision_u,
        }
    }

    /// Checks goals are in their ranges ([`crate::validate::JOINT_ANGLE`], rates and
    /// accelerations likewise) and precisions in
    /// [`crate::validate::PRECISION_ENTRY`], symmetric and positive semi-definite, and that they
    /// can make Π^U positive definite at all ([`Error::ConfidenceRank`]).
    pub fn validate(&self) -> Result<(), Error> {
        use crate::validate::{JOINT_ACCELERATION, JOINT_ANGLE, JOINT_RATE};
        for (name, goal, range) in [
            ("theta_g", &self.goal_theta, JOINT_ANGLE),
            ("theta_dot_g", &self.goal_theta_dot, JOINT_RATE),
            ("theta_ddot_g", &self.goal_theta_ddot, JOINT_ACCELERATION),
        ] {
            if let Some(&value) = goal.iter().find(|v| !range.contains(**v)) {
                return Err(Error::InvalidGoal { name, value, range });
            }
        }
        for (name, p) in [
            ("P_theta", &self.precision_theta),
            ("P_theta_dot", &self.precision_theta_dot),
            ("P_theta_ddot", &self.precision_theta_ddot),
            ("P_u", &self.precision_u),
        ] {
            check_precision(name, p)?;
        }
        self.check_confidence_rank()
    }

    /// Π^U = Σ SᵀPS + P^U over the terms the task uses, and rank(SᵀPS) ≤ rank(P) whatever the
    /// tool's sensitivities S: if the ranks of those precisions add up to fewer than N, Π^U is
    /// singular for every tool, and no tool has a control confidence ([`Error::ConfidenceRank`]).
    fn check_confidence_rank(&self) -> Result<(), Error> {
        let used = [
            (Term::Theta, &self.precision_theta),
            (Term::ThetaDot, &self.precision_theta_dot),
            (Term::ThetaDdot, &self.precision_theta_ddot),
            (Term::U, &self.precision_u),
        ];
        let rank: usize = used
            .iter()
            .filter(|(term, _)| self.kind.uses(*term))
            .map(|(_, p)| psd_rank(p))
            .sum();
        if rank < N {
            return Err(Error::ConfidenceRank {
                kind: self.kind,
                rank,
                joints: N,
            });
        }
        Ok(())
    }
}

impl TaskN<2> {
    /// The paper's task `kind` for its arm, with the published goals and precisions
    /// ("Implementation details"; [`ArmModel::paper_task`] of [`crate::Arm2`]; another model's is
    /// its own `paper_task`).
    pub fn paper(kind: TaskKind) -> Self {
        crate::Arm2::paper_task(kind)
    }
}

/// The rank of a symmetric positive semi-definite matrix: the pivots of a Cholesky
/// factorisation with diagonal pivoting above 1e-12 of the largest entry (on the stack: no
/// allocation).
fn psd_rank<const N: usize>(p: &SMatrix<f64, N, N>) -> usize {
    let mut a = *p;
    let tolerance = 1e-12 * a.amax();
    let mut rank = 0;
    let mut remaining: [bool; N] = [true; N];
    for _ in 0..N {
        let Some(k) = (0..N)
            .filter(|&i| remaining[i])
            .max_by(|&i, &j| a[(i, i)].total_cmp(&a[(j, j)]))
        else {
            break;
        };
        let pivot = a[(k, k)];
        if !(pivot > tolerance) {
            break;
        }
        remaining[k] = false;
        rank += 1;
        for i in 0..N {
            for j in 0..N {
                if remaining[i] && remaining[j] {
                    a[(i, j)] -= a[(i, k)] * a[(k, j)] / pivot;
                }
            }
        }
    }
    rank
}

/// Finite, symmetric (to 1e-12 relative) and positive semi-definite: the smallest eigenvalue
/// of the symmetric part is ≥ −1e-12·max|P| (for N = 2 the closed-form determinant test).
fn check_precision<const N: usize>(
    name: &'static str,
    p: &SMatrix<f64, N, N>,
) -> Result<(), Error> {
    let invalid = |problem| Error::InvalidPrecision { name, problem };
    let in_range = |v: &&f64| crate::validate::PRECISION_ENTRY.contains(**v);
    if let Some(&value) = p.iter().find(|v| !in_range(v)) {
        return Err(invalid(PrecisionProblem::OutOfRange { value }));
    }
    let scale = p.amax();
    for i in 0..N {
        for j in (i + 1)..N {
            if (p[(i, j)] - p[(j, i)]).abs() > 1e-12 * scale.max(1.0) {
                return Err(invalid(PrecisionProblem::NotSymmetric {
                    upper: p[(i, j)],
                    lower: p[(j, i)],
                }));
            }
        }
    }
    let not_psd = || invalid(PrecisionProblem::NotPositiveSemiDefinite);
    if N == 2 {
        let det = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)];
        if p[(0, 0)] < 0.0 || p[(1, 1)] < 0.0 || det < -1e-12 * (scale * scale) {
            return Err(not_psd());
        }
    } else if N > 0 && !crate::linalg::is_positive_semi_definite(p, 1e-12 * scale) {
        return Err(not_psd());
    }
    Ok(())
}
