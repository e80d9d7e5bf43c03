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
    /// eigenvalues; the quantity comparable across models with different N (docs/mixed-tools.md).
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
/// docs/performance.md).
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

/// ln|Π| of a symmetric positive definite Π, or [`Error::NotPositiveDefinite`].
///
/// In general 2 Σ ln L_ii of the Cholesky factor. For N = 2 it is ln(Π₀₀Π₁₁ − Π₀₁Π₁₀) instead:
/// a symmetric 2×2 is positive definite iff Π₀₀ > 0 and its determinant > 0, so one product and
/// one logarithm decide and give ln|Π| exactly; Cholesky would also round differently in the last
/// bits, and the paper's numbers (tests/numbers_snapshot.rs and the figure snapshots) are pinned
/// to every digit of this closed form. `N` is a constant, so the branch is resolved at compile
/// time.
#[inline]
pub fn logdet_of<const N: usize>(pi: &SMatrix<f64, N, N>) -> Result<f64, Error> {
    if N == 2 {
        let determinant = pi[(0, 0)] * pi[(1, 1)] - pi[(0, 1)] * pi[(1, 0)];
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
    let cholesky = nalgebra::Cholesky::new(*pi).ok_or_else(not_pd)?;
    let l = cholesky.l_dirty();
    let mut logdet = 0.0;
    for i in 0..N {
        let d = l[(i, i)];
        if !(d > 0.0 && d.is_finite()) {
            return Err(not_pd());
        }
        logdet += 2.0 * crate::ln(d);
    }
    if logdet.is_finite() {
        Ok(logdet)
    } else {
        Err(not_pd())
    }
}
