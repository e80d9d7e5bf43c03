//! The little linear algebra the core needs beyond nalgebra's fixed-size arithmetic, for any
//! size N given as a const generic.
//!
//! Why not nalgebra's: its determinant and symmetric eigen-decomposition require dimension
//! bounds (`DimMin`, `DimSub<U1>`) that a const generic N cannot state on stable Rust, so the
//! std runtime used heap matrices (`DMatrix`) for them; without an allocator that is not
//! possible. Cholesky has no such bound and is nalgebra's. The determinant and eigenvalue uses
//! are once per task or on an error path; [`Lu`] is also the integrators' per-step solve.

use nalgebra::{SMatrix, SVector};

/// `P·A = L·U` with partial pivoting, for `D × D` matrices on the stack: the one elimination of
/// the crates (the Rosenbrock steppers' `E = I − hγJ` every step, the determinant here).
///
/// Why not nalgebra's `LU`: its `solve` needs the `DimMin` bound a const generic D cannot state
/// on stable Rust (see the module docs), and the steppers solve eight times per factorisation,
/// where the stored reciprocals of U's diagonal let [`Lu::solve_by_reciprocals`] multiply
/// instead of divide (six divisions fewer per solve, on the critical path).
#[derive(Debug, Clone, Copy)]
pub struct Lu<const D: usize> {
    /// L below the diagonal (unit diagonal implied), U on and above it.
    lu: SMatrix<f64, D, D>,
    /// Row i of `P·A` is row `rows[i]` of A.
    rows: [usize; D],
    /// 1 / U_kk.
    inverse_pivots: [f64; D],
    /// det P = ±1.
    sign: f64,
}

impl<const D: usize> Lu<D> {
    /// The factorisation, or `None` for a singular matrix (an exactly zero pivot column).
    #[inline]
    pub fn new(mut a: SMatrix<f64, D, D>) -> Option<Self> {
        let mut rows = [0; D];
        let mut inverse_pivots = [0.0; D];
        let mut sign = 1.0;
        for (i, r) in rows.iter_mut().enumerate() {
            *r = i;
        }
        for k in 0..D {
            let mut pivot = k;
            for i in k + 1..D {
                if a[(i, k)].abs() > a[(pivot, k)].abs() {
                    pivot = i;
                }
            }
            if a[(pivot, k)] == 0.0 {
                return None;
            }
            if pivot != k {
                a.swap_rows(k, pivot);
                rows.swap(k, pivot);
                sign = -sign;
            }
            let inverse = 1.0 / a[(k, k)];
            inverse_pivots[k] = inverse;
            for i in k + 1..D {
                let l = a[(i, k)] * inverse;
                a[(i, k)] = l;
                for j in k + 1..D {
                    a[(i, j)] -= l * a[(k, j)];
                }
            }
        }
        Some(Self {
            lu: a,
            rows,
            inverse_pivots,
            sign,
        })
    }

    /// x with `A·x = b`, dividing by U's diagonal (`rodas.f`'s `SOL`: the stiff stepper that
    /// reproduces the reference integrator bit for bit solves this way).
    #[inline]
    pub fn solve(&self, b: &SVector<f64, D>) -> SVector<f64, D> {
        let mut x = self.forward(b);
        for i in (0..D).rev() {
            for j in i + 1..D {
                x[i] -= self.lu[(i, j)] * x[j];
            }
            x[i] /= self.lu[(i, i)];
        }
        x
    }

    /// x with `A·x = b`, multiplying by the stored reciprocals of U's diagonal: the last bits
    /// differ from [`Lu::solve`]'s, the work on the critical path is less.
    #[inline(always)]
    pub fn solve_by_reciprocals(&self, b: &SVector<f64, D>) -> SVector<f64, D> {
        let mut x = self.forward(b);
        for i in (0..D).rev() {
            for j in i + 1..D {
                x[i] -= self.lu[(i, j)] * x[j];
            }
            x[i] *= self.inverse_pivots[i];
        }
        x
    }

    /// det A = det P · Π U_kk.
    pub fn determinant(&self) -> f64 {
        (0..D).fold(self.sign, |det, k| det * self.lu[(k, k)])
    }

