//! Paired tests for the benchmarking experiment (Results, "Benchmarking tool selection"):
//! in each trial F and J each choose a tool, so their outcomes pair up by trial.

use super::error::{check_pairs, StatsError, AB};
use super::rank::ranks_and_ties;
use super::special::{normal_two_sided, student_t_two_sided};

/// Result of [`paired_test`] on the differences d = a − b.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairedTest {
    /// Number of pairs (zero differences included).
    pub n: usize,
    pub mean_difference: f64,
    /// Paired t statistic mean(d) / (sd(d)/√n), df = n − 1.
    pub t: f64,
    /// Two-sided p-value of `t` under Student's t with n − 1 degrees of freedom.
    pub t_p_value: f64,
    /// Wilcoxon signed-rank statistic min(R⁺, R⁻) over the non-zero differences.
    pub wilcoxon_w: f64,
    /// Two-sided p-value of the signed-rank test, normal approximation (see [`paired_test`]).
    pub wilcoxon_p_value: f64,
}

/// The pairs (a_i, b_i) with both values present, as two samples: what a paired test compares
/// when an episode that failed left its value out.
pub fn complete_pairs(a: &[Option<f64>], b: &[Option<f64>]) -> (Vec<f64>, Vec<f64>) {
    a.iter()
        .zip(b)
        .filter_map(|(a, b)| Some(((*a)?, (*b)?)))
        .unzip()
}

/// Paired t-test and Wilcoxon signed-rank test of `a` against `b`, both two-sided.
///
/// Wilcoxon variant, the same as `scipy.stats.wilcoxon(a, b, zero_method='wilcox',
/// correction=False, method='approx')` (`'asymptotic'` in newer scipy):
/// - zero differences are dropped (Wilcoxon's method), leaving m non-zero ones;
/// - |d| are ranked with ties sharing their average rank; R⁺, R⁻ sum the ranks of positive and
///   negative differences, W = min(R⁺, R⁻);
/// - z = (R⁺ − m(m+1)/4) / σ with σ² = [m(m+1)(2m+1) − ½ Σ(tᵢ³ − tᵢ)] / 24 over tie groups tᵢ;
/// - no continuity correction; p = P(|Z| ≥ |z|).
///
/// The normal approximation is rough for small m (scipy's default uses the exact distribution
/// below 50 pairs); with the paper's 50 trials it is adequate.
///
/// Errors: different lengths, fewer than 2 pairs, non-finite values, or all differences equal
/// (sd 0 leaves t undefined; this includes a = b, where no signed rank exists either).
pub fn paired_test(a: &[f64], b: &[f64]) -> Result<PairedTest, StatsError> {
    check_pairs(&AB, a, b, 2)?;
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    if let Some(i) = d.iter().position(|v| !v.is_finite()) {
        return Err(StatsError::degenerate(format!(
            "difference a[{i}] − b[{i}] = {} − {} overflows",
            a[i], b[i]
        )));
    }
    if d.iter().all(|&v| v == d[0]) {
        return Err(StatsError::degenerate(format!(
            "all {} differences a − b equal {}, so their sd is 0 and the t statistic is undefined",
            d.len(),
            d[0]
        )));
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0)).sqrt();
    let t = mean / (sd / n.sqrt());
    if !(sd.is_finite() && t.is_finite()) {
        return Err(StatsError::degenerate(
            "the mean or sd of the differences a − b overflows the f64 range",
        ));
    }
    let (wilcoxon_w, wilcoxon_p_value) = wilcoxon(&d)?;
    Ok(PairedTest {
        n: d.len(),
        mean_difference: mean,
        t,
        t_p_value: student_t_two_sided(t, n - 1.0)?,
        wilcoxon_w,
        wilcoxon_p_value,
    })
}

