//! What the modules' tests share: the relative comparison with SciPy's values, the paper-sized
//! sample they are checked on, and the check of a non-finite input's error.

use crate::StatsError;

/// |a − b| ≤ rel·|b|: `a` agrees with the reference value `b` to a relative `rel`.
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

/// The paper-sized sample the SciPy references are computed on, i < 300:
/// x_i = ((7919 i) mod 300)·0.37, y_i = 50 e^{-0.02 x_i} + ((31 i) mod 17) − 8.
pub fn three_hundred_points() -> (Vec<f64>, Vec<f64>) {
    let x: Vec<f64> = (0..300).map(|i| ((i * 7919) % 300) as f64 * 0.37).collect();
    let y: Vec<f64> = (0..300)
        .map(|i| 50.0 * (-0.02 * x[i]).exp() + ((i * 31) % 17) as f64 - 8.0)
        .collect();
    (x, y)
}

/// Whether `e` names input `what` as not finite at `index`.
pub fn is_non_finite(e: &StatsError, what: &str, index: usize) -> bool {
    matches!(e, StatsError::NonFinite { what: w, index: i, .. } if *w == what && *i == index)
}
