//! The right-hand side and Jacobian as the Rosenbrock steppers see them: analytic, or by
//! forward differences.

use nalgebra::{SMatrix, SVector};

use super::rosenbrock;

/// A problem with its analytic Jacobian.
pub(super) struct Analytic<F, J> {
    pub(super) rhs: F,
    pub(super) jacobian: J,
}

impl<const D: usize, F, J> rosenbrock::Problem<D> for Analytic<F, J>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
    J: FnMut(f64, &SVector<f64, D>) -> (SMatrix<f64, D, D>, SVector<f64, D>),
{
    #[inline]
    fn rhs(&mut self, t: f64, y: &SVector<f64, D>) -> SVector<f64, D> {
        (self.rhs)(t, y)
    }

    #[inline]
    fn jacobian(
        &mut self,
        t: f64,
        y: &SVector<f64, D>,
        _f: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SVector<f64, D>, usize) {
        let (dfdy, dfdt) = (self.jacobian)(t, y);
        (dfdy, dfdt, 0)
    }
}

/// A problem whose Jacobian is formed by forward differences, as `rodas.f` does without one:
/// column j with the increment `√eps·max(|y_j|, atol/rtol)`, ∂f/∂t with `√(eps·max(|t|, 1e-5))`.
pub(super) struct FiniteDifference<F> {
    pub(super) rhs: F,
    pub(super) threshold: f64,
}

impl<const D: usize, F> rosenbrock::Problem<D> for FiniteDifference<F>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
{
    #[inline]
    fn rhs(&mut self, t: f64, y: &SVector<f64, D>) -> SVector<f64, D> {
        (self.rhs)(t, y)
    }

    fn jacobian(
        &mut self,
        t: f64,
        y: &SVector<f64, D>,
        f: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SVector<f64, D>, usize) {
        let sqrt_eps = f64::EPSILON.sqrt();
        let mut dfdy = SMatrix::<f64, D, D>::zeros();
        for j in 0..D {
            let mut shifted = *y;
            shifted[j] += sqrt_eps * y[j].abs().max(self.threshold);
            // The increment as represented, not as intended.
            let delta = shifted[j] - y[j];
            dfdy.set_column(j, &(((self.rhs)(t, &shifted) - f) / delta));
        }
        let t_shifted = t + (f64::EPSILON * t.abs().max(1e-5)).sqrt();
        let dfdt = ((self.rhs)(t_shifted, y) - f) / (t_shifted - t);
        (dfdy, dfdt, D + 1)
    }
}
