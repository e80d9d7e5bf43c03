//! Descriptive statistics for the paper's box plots (e.g. the benchmarking figure's
//! confidence, task error and perturbation sensitivity of the tools chosen by F, J and Π^U).

use super::error::{check_finite, check_len, StatsError};

/// Five-number summary plus mean and standard deviation of one sample.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Summary {
    pub n: usize,
    pub mean: f64,
    /// Sample standard deviation (divisor n − 1).
    pub sd: f64,
    pub min: f64,
    pub q1: f64,
    pub median: f64,
    pub q3: f64,
    pub max: f64,
}

/// Summarises `x`: mean, sd (n − 1), and quartiles by linear interpolation between order
/// statistics (Hyndman & Fan type 7, the default of `numpy.percentile` and R's `quantile`).
///
/// Errors: fewer than 2 values (sd needs n − 1 ≥ 1), a non-finite value, or a mean/sd that
/// overflows f64.
pub fn summary(x: &[f64]) -> Result<Summary, StatsError> {
    check_len("values", x.len(), 2)?;
    check_finite("x", x)?;
    let (mean, sd) = mean_sd(x);
    if !(mean.is_finite() && sd.is_finite()) {
        return Err(StatsError::degenerate(
            "the mean or standard deviation overflows the f64 range",
        ));
    }
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    Ok(Summary {
        n: x.len(),
        mean,
        sd,
        min: sorted[0],
        q1: quantile_sorted(&sorted, 0.25),
        median: quantile_sorted(&sorted, 0.5),
        q3: quantile_sorted(&sorted, 0.75),
        max: sorted[sorted.len() - 1],
    })
}

/// Needs n ≥ 2 finite values.
fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let direct = |x: &[f64]| {
        let mean = x.iter().sum::<f64>() / n;
        let ss: f64 = x.iter().map(|v| (v - mean) * (v - mean)).sum();
        (mean, (ss / (n - 1.0)).sqrt())
    };
    let (mean, sd) = direct(x);
    if mean.is_finite() && sd.is_finite() {
        return (mean, sd);
    }
    // Only data near f64::MAX get here; scaling costs an ulp per value but avoids inf.
    let m = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let scaled: Vec<f64> = x.iter().map(|v| v / m).collect();
    let (mean, sd) = direct(&scaled);
    (mean * m, sd * m)
}

/// Type-7 quantile of ascending, finite, non-empty `sorted`, `p` in [0, 1].
pub(crate) fn quantile_sorted(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    lerp(sorted[lo], sorted[hi], h - lo as f64)
}

/// numpy's `_lerp`: exact at both ends and monotone; the blend form is only for
/// ranges whose width b − a overflows.
fn lerp(a: f64, b: f64, t: f64) -> f64 {
    let d = b - a;
    if !d.is_finite() {
        return a * (1.0 - t) + b * t;
    }
    if t < 0.5 {
        a + d * t
    } else {
        b - d * (1.0 - t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn small_sample_by_hand() {
        // x = 1,2,3,4: mean 2.5; squared deviations 2.25+.25+.25+2.25 = 5, sd = sqrt(5/3).
        // Type 7: h = 3p -> q1 at h = .75: 1 + .75*(2-1) = 1.75; median h = 1.5 -> 2.5;
        // q3 h = 2.25 -> 3.25.
        let s = summary(&[4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!((s.n, s.mean, s.min, s.max), (4, 2.5, 1.0, 4.0));
        assert!(close(s.sd, (5.0_f64 / 3.0).sqrt(), 1e-15));
        assert_eq!((s.q1, s.median, s.q3), (1.75, 2.5, 3.25));
    }

    #[test]
    fn quartiles_match_numpy() {
        let x = [3.2, -1.5, 7.8, 0.4, 2.2, 9.9, 5.1, 2.2, -0.3, 4.6, 8.05];
        // Sorted: -1.5 -0.3 0.4 2.2 2.2 3.2 4.6 5.1 7.8 8.05 9.9; h = 10p.
        // q1: h = 2.5 -> 0.4 + .5*(2.2-0.4) = 1.3; median: h = 5 -> 3.2; q3: h = 7.5 -> 6.45.
        // numpy 2.4.6: numpy.percentile(x, 25) = 1.3, numpy.percentile(x, 50) = 3.2,
        //   numpy.percentile(x, 75) = 6.449999999999999,
        //   numpy.mean(x) = 3.786363636363637, numpy.std(x, ddof=1) = 3.681581922835
        let s = summary(&x).unwrap();
        assert!(close(s.q1, 1.3, 1e-15));
        assert!(close(s.median, 3.2, 1e-15));
        assert!(close(s.q3, 6.449999999999999, 1e-15));
        assert!(close(s.mean, 3.786363636363637, 1e-15));
        assert!(close(s.sd, 3.681581922835, 1e-14));
        assert_eq!((s.min, s.max), (-1.5, 9.9));
    }

    #[test]
    fn extreme_values_do_not_overflow() {
        let s = summary(&[-1e308, 1e308]).unwrap();
        assert_eq!((s.mean, s.median), (0.0, 0.0));
        // sd = sqrt(2 * 1e308^2 / 1) = 1e308 * sqrt(2), representable though its square is not
        // (numpy.std([-1e308, 1e308], ddof=1) overflows to inf here).
        assert!(close(s.sd, 1e308 * 2.0_f64.sqrt(), 1e-15));
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(matches!(
            summary(&[]),
            Err(StatsError::TooFew {
                got: 0,
                need: 2,
                ..
            })
        ));
        assert!(matches!(
            summary(&[1.0]),
            Err(StatsError::TooFew { got: 1, .. })
        ));
        let e = summary(&[1.0, f64::NAN]).unwrap_err();
        assert_eq!(e.to_string(), "x[1] = NaN is not a finite number");
        // The sd of ±1.7e308 is 1.7e308 * sqrt(2), beyond f64::MAX.
        assert!(matches!(
            summary(&[-f64::MAX, f64::MAX]),
            Err(StatsError::Degenerate { .. })
        ));
    }
}