/// (W, p) of the signed-rank test on differences that are not all zero.
fn wilcoxon(d: &[f64]) -> Result<(f64, f64), StatsError> {
    let nonzero: Vec<f64> = d.iter().copied().filter(|&v| v != 0.0).collect();
    let abs: Vec<f64> = nonzero.iter().map(|v| v.abs()).collect();
    let (r, ties) = ranks_and_ties(&abs);
    let r_plus: f64 = nonzero
        .iter()
        .zip(&r)
        .filter(|(v, _)| **v > 0.0)
        .map(|(_, r)| r)
        .sum();
    let r_minus: f64 = nonzero
        .iter()
        .zip(&r)
        .filter(|(v, _)| **v < 0.0)
        .map(|(_, r)| r)
        .sum();
    let m = nonzero.len() as f64;
    let tie_sum: f64 = ties.iter().map(|&t| (t * t * t - t) as f64).sum();
    // Positive for every m ≥ 1: the tie term is at most (m³ − m)/2 < m(m+1)(2m+1).
    let variance = (m * (m + 1.0) * (2.0 * m + 1.0) - 0.5 * tie_sum) / 24.0;
    let z = (r_plus - m * (m + 1.0) / 4.0) / variance.sqrt();
    Ok((r_plus.min(r_minus), normal_two_sided(z)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{close, is_non_finite, three_hundred_points};

    #[test]
    fn wilcoxon_by_hand_with_zero_and_ties() {
        // d = 1,2,0,3,-1,2,5,2. Drop the zero: m = 7, |d| = 1,2,3,1,2,5,2.
        // Sorted 1,1,2,2,2,3,5 -> ranks 1.5 (the 1s), 4 (the 2s), 6, 7.
        // R- = 1.5 (the -1), R+ = 28 - 1.5 = 26.5, W = 1.5.
        // Ties: groups of 2 and 3 -> Σ(t³-t) = 6 + 24 = 30.
        // σ² = (7·8·15 - 15)/24 = 34.375; z = (26.5 - 14)/√34.375 = 2.13201...
        // scipy 1.17.1: scipy.stats.wilcoxon([1,2,0,3,-1,2,5,2], [0]*8, method='approx',
        //   correction=False) -> statistic 1.5, pvalue 0.03300625766123253
        let a = [1.0, 2.0, 0.0, 3.0, -1.0, 2.0, 5.0, 2.0];
        let r = paired_test(&a, &[0.0; 8]).unwrap();
        assert_eq!(r.wilcoxon_w, 1.5);
        assert!(close(r.wilcoxon_p_value, 0.03300625766123253, 1e-12));
    }

    #[test]
    fn t_test_by_hand() {
        // a - b = 1, 2, 3: mean 2, sd 1, t = 2/(1/√3) = 2√3, df = 2.
        // For df = 2 the two-sided p is 1 - |t|/√(2 + t²) = 1 - 2√3/√14.
        let r = paired_test(&[2.0, 4.0, 6.0], &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((r.n, r.mean_difference), (3, 2.0));
        assert!(close(r.t, 2.0 * 3.0_f64.sqrt(), 1e-15));
        assert!(close(
            r.t_p_value,
            1.0 - 2.0 * 3.0_f64.sqrt() / 14.0_f64.sqrt(),
            1e-13
        ));
    }

    #[test]
    fn matches_scipy_on_benchmark_like_data() {
        let a = [
            0.82, 1.35, 0.97, 1.10, 0.64, 1.52, 0.88, 1.21, 0.75, 1.04, 0.99, 1.18, 0.71, 1.40,
            0.93,
        ];
        let b = [
            0.90, 1.29, 1.12, 1.25, 0.70, 1.61, 0.88, 1.30, 0.81, 1.20, 0.95, 1.33, 0.80, 1.38,
            1.07,
        ];
        // scipy 1.17.1: r = scipy.stats.ttest_rel(a, b) -> statistic -3.8667113042842503,
        //   pvalue 0.0017102772430272908
        // scipy.stats.wilcoxon(a, b, zero_method='wilcox', correction=False, method='approx')
        //   -> statistic 7.5, pvalue 0.004667535362406779
        let r = paired_test(&a, &b).unwrap();
        assert_eq!(r.n, 15);
        assert!(close(r.t, -3.8667113042842503, 1e-12));
        assert!(close(r.t_p_value, 0.0017102772430272908, 1e-10));
        assert_eq!(r.wilcoxon_w, 7.5);
        assert!(close(r.wilcoxon_p_value, 0.004667535362406779, 1e-10));
    }

    #[test]
    fn matches_scipy_at_three_hundred_pairs() {
        // (a, b) is the paper-sized sample (x, y) of `three_hundred_points`.
        // scipy 1.17.1: scipy.stats.ttest_rel(a, b) -> statistic 13.671406662265714,
        //   pvalue 2.1979822583297454e-33
        // scipy.stats.wilcoxon(a, b, method='approx', correction=False) (zero_method='wilcox')
        //   -> statistic 6534.0, pvalue 1.4471703808725505e-26
        let (a, b) = three_hundred_points();
        let r = paired_test(&a, &b).unwrap();
        assert!(close(r.t, 13.671406662265714, 1e-12));
        assert!(close(r.t_p_value, 2.1979822583297454e-33, 1e-9));
        assert_eq!(r.wilcoxon_w, 6534.0);
        assert!(close(r.wilcoxon_p_value, 1.4471703808725505e-26, 1e-9));
    }

    #[test]
    fn complete_pairs_keep_the_trials_with_both_values_in_order() {
        let a = [Some(1.0), None, Some(3.0), Some(4.0), Some(5.0)];
        let b = [Some(-1.0), Some(-2.0), None, Some(-4.0)];
        assert_eq!(complete_pairs(&a, &b), (vec![1.0, 4.0], vec![-1.0, -4.0]));
        assert_eq!(complete_pairs(&[], &b), (vec![], vec![]));
    }

    #[test]
    fn bad_input_is_an_error() {
        let e = paired_test(&[1.0, 2.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a and b have different lengths (2 and 3); they must be paired one to one"
        );
        assert!(matches!(
            paired_test(&[1.0], &[2.0]),
            Err(StatsError::TooFew {
                got: 1,
                need: 2,
                ..
            })
        ));
        let e = paired_test(&[1.0, f64::NAN], &[1.0, 2.0]).unwrap_err();
        assert!(is_non_finite(&e, "a", 1), "{e}");
        let e = paired_test(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(
            e.to_string().contains("all 3 differences a − b equal 0"),
            "{e}"
        );
        let e = paired_test(&[2.0, 3.0, 4.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(matches!(e, StatsError::Degenerate { .. }));
        let e = paired_test(&[f64::MAX, 0.0], &[-f64::MAX, 0.0]).unwrap_err();
        assert!(e.to_string().contains("overflows"), "{e}");
        let e = paired_test(&[1e300, -1e300, 0.0], &[-1e300, 1e300, 0.0]).unwrap_err();
        assert!(e.to_string().contains("overflows"), "{e}");
    }
}