    /// L⁻¹ P b.
    #[inline(always)]
    fn forward(&self, b: &SVector<f64, D>) -> SVector<f64, D> {
        let mut x = SVector::<f64, D>::from_fn(|i, _| b[self.rows[i]]);
        for i in 0..D {
            for j in 0..i {
                x[i] -= self.lu[(i, j)] * x[j];
            }
        }
        x
    }
}

/// det M, for the message of a Π^U that is not positive definite: nalgebra's closed forms for
/// N ≤ 3 (the same operations, so the same bits as `DMatrix::determinant`), [`Lu`] above.
pub(crate) fn determinant<const N: usize>(m: &SMatrix<f64, N, N>) -> f64 {
    match N {
        0 => 1.0,
        1 => m[(0, 0)],
        2 => m[(0, 0)] * m[(1, 1)] - m[(1, 0)] * m[(0, 1)],
        3 => {
            let minor_m12_m23 = m[(1, 1)] * m[(2, 2)] - m[(2, 1)] * m[(1, 2)];
            let minor_m11_m23 = m[(1, 0)] * m[(2, 2)] - m[(2, 0)] * m[(1, 2)];
            let minor_m11_m22 = m[(1, 0)] * m[(2, 1)] - m[(2, 0)] * m[(1, 1)];
            m[(0, 0)] * minor_m12_m23 - m[(0, 1)] * minor_m11_m23 + m[(0, 2)] * minor_m11_m22
        }
        _ => Lu::new(*m).map_or(0.0, |lu| lu.determinant()),
    }
}

/// Whether the symmetric part of `p` has no eigenvalue below −`tolerance` (≥ 0): `p` is
/// positive semi-definite up to rounding. The smallest eigenvalue is ≥ −t exactly when
/// sym(p) + t·I is positive definite, which Cholesky decides; a zero matrix with zero tolerance
/// is semi-definite, though Cholesky would stop at its first pivot.
pub(crate) fn is_positive_semi_definite<const N: usize>(
    p: &SMatrix<f64, N, N>,
    tolerance: f64,
) -> bool {
    let shifted = SMatrix::<f64, N, N>::from_fn(|i, j| {
        0.5 * (p[(i, j)] + p[(j, i)]) + if i == j { tolerance } else { 0.0 }
    });
    if shifted.iter().all(|v| *v == 0.0) {
        return true;
    }
    nalgebra::Cholesky::new(shifted).is_some()
}

