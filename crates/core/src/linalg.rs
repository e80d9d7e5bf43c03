//! The little linear algebra the core needs beyond nalgebra's fixed-size arithmetic, for any
//! size N given as a const generic.
//!
//! Why not nalgebra's: its determinant and symmetric eigen-decomposition require dimension
//! bounds (`DimMin`, `DimSub<U1>`) that a const generic N cannot state on stable Rust, so the
//! std runtime used heap matrices (`DMatrix`) for them; without an allocator that is not
//! possible. Cholesky has no such bound and is nalgebra's. Both uses are once per task or on an
//! error path, never per integrator step.

use nalgebra::SMatrix;

/// det M, for the message of a Π^U that is not positive definite: nalgebra's closed forms for
/// N ≤ 3 (the same operations, so the same bits as `DMatrix::determinant`), Gaussian
/// elimination with partial pivoting (nalgebra's LU) above.
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
        _ => {
            let mut a = *m;
            let mut det = 1.0;
            for k in 0..N {
                let pivot = (k..N).fold(k, |best, i| {
                    if a[(i, k)].abs() > a[(best, k)].abs() {
                        i
                    } else {
                        best
                    }
                });
                if a[(pivot, k)] == 0.0 {
                    return 0.0;
                }
                if pivot != k {
                    a.swap_rows(pivot, k);
                    det = -det;
                }
                det *= a[(k, k)];
                for i in (k + 1)..N {
                    let factor = a[(i, k)] / a[(k, k)];
                    for j in (k + 1)..N {
                        a[(i, j)] -= factor * a[(k, j)];
                    }
                }
            }
            det
        }
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
