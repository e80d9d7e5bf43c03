//! Pearson and Spearman correlation: the paper's "control confidence is correlated with task
//! error" claim (Results, Sec. "Control confidence and tool performance") as one number.

use super::error::{check_pairs, StatsError, XY};
use super::rank::ranks;

/// Pearson's product-moment correlation of paired samples.
///
/// Errors: different lengths, fewer than 3 pairs (2 points always give ±1), a non-finite
/// value, or a constant sample (zero variance).
pub fn pearson(x: &[f64], y: &[f64]) -> Result<f64, StatsError> {
    check_pairs(&XY, x, y, 3)?;
    check_not_constant("x", x, "values")?;
    check_not_constant("y", y, "values")?;
    // Correlation is scale-invariant; dividing by the largest magnitude keeps every product
    // in range even for data near f64::MAX or in the subnormals.
    correlation(&unit_scaled(x), &unit_scaled(y))
}

/// Spearman's rank correlation: Pearson on average ranks (ties share their mean rank),
/// as `scipy.stats.spearmanr`.
///
/// Errors as [`pearson`]; a sample whose values are all tied has constant ranks and is
/// [`StatsError::Degenerate`].
pub fn spearman(x: &[f64], y: &[f64]) -> Result<f64, StatsError> {
    check_pairs(&XY, x, y, 3)?;
    check_not_constant("x", x, "ranks")?;
    check_not_constant("y", y, "ranks")?;
    // Ranks are small multiples of 1/2, so the sums below are exact and a perfectly monotone
    // relation gives exactly ±1.
    correlation(&ranks(x), &ranks(y))
}

/// Exact equality, not a variance threshold: a mean computed in floating point need not equal
/// a repeated value, so a tiny nonzero "variance" of constant data would pass a `== 0` test.
fn check_not_constant(name: &str, x: &[f64], of: &str) -> Result<(), StatsError> {
    if x.iter().all(|&v| v == x[0]) {
        return Err(StatsError::degenerate(format!(
            "all {} {name} values equal {}, so the {of} of {name} have zero variance and no correlation exists",
            x.len(),
            x[0]
        )));
    }
    Ok(())
}

/// Needs equal lengths ≥ 2, finite, non-constant inputs of moderate magnitude.
fn correlation(x: &[f64], y: &[f64]) -> Result<f64, StatsError> {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (dx, dy) = (a - mx, b - my);
        sxy += dx * dy;
        sxx += dx * dx;
        syy += dy * dy;
    }
    // sqrt(s·s) == s exactly in IEEE arithmetic, so identical inputs give r = 1 exactly.
    let r = sxy / (sxx * syy).sqrt();
    if !r.is_finite() {
        return Err(StatsError::degenerate(
            "the variance of x or y underflowed to zero",
        ));
    }
    // Rounding can push |r| a few ulps past 1 for perfectly (anti)correlated data.
    Ok(r.clamp(-1.0, 1.0))
}

fn unit_scaled(x: &[f64]) -> Vec<f64> {
    let m = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if m == 0.0 {
        return x.to_vec();
    }
    x.iter().map(|v| v / m).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::is_non_finite;

    #[test]
    fn monotone_transforms_give_plus_and_minus_one() {
        let x = [0.3, 1.0, 2.5, 4.0, 9.0, 12.0];
        let up: Vec<f64> = x.iter().map(|v: &f64| v.exp()).collect();
        let down: Vec<f64> = x.iter().map(|v| -v * v * v).collect();
        assert_eq!(spearman(&x, &up).unwrap(), 1.0);
        assert_eq!(spearman(&x, &down).unwrap(), -1.0);
        let reversed: Vec<f64> = x.iter().rev().copied().collect();
        assert_eq!(spearman(&x, &reversed).unwrap(), -1.0);
    }

    #[test]
    fn pearson_by_hand() {
        // x = 1,2,3,4 (mean 2.5), y = 2,4,5,4 (mean 3.75).
        // dx = -1.5,-.5,.5,1.5; dy = -1.75,.25,1.25,.25.
        // Sxy = 2.625-.125+.625+.375 = 3.5; Sxx = 5; Syy = 3.0625+.0625+1.5625+.0625 = 4.75.
        // r = 3.5 / sqrt(5 * 4.75) = 0.718184...
        let r = pearson(&[1.0, 2.0, 3.0, 4.0], &[2.0, 4.0, 5.0, 4.0]).unwrap();
        assert!((r - 3.5 / (5.0_f64 * 4.75).sqrt()).abs() < 1e-15);
        // Linear data at the edge of the f64 range still correlate exactly.
        let big = [1e300, 2e300, 3e300, 4e300];
        assert!((pearson(&big, &[1.0, 2.0, 3.0, 4.0]).unwrap() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn spearman_with_ties_matches_scipy() {
        // scipy 1.17.1: scipy.stats.spearmanr([1, 2, 2, 3, 4, 4, 4, 5], [2, 1, 3, 3, 5, 4, 6, 6]).statistic
        //   = 0.9007775105401477
        let x = [1.0, 2.0, 2.0, 3.0, 4.0, 4.0, 4.0, 5.0];
        let y = [2.0, 1.0, 3.0, 3.0, 5.0, 4.0, 6.0, 6.0];
        assert!((spearman(&x, &y).unwrap() - 0.9007775105401477).abs() < 1e-14);
        // scipy 1.17.1: scipy.stats.pearsonr([1, 2, 2, 3, 4, 4, 4, 5], [2, 1, 3, 3, 5, 4, 6, 6]).statistic
        //   = 0.8767227853705734
        assert!((pearson(&x, &y).unwrap() - 0.8767227853705734).abs() < 1e-14);
    }

    #[test]
    fn bad_input_is_an_error_not_nan() {
        let e = spearman(&[1.0, 2.0, 3.0], &[1.0, 2.0]).unwrap_err();
        assert!(matches!(
            e,
            StatsError::Length {
                left: 3,
                right: 2,
                ..
            }
        ));
        let e = spearman(&[1.0, 2.0], &[1.0, 2.0]).unwrap_err();
        assert!(matches!(
            e,
            StatsError::TooFew {
                got: 2,
                need: 3,
                ..
            }
        ));
        let e = pearson(&[1.0, f64::INFINITY, 3.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(is_non_finite(&e, "x", 1), "{e}");
        let e = spearman(&[1.0, 2.0, 3.0], &[1.0, 2.0, f64::NAN]).unwrap_err();
        assert!(is_non_finite(&e, "y", 2), "{e}");
        let e = spearman(&[4.0, 4.0, 4.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(e.to_string().contains("all 3 x values equal 4"), "{e}");
        let e = pearson(&[1.0, 2.0, 3.0], &[0.1, 0.1, 0.1]).unwrap_err();
        assert!(matches!(e, StatsError::Degenerate { .. }), "{e}");
    }
}
