//! Control confidence Π^U and ln|Π^U| (eq. control_conf) of a tool on a validated task.

use nalgebra::{SMatrix, SVector};

use crate::Error;

use super::{ArmModel, TaskN, ToolN};

/// Π^U with its log-determinant ln|Π^U|, the confidence term of the free energy
/// (eq. FE_components).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlConfidenceN<const N: usize> {
    /// Π^U, symmetric positive definite.
    pub pi_u: SMatrix<f64, N, N>,
    /// ln|Π^U|.
    pub logdet: f64,
}

impl<const N: usize> ControlConfidenceN<N> {
    /// ln|Π^U|/N: the mean log precision per control channel, ln of the geometric mean of Π^U's
    /// eigenvalues; the quantity comparable across models with different N (docs/explanation/mixed-tools.md).
    pub fn logdet_per_joint(&self) -> f64 {
        self.logdet / N as f64
    }
}

/// The closed-form control confidence of `tool` for `task` (eq. control_conf and the closed
/// forms after it): Π^U = Σ Sᵀ P S over the task's terms, plus P^U, and ln|Π^U|.
///
/// It depends only on the tool and the task's precisions, so it can be computed before the tool
/// is used. Errors if the task is invalid or Π^U is not positive definite
/// ([`Error::NotPositiveDefinite`], with the determinant; possible only with user precisions,
/// e.g. all zero). ln|Π^U| comes from [`logdet_of`].
pub fn control_confidence<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
) -> Result<ControlConfidenceN<N>, Error>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    task.validate()?;
    ValidatedTaskN(*task).control_confidence(tool)
}

/// A task whose goals and precisions have been checked once ([`TaskN::validated`]): ranking many
/// tools for one task then costs only the closed form and the log-determinant per tool, not the
/// task's checks (about half of [`control_confidence`]'s time for the 2-link arm, see
/// docs/explanation/performance.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidatedTaskN<const N: usize>(pub(super) TaskN<N>);

impl<const N: usize> ValidatedTaskN<N> {
    pub fn task(&self) -> &TaskN<N> {
        &self.0
    }

    /// Π^U of `tool` (eq. control_conf), the closed form alone: no positive-definiteness check
    /// and no logarithm (rank by confidence with [`ValidatedTaskN::control_confidence`]).
    #[inline]
    pub fn pi_u<M, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> SMatrix<f64, N, N>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::pi_u(&self.0, &tool.params())
    }

    /// ∂ln|Π^U|/∂p of `tool`, one entry per tool parameter (the generated closed form of
    /// Jacobi's formula, d ln|Π| = tr(Π⁻¹ dΠ)); meaningful where Π^U is positive definite.
    #[inline]
    pub fn logdet_gradient<M, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> SVector<f64, NP>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::logdet_gradient(&self.0, &tool.params())
    }

    /// Π^U and ln|Π^U| of `tool` (eq. control_conf); errors only if Π^U is not positive definite.
    #[inline]
    pub fn control_confidence<M, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> Result<ControlConfidenceN<N>, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let pi_u = self.pi_u(tool);
        let logdet = logdet_of(&pi_u)?;
        Ok(ControlConfidenceN { pi_u, logdet })
    }
}

/// The smallest a determinant (2×2: of Π₀₀Π₁₁) or a squared Cholesky pivot (of max Π_ii) may be
/// for ln|Π^U| to be computed ([`logdet_of`]): with rounding ε ≈ 2.2e-16 in the entries, the
/// determinant is then good to about 4e-6 relative.
pub const MIN_PIVOT_RATIO: f64 = 1e-10;

/// ln|Π| of a symmetric positive definite Π, or [`Error::NotPositiveDefinite`] (or
/// [`Error::IllConditioned`]).
///
/// In general 2 Σ ln L_ii of the Cholesky factor. For N = 2 it is ln(Π₀₀Π₁₁ − Π₀₁Π₁₀) instead:
/// a symmetric 2×2 is positive definite iff Π₀₀ > 0 and its determinant > 0, so one product and
/// one logarithm decide and give ln|Π| exactly; Cholesky would also round differently in the last
/// bits, and the paper's numbers (tests/numbers_snapshot.rs and the figure snapshots) are pinned
/// to every digit of this closed form. `N` is a constant, so the branch is resolved at compile
/// time.
///
/// Conditioning: Π^U's entries carry the generated arithmetic's rounding, about ε·|Π_ij|, so its
/// determinant is known only to about ε·Π₀₀Π₁₁ (ε·max Π_ii per pivot for N > 2). A determinant
/// below [`MIN_PIVOT_RATIO`] of that (a tool whose parameters span many decades: with every
/// parameter at 1e-4 or 1e4, Π^U of the velocity task has a condition number of 10¹⁶) is
/// [`Error::IllConditioned`] rather than a ln|Π^U| with no correct digit; above it, ln|Π^U| is
/// good to about 1e-5.
#[inline]
pub fn logdet_of<const N: usize>(pi: &SMatrix<f64, N, N>) -> Result<f64, Error> {
    if N == 2 {
        let product = pi[(0, 0)] * pi[(1, 1)];
        let determinant = product - pi[(0, 1)] * pi[(1, 0)];
        let positive = pi[(0, 0)] > 0.0 && pi[(1, 1)] > 0.0;
        if positive && determinant.abs() < MIN_PIVOT_RATIO * product {
            return Err(Error::IllConditioned {
                ratio: determinant / product,
            });
        }
        if !(pi[(0, 0)] > 0.0 && determinant > 0.0 && determinant.is_finite()) {
            return Err(Error::NotPositiveDefinite { determinant });
        }
        return Ok(crate::ln(determinant));
    }
    let not_pd = || Error::NotPositiveDefinite {
        determinant: crate::linalg::determinant(pi),
    };
    if pi.iter().any(|v| !v.is_finite()) {
        return Err(not_pd());
    }
    let largest = (0..N).map(|i| pi[(i, i)]).fold(0.0_f64, f64::max);
    let Some(cholesky) = nalgebra::Cholesky::new(*pi) else {
        return Err(why_not_positive_definite(pi, largest).unwrap_or_else(not_pd));
    };
    let l = cholesky.l_dirty();
    let mut logdet = 0.0;
    for i in 0..N {
        let d = l[(i, i)];
        if !(d > 0.0 && d.is_finite()) {
            return Err(not_pd());
        }
        if d * d < MIN_PIVOT_RATIO * largest {
            return Err(Error::IllConditioned {
                ratio: d * d / largest,
            });
        }
        logdet += 2.0 * crate::ln(d);
    }
    if logdet.is_finite() {
        Ok(logdet)
    } else {
        Err(not_pd())
    }
}

/// Why a Cholesky factorisation of Π failed: a pivot within [`MIN_PIVOT_RATIO`] of Π's largest
/// diagonal entry, of either sign, is rounding in an ill-conditioned matrix
/// ([`Error::IllConditioned`]); `None` if a pivot is clearly negative (not positive definite).
fn why_not_positive_definite<const N: usize>(
    pi: &SMatrix<f64, N, N>,
    largest: f64,
) -> Option<Error> {
    let mut a = *pi;
    for k in 0..N {
        let d = a[(k, k)];
        if d.abs() < MIN_PIVOT_RATIO * largest {
            return Some(Error::IllConditioned { ratio: d / largest });
        }
        if !(d > 0.0) {
            return None;
        }
        for i in k + 1..N {
            for j in k + 1..N {
                a[(i, j)] -= a[(i, k)] * a[(k, j)] / d;
            }
        }
    }
    None
}
