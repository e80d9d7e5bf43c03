//! The distributions behind the p-values of the paired tests, from `statrs`: Student's t (its
//! survival function, through the regularised incomplete beta function) and the standard normal
//! as Q(1/2, z²/2), the regularised upper incomplete gamma function: statrs's `erfc`, behind its
//! `Normal`, is off by 9e-11 relative at z = 1 (0.3173105078901145 for 0.31731050786291415),
//! its incomplete gamma by 4e-16. Each tail is computed as itself, not as 1 − cdf, so a tiny
//! p-value keeps its digits. The closed forms and SciPy's values below check them. What statrs
//! lacks stays in this crate: numpy's type-7 quantile (summary.rs) and the Wilcoxon statistic
//! with SciPy's tie correction (paired.rs).

use statrs::distribution::{ContinuousCDF, StudentsT};
use statrs::function::gamma::checked_gamma_ur;

use super::error::StatsError;

/// Two-sided p-value P(|T| ≥ |t|) of Student's t with `df` > 0 degrees of freedom.
pub(crate) fn student_t_two_sided(t: f64, df: f64) -> Result<f64, StatsError> {
    if !(t * t).is_finite() {
        return Ok(0.0);
    }
    let t_dist = StudentsT::new(0.0, 1.0, df).map_err(|e| {
        StatsError::degenerate(format!("Student's t with {df} degrees of freedom: {e}"))
    })?;
    Ok((2.0 * t_dist.sf(t.abs())).clamp(0.0, 1.0))
}

/// Two-sided p-value P(|Z| ≥ |z|) of the standard normal: erfc(|z|/√2) = Q(1/2, z²/2).
pub(crate) fn normal_two_sided(z: f64) -> Result<f64, StatsError> {
    let x = 0.5 * z * z;
    if x == 0.0 {
        return Ok(1.0);
    }
    if !x.is_finite() {
        return Ok(0.0);
    }
    let q = checked_gamma_ur(0.5, x)
        .map_err(|e| StatsError::degenerate(format!("the normal tail at z = {z}: {e}")))?;
    Ok(q.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::close;

    #[test]
    fn closed_forms() {
        // df = 1 is Cauchy: P(|T| ≥ 1) = 1 − (2/π) atan(1) = 1/2. df = 2: p = 1 − |t|/√(2+t²),
        // so t = 1 gives 1 − 1/√3.
        assert!(close(student_t_two_sided(1.0, 1.0).unwrap(), 0.5, 1e-14));
        assert!(close(
            student_t_two_sided(-1.0, 2.0).unwrap(),
            1.0 - 1.0 / 3.0_f64.sqrt(),
            1e-14
        ));
        assert_eq!(student_t_two_sided(0.0, 7.0).unwrap(), 1.0);
        assert_eq!(student_t_two_sided(1e200, 7.0).unwrap(), 0.0);
        // P(|Z| ≥ 1) = erfc(1/√2) = 0.31731050786291415 (A&S 26.2, to 17 digits).
        assert!(close(
            normal_two_sided(1.0).unwrap(),
            0.317_310_507_862_914_15,
            1e-14
        ));
        assert_eq!(normal_two_sided(0.0).unwrap(), 1.0);
    }

    #[test]
    fn match_scipy() {
        // scipy 1.17.1: 2 * scipy.stats.t.sf(2.5, 9) = 0.033861827682985735
        assert!(close(
            student_t_two_sided(2.5, 9.0).unwrap(),
            0.033861827682985735,
            1e-12
        ));
        // 2 * scipy.stats.t.sf(12.0, 299) = 2.4004975588464717e-27
        assert!(close(
            student_t_two_sided(12.0, 299.0).unwrap(),
            2.4004975588464717e-27,
            1e-9
        ));
        // 2 * scipy.stats.t.sf(0.3, 49) = 0.7654461897840288
        assert!(close(
            student_t_two_sided(0.3, 49.0).unwrap(),
            0.7654461897840288,
            1e-13
        ));
        // 2 * scipy.stats.norm.sf(1.96) = 0.04999579029644087
        assert!(close(
            normal_two_sided(1.96).unwrap(),
            0.04999579029644087,
            1e-13
        ));
        // 2 * scipy.stats.norm.sf(8.5) = 1.89590696444065e-17
        assert!(close(
            normal_two_sided(-8.5).unwrap(),
            1.89590696444065e-17,
            1e-12
        ));
        // 2 * scipy.stats.norm.sf(0.1) = 0.920344325445942
        assert!(close(
            normal_two_sided(0.1).unwrap(),
            0.920344325445942,
            1e-14
        ));
    }
}
