//! [`TaskN`]: a task's goals and precisions for N joints, and their checks.

use nalgebra::{SMatrix, SVector};

use crate::generated;
use crate::generated::{Read, TaskKind, Term, TERMS};
use crate::{Error, PrecisionProblem};

use super::ValidatedTaskN;

/// A task for N joints: a goal and a prior precision for every free-energy term
/// (eq. free_energy), indexed by [`Term::index`]: θ^g, θ̇^g, θ̈^g and P^θ, P^θ̇, P^θ̈, P^U for the
/// paper's terms. A term the task's controller does not use has precision zero (task 2 ignores θ,
/// task 3 θ and θ̇); the goal of the control's own term is zero (η^U = 0).
///
/// A term read from the tool's tip ([`Read::Tip`]: y, ẏ) has the tip's `d` components
/// ([`crate::ArmModel::tip_dim`]: 3, 2 for a planar arm), stored padded in the N slots: its goal in the
/// first d rows and zeros after, its precision in the upper-left d × d block and zeros elsewhere
/// (as its generated sensitivity J ∂θ/∂U has zero rows after the d-th; derive/tasks.toml, `J`).
/// Every sum the controller and Π^U form is then the same for joint and tip terms, on the stack,
/// and a padded zero adds nothing. It needs d ≤ N, which the derivation checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskN<const N: usize> {
    pub kind: TaskKind,
    pub goal: [SVector<f64, N>; TERMS],
    pub precision: [SMatrix<f64, N, N>; TERMS],
}

impl<const N: usize> TaskN<N> {
    /// Checks the task once for ranking many tools ([`ValidatedTaskN::control_confidence`]).
    pub fn validated(&self) -> Result<ValidatedTaskN<N>, Error> {
        self.validate()?;
        Ok(ValidatedTaskN(*self))
    }

    /// The goal of `term`.
    #[inline]
    pub fn goal(&self, term: Term) -> &SVector<f64, N> {
        &self.goal[term.index()]
    }

    /// The precision of `term`.
    #[inline]
    pub fn precision(&self, term: Term) -> &SMatrix<f64, N, N> {
        &self.precision[term.index()]
    }

    /// The task with a model's generated defaults (goals; precisions P = value · I, the
    /// identity of the term's own components: the tip's `tip_dim` for a tip term).
    pub fn from_defaults(kind: TaskKind, d: &generated::TaskDefaults<N>, tip_dim: usize) -> Self {
        TaskN {
            kind,
            goal: d.goal.map(SVector::from),
            precision: Term::ALL.map(|t| term_identity(t, tip_dim) * d.precision[t.index()]),
        }
    }

    /// Checks goals are in their terms' ranges ([`crate::validate::goal_range`]; a term without
    /// one has goal zero) and precisions in [`crate::validate::PRECISION_ENTRY`], symmetric and
    /// positive semi-definite, and that they can make Π^U positive definite at all
    /// ([`Error::ConfidenceRank`]).
    pub fn validate(&self) -> Result<(), Error> {
        for term in Term::ALL {
            let goal = self.goal(term);
            let bad = match crate::validate::goal_range(term) {
                Some(range) => goal
                    .iter()
                    .find(|v| !range.contains(**v))
                    .map(|v| (*v, range)),
                None => goal
                    .iter()
                    .find(|v| **v != 0.0)
                    .map(|v| (*v, crate::validate::Range::closed(0.0, 0.0, ""))),
            };
            if let Some((value, range)) = bad {
                return Err(Error::InvalidGoal { term, value, range });
            }
        }
        for term in Term::ALL {
            check_precision(term, self.precision(term))?;
        }
        self.check_confidence_rank()
    }

    /// Π^U = Σ SᵀPS + P^U over the terms the task uses, and rank(SᵀPS) ≤ rank(P) whatever the
    /// tool's sensitivities S: if the ranks of those precisions add up to fewer than N, Π^U is
    /// singular for every tool, and no tool has a control confidence ([`Error::ConfidenceRank`]).
    fn check_confidence_rank(&self) -> Result<(), Error> {
        let rank: usize = Term::ALL
            .iter()
            .filter(|term| self.kind.uses(**term))
            .map(|term| psd_rank(self.precision(*term)))
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

/// How many components `term` has for N joints and a tip of `tip_dim` ([`TaskN`]'s padding):
/// `tip_dim` for a term read from the tip, N for the others.
pub const fn term_components(term: Term, n: usize, tip_dim: usize) -> usize {
    match term.read() {
        Read::Tip { .. } => tip_dim,
        _ => n,
    }
}

/// The identity of `term`'s own components in the N × N slots: I for a joint term, the tip's
/// `tip_dim` × `tip_dim` identity padded with zeros for a tip term ([`TaskN`]).
pub fn term_identity<const N: usize>(term: Term, tip_dim: usize) -> SMatrix<f64, N, N> {
    let d = term_components(term, N, tip_dim);
    SMatrix::from_fn(|i, j| if i == j && i < d { 1.0 } else { 0.0 })
}

/// Whether the task's controller reads the tool's tip (a tip task).
pub fn reads_tip(kind: TaskKind) -> bool {
    kind.terms()
        .iter()
        .any(|t| matches!(t.read(), Read::Tip { .. }))
}

/// Whether the task's controller reads the tip's acceleration ÿ (a term [`Read::Tip`] of order
/// 2, which needs J̇ q̇).
pub fn reads_tip_acceleration(kind: TaskKind) -> bool {
    kind.terms()
        .iter()
        .any(|t| matches!(t.read(), Read::Tip { order: 2.. }))
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
fn check_precision<const N: usize>(term: Term, p: &SMatrix<f64, N, N>) -> Result<(), Error> {
    let invalid = |problem| Error::InvalidPrecision { term, problem };
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
