//! Percentile-bootstrap confidence interval for Spearman's ρ, so a reported correlation between
//! control confidence and task error comes with its sampling uncertainty.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::correlation::spearman;
use super::error::StatsError;
use super::summary::quantile_sorted;

/// A closed interval [low, high].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Interval {
    pub low: f64,
    pub high: f64,
}

impl Interval {
    pub fn contains(&self, v: f64) -> bool {
        self.low <= v && v <= self.high
    }
}

/// Percentile bootstrap interval for `spearman(x, y)` at confidence `level` (e.g. 0.95).
///
/// Each of `resamples` resamples draws n pairs with replacement (pairs stay together) from a
/// [`ChaCha8Rng`] seeded with `seed`, so the interval is reproducible across runs and platforms.
/// A resample whose ρ is undefined (e.g. it drew one pair n times) is skipped; the bounds are
/// the type-7 quantiles (1 − level)/2 and (1 + level)/2 of the remaining ρ values.
///
/// Errors: those of [`spearman`] on the full sample, `resamples` = 0, `level` outside (0, 1),
/// or more than half of the resamples degenerate (the interval would describe a biased subset).
pub fn bootstrap_spearman_ci(
    x: &[f64],
    y: &[f64],
    resamples: usize,
    level: f64,
    seed: u64,
) -> Result<Interval, StatsError> {
    spearman(x, y)?;
    if resamples == 0 {
        return Err(StatsError::TooFew {
            what: "bootstrap resamples",
            got: 0,
            need: 1,
        });
    }
    if !(level > 0.0 && level < 1.0) {
        return Err(StatsError::InvalidArgument {
            name: "confidence level",
            value: level,
            expected: "must lie strictly between 0 and 1, e.g. 0.95",
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = x.len();
    let (mut xs, mut ys) = (vec![0.0; n], vec![0.0; n]);
    let mut rhos = Vec::with_capacity(resamples);
    for _ in 0..resamples {
        for k in 0..n {
            let i = rng.random_range(0..n);
            xs[k] = x[i];
            ys[k] = y[i];
        }
        if let Ok(rho) = spearman(&xs, &ys) {
            rhos.push(rho);
        }
    }
    let skipped = resamples - rhos.len();
    if 2 * skipped > resamples {
        return Err(StatsError::degenerate(format!(
            "{skipped} of {resamples} bootstrap resamples had constant ranks; \
             the sample has too few distinct values for a bootstrap interval"
        )));
    }
    rhos.sort_by(f64::total_cmp);
    let tail = (1.0 - level) / 2.0;
    Ok(Interval {
        low: quantile_sorted(&rhos, tail),
        high: quantile_sorted(&rhos, 1.0 - tail),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 40 points of a decreasing, noisy relation (like task error vs confidence).
    fn strong() -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..40).map(|i| i as f64).collect();
        // The wobble (period 7) reorders neighbours but not the overall trend.
        let y: Vec<f64> = x
            .iter()
            .map(|&v| 100.0 - 2.0 * v + 5.0 * ((v * 3.0) % 7.0))
            .collect();
        (x, y)
    }

    #[test]
    fn interval_contains_estimate_and_is_reproducible() {
        let (x, y) = strong();
        let rho = spearman(&x, &y).unwrap();
        assert!(
            rho < -0.8,
            "test data should be strongly correlated, got {rho}"
        );
        let ci = bootstrap_spearman_ci(&x, &y, 2000, 0.95, 7).unwrap();
        assert!(
            ci.contains(rho) && ci.low < ci.high && ci.low >= -1.0 && ci.high <= 1.0,
            "{ci:?}"
        );
        assert_eq!(ci, bootstrap_spearman_ci(&x, &y, 2000, 0.95, 7).unwrap());
        assert_ne!(ci, bootstrap_spearman_ci(&x, &y, 2000, 0.95, 8).unwrap());
        // A wider level gives a wider interval from the same resamples.
        let wide = bootstrap_spearman_ci(&x, &y, 2000, 0.99, 7).unwrap();
        assert!(wide.low <= ci.low && wide.high >= ci.high);
    }

    #[test]
    fn perfect_rank_agreement_gives_a_point_interval() {
        // Every non-degenerate resample of a monotone relation has ρ = 1 exactly.
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let y = x.map(|v: f64| v.ln());
        let ci = bootstrap_spearman_ci(&x, &y, 500, 0.9, 1).unwrap();
        assert_eq!((ci.low, ci.high), (1.0, 1.0));
    }

    #[test]
    fn bad_input_is_an_error() {
        let (x, y) = strong();
        assert!(matches!(
            bootstrap_spearman_ci(&x, &y, 0, 0.95, 1),
            Err(StatsError::TooFew { .. })
        ));
        for level in [0.0, 1.0, -0.5, f64::NAN] {
            let e = bootstrap_spearman_ci(&x, &y, 100, level, 1).unwrap_err();
            assert!(matches!(e, StatsError::InvalidArgument { .. }), "{e}");
        }
        let e = bootstrap_spearman_ci(&x, &y[..39], 100, 0.95, 1).unwrap_err();
        assert!(matches!(e, StatsError::Length { .. }));
        // x = [1, 0, 0], y = [0, 1, 0]: a resample of 3 pairs is degenerate if x or y comes out
        // constant. P(x constant) = P(index 0 never drawn) + P(only index 0) = (8 + 1)/27, same
        // for y; both constant iff all three draws hit one index: 3/27. Union = 15/27 ≈ 0.56 > 1/2,
        // so ~556 of 1000 resamples (sd ≈ 16) are skipped.
        let e =
            bootstrap_spearman_ci(&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], 1000, 0.95, 3).unwrap_err();
        assert!(
            e.to_string()
                .contains("of 1000 bootstrap resamples had constant ranks"),
            "{e}"
        );
    }
}