/// ρ(M), the largest |eigenvalue| of a real matrix (complex eigenvalues included), by Gelfand's
/// formula ρ = lim ‖M^(2^k)‖^(1/2^k): M squared 60 times, renormalised each time, its log-norm
/// accumulated. Each squaring halves the weight of the transient (the eigenvector basis's
/// condition number), so the result is ρ to rounding for any M a controller meets; a nilpotent M
/// gives 0.
pub(crate) fn spectral_radius<const N: usize>(m: &SMatrix<f64, N, N>) -> f64 {
    let norm = m.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return if norm == 0.0 { 0.0 } else { f64::INFINITY };
    }
    let mut b = m / norm;
    let mut log_rho = crate::ln(norm);
    let mut weight = 1.0;
    for _ in 0..60 {
        let square = b * b;
        let n = square.norm();
        if n == 0.0 {
            return 0.0;
        }
        weight *= 0.5;
        log_rho += weight * crate::ln(n);
        b = square / n;
    }
    libm::exp(log_rho)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Matrix4, SMatrix};

    #[test]
    fn lu_solves_and_determines_like_nalgebra_and_reports_singular_matrices() {
        use nalgebra::{Matrix1, Matrix2, SVector, Vector1};
        // Deterministic pseudo-random 6×6 matrices, some needing row exchanges.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for case in 0..200 {
            let mut a = SMatrix::<f64, 6, 6>::from_fn(|_, _| next());
            if case % 3 == 0 {
                a[(0, 0)] = 0.0;
            }
            let b = SVector::<f64, 6>::from_fn(|_, _| next());
            let lu = Lu::new(a).unwrap();
            let expected = a.lu().solve(&b).unwrap();
            let scale = expected.amax().max(1.0);
            for x in [lu.solve(&b), lu.solve_by_reciprocals(&b)] {
                assert!((x - expected).amax() < 1e-10 * scale, "{x} vs {expected}");
                assert!(
                    (a * x - b).amax() < 1e-12 * scale * a.amax().max(1.0),
                    "residual"
                );
            }
            let det = a.lu().determinant();
            assert!((lu.determinant() - det).abs() < 1e-12 * det.abs().max(1.0));
            assert!((determinant(&a) - det).abs() < 1e-12 * det.abs().max(1.0));
        }
        assert!(Lu::new(Matrix2::new(1.0, 2.0, 2.0, 4.0)).is_none());
        assert!(Lu::new(Matrix1::new(0.0)).is_none());
        let four = Lu::new(Matrix1::new(4.0)).unwrap();
        assert_eq!(four.solve(&Vector1::new(2.0)), Vector1::new(0.5));
        assert_eq!(
            four.solve_by_reciprocals(&Vector1::new(2.0)),
            Vector1::new(0.5)
        );
    }

    #[test]
    fn determinants_agree_with_the_product_of_an_upper_triangle_after_row_swaps() {
        // A permuted triangular matrix has det = ± product of the diagonal.
        let upper = Matrix4::new(
            2.0, 1.0, -3.0, 0.5, 0.0, -1.5, 4.0, 2.0, 0.0, 0.0, 0.25, 1.0, 0.0, 0.0, 0.0, 8.0,
        );
        let mut swapped = upper;
        swapped.swap_rows(0, 3);
        assert_eq!(determinant(&upper), 2.0 * -1.5 * 0.25 * 8.0);
        assert_eq!(determinant(&swapped), -(2.0 * -1.5 * 0.25 * 8.0));
        let m3 = Matrix3::new(2.0, -1.0, 0.0, -1.0, 2.0, -1.0, 0.0, -1.0, 2.0);
        assert_eq!(determinant(&m3), 4.0);
        assert_eq!(determinant(&SMatrix::<f64, 5, 5>::zeros()), 0.0);
        assert_eq!(determinant(&SMatrix::<f64, 7, 7>::identity()), 1.0);
    }

    #[test]
    fn spectral_radii_of_known_matrices() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.max(1.0);
        // Diagonal, a rotation (complex pair of modulus 0.9), a Jordan block, nilpotent.
        let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.5, -1.5, 1.2));
        assert!(close(spectral_radius(&d), 1.5));
        let (c, s) = (0.9 * 0.6, 0.9 * 0.8);
        assert!(close(
            spectral_radius(&nalgebra::Matrix2::new(c, -s, s, c)),
            0.9
        ));
        let jordan = nalgebra::Matrix2::new(0.7, 1.0, 0.0, 0.7);
        assert!((spectral_radius(&jordan) - 0.7).abs() < 1e-9);
        assert_eq!(
            spectral_radius(&nalgebra::Matrix2::new(0.0, 1.0, 0.0, 0.0)),
            0.0
        );
        // Eigenvalues 2 and 0.5 of a non-normal matrix M = V diag(2, 0.5) V⁻¹.
        let m = nalgebra::Matrix2::new(2.0, 3.0, 0.0, 0.5);
        assert!(close(spectral_radius(&m), 2.0));
    }

    #[test]
    fn semi_definite_up_to_the_tolerance() {
        let psd = Matrix3::new(1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0); // eigenvalues 2, 0, 0
        assert!(is_positive_semi_definite(&psd, 1e-12));
        assert!(is_positive_semi_definite(&Matrix3::zeros(), 0.0));
        let indefinite = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0); // eigenvalue −1
        assert!(!is_positive_semi_definite(&indefinite, 1e-12));
        let barely = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, -1e-13));
        assert!(is_positive_semi_definite(&barely, 1e-12));
        assert!(!is_positive_semi_definite(&barely, 1e-14));
        let seven = SMatrix::<f64, 7, 7>::from_fn(|i, j| if i == j { 2.0 } else { -1.0 / 7.0 });
        assert!(is_positive_semi_definite(&seven, 0.0));
    }
}
