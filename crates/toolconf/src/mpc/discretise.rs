//! Exact zero-order-hold discretisation of an affine model ẋ = A x + B u + c.

use nalgebra::{DMatrix, SMatrix, SVector};

/// x_{k+1} = ad x_k + bd u_k + cd, exact for u held constant over one period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Discretised<const N: usize, const M: usize> {
    pub ad: SMatrix<f64, N, N>,
    pub bd: SMatrix<f64, N, M>,
    pub cd: SVector<f64, N>,
}

/// Discretises ẋ = A x + B u + c with a zero-order hold of length `period`.
///
/// exp([[A, B, c], [0, 0, 0]]·T) = [[Ad, Bd, cd], [0, I, 0], [0, 0, 1]] gives all three at
/// once and needs no A⁻¹, so it also holds for singular A (the double integrator) and keeps
/// the offset exact instead of assuming the equilibrium is a fixed point of the discrete map.
/// The augmented matrix is dynamic because N + M + 1 is not expressible as a const generic.
pub fn discretise<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    c: &SVector<f64, N>,
    period: f64,
) -> Discretised<N, M> {
    let size = N + M + 1;
    let mut augmented = DMatrix::<f64>::zeros(size, size);
    augmented.view_mut((0, 0), (N, N)).copy_from(&(a * period));
    augmented.view_mut((0, N), (N, M)).copy_from(&(b * period));
    augmented
        .view_mut((0, N + M), (N, 1))
        .copy_from(&(c * period));
    let e = augmented.exp();
    Discretised {
        ad: e.fixed_view::<N, N>(0, 0).into_owned(),
        bd: e.fixed_view::<N, M>(0, N).into_owned(),
        cd: e.fixed_view::<N, 1>(0, N + M).into_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use toolconf_model::model::{Arm2, ArmModel};
    use toolconf_model::Arm;

    #[test]
    fn double_integrator_matches_closed_form() {
        let a = SMatrix::<f64, 2, 2>::new(0.0, 1.0, 0.0, 0.0);
        let b = SMatrix::<f64, 2, 1>::new(0.0, 1.0);
        let t = 0.05;
        let d = discretise(&a, &b, &SVector::<f64, 2>::zeros(), t);
        assert!((d.ad - SMatrix::<f64, 2, 2>::new(1.0, t, 0.0, 1.0)).amax() < 1e-15);
        assert!((d.bd - SMatrix::<f64, 2, 1>::new(t * t / 2.0, t)).amax() < 1e-15);
        assert_eq!(d.cd, SVector::<f64, 2>::zeros());
    }

    #[test]
    fn scalar_affine_matches_closed_form() {
        // ẋ = a x + b u + c: Ad = e^{aT}, Bd = b (e^{aT} − 1)/a, cd = c (e^{aT} − 1)/a.
        let (a, b, c, t) = (-3.0, 2.0, 0.7, 0.05);
        let d = discretise(
            &SMatrix::<f64, 1, 1>::new(a),
            &SMatrix::<f64, 1, 1>::new(b),
            &SVector::<f64, 1>::new(c),
            t,
        );
        let phi = (a * t).exp();
        assert!((d.ad[0] - phi).abs() < 1e-15);
        assert!((d.bd[0] - b * (phi - 1.0) / a).abs() < 1e-15);
        assert!((d.cd[0] - c * (phi - 1.0) / a).abs() < 1e-15);
    }

    #[test]
    fn arm_matches_taylor_series() {
        let t = 0.05;
        for arm in [
            Arm::new([0.3, 0.3, 0.3, 0.3]),
            Arm::new([0.6, 0.1, 0.1, 0.6]),
            Arm::new([0.1, 0.6, 0.5, 0.1]),
        ] {
            let arm = arm.unwrap();
            let (a, b) = (arm.state_matrix(), arm.input_matrix());
            let xe = Arm2::equilibrium_state();
            let d = discretise(&a, &b, &(-a * xe), t);
            // Ad = Σ (AT)^k/k!, Bd = Σ A^k B T^{k+1}/(k+1)!; 40 terms is far past convergence
            // for ‖AT‖ ≲ 12 on these arms.
            let mut ad = SMatrix::<f64, 4, 4>::identity();
            let mut bd = b * t;
            let mut term = SMatrix::<f64, 4, 4>::identity();
            for k in 1..40 {
                term = term * a * t / k as f64;
                ad += term;
                bd += term * b * t / (k + 1) as f64;
            }
            assert!(
                (d.ad - ad).amax() < 1e-12 * ad.amax(),
                "{arm}: Ad off by {}",
                (d.ad - ad).amax()
            );
            assert!(
                (d.bd - bd).amax() < 1e-12 * bd.amax(),
                "{arm}: Bd off by {}",
                (d.bd - bd).amax()
            );
            // The equilibrium stays put with zero torque.
            assert!((d.ad * xe + d.cd - xe).amax() < 1e-12, "{arm}: X^e drifts");
        }
    }
}
