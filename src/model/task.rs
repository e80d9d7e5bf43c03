//! [`TaskN`]: a task's goals and precisions for N joints, and their checks.

use std::fmt::Debug;

use nalgebra::{SMatrix, SVector};

use crate::generated;
use crate::generated::{TaskKind, Term};
use crate::Error;

use super::{ArmModel, ValidatedTaskN};

/// A task for N joints: goals and prior precisions (the N-joint [`crate::Task`]). A term the task's
/// controller does not use has precision zero.
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

    /// Model `M`'s paper-style task ([`ArmModel::paper_task`]).
    pub fn paper<M, const NX: usize, const NP: usize, const NZ: usize>(kind: TaskKind) -> Self
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::paper_task(kind)
    }

    /// Checks goals are in [`crate::validate::JOINT_VALUE`] and precisions in
    /// [`crate::validate::PRECISION_ENTRY`], symmetric and positive semi-definite, and that they
    /// can make Π^U positive definite at all ([`Error::ConfidenceRank`]), with the errors
    /// [`crate::Task::validate`] gives.
    pub fn validate(&self) -> Result<(), Error> {
        for (name, goal) in [
            ("theta_g", &self.goal_theta),
            ("theta_dot_g", &self.goal_theta_dot),
            ("theta_ddot_g", &self.goal_theta_ddot),
        ] {
            let valid = |v: &f64| crate::validate::JOINT_VALUE.contains(*v);
            if let Some(&value) = goal.iter().find(|v| !valid(v)) {
                return Err(Error::InvalidGoal {
                    name: name.into(),
                    value,
                });
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
fn check_precision<const N: usize>(name: &str, p: &SMatrix<f64, N, N>) -> Result<(), Error> {
    let invalid = |reason: String| Error::InvalidPrecision {
        name: name.into(),
        reason,
    };
    if let Some(&v) = p
        .iter()
        .find(|v| !crate::validate::PRECISION_ENTRY.contains(**v))
    {
        return Err(invalid(format!(
            "entry {} must be a number in {}",
            crate::display::Short(v),
            crate::validate::PRECISION_ENTRY
        )));
    }
    let scale = p.amax();
    for i in 0..N {
        for j in (i + 1)..N {
            if (p[(i, j)] - p[(j, i)]).abs() > 1e-12 * scale.max(1.0) {
                return Err(invalid(format!(
                    "is not symmetric ({} vs {})",
                    p[(i, j)],
                    p[(j, i)]
                )));
            }
        }
    }
    let not_psd = || invalid("is not positive semi-definite".into());
    if N == 2 {
        let det = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)];
        if p[(0, 0)] < 0.0 || p[(1, 1)] < 0.0 || det < -1e-12 * scale.powi(2) {
            return Err(not_psd());
        }
    } else if N > 0 {
        // Dynamic storage: nalgebra's eigen-decomposition needs dimension bounds a const
        // generic N cannot state on stable Rust. Once per task, so the allocation is moot.
        let symmetric = nalgebra::DMatrix::from_fn(N, N, |i, j| 0.5 * (p[(i, j)] + p[(j, i)]));
        let smallest = symmetric.symmetric_eigenvalues().min();
        if smallest < -1e-12 * scale {
            return Err(not_psd());
        }
    }
    Ok(())
}
