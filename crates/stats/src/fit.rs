//! Exponential curve fit y = a·exp(b·x), the trend line of the paper's "task error vs control
//! confidence" figure.

use super::error::{check_pairs, StatsError, XY};

/// Least-squares fit of y = a·exp(b·x), with its goodness of fit in y space.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExpFit {
    pub a: f64,
    pub b: f64,
    /// 1 − SSE/SST of the residuals y − a·exp(b·x).
    pub r_squared: f64,
    /// √(SSE/n).
    pub rmse: f64,
}

const MAX_ITERATIONS: usize = 1000;
/// Steps below this (relative in the amplitude, absolute in the rate per unit of scaled x)
/// change the fit by less than rounding does.
const STEP_TOL: f64 = 1e-13;
/// Damping beyond this means no direction decreases the SSE: we are at the minimum.
const MAX_DAMPING: f64 = 1e16;

/// Fits y = a·exp(b·x) by least squares in y (not in ln y, which would weight small y more and
/// drop y ≤ 0). Starts from the straight-line fit of ln y on x over the points with y > 0, then
/// refines with Levenberg–Marquardt (Marquardt's diagonal scaling).
///
/// Internally x is centred and scaled to [−1, 1] so exp(b·x) cannot overflow for any sane fit
/// and the two parameters are well conditioned; a and b are mapped back at the end.
///
/// Errors: different lengths, fewer than 3 points, non-finite values, constant x or y, fewer
/// than two points with y > 0 at distinct x (no starting point), a fit that does not converge,
/// or an a that overflows when mapped back.
pub fn fit_exponential(x: &[f64], y: &[f64]) -> Result<ExpFit, StatsError> {
    check_pairs(&XY, x, y, 3)?;
    if x.iter().all(|&v| v == x[0]) {
        return Err(StatsError::degenerate(format!(
            "all x values equal {}, so the rate b cannot be determined",
            x[0]
        )));
    }
    if y.iter().all(|&v| v == y[0]) {
        return Err(StatsError::degenerate(format!(
            "all y values equal {}, so R² (1 − SSE/SST with SST = 0) is undefined",
            y[0]
        )));
    }
    let n = x.len() as f64;
    // Halving before adding keeps the midpoint and half-width finite for any finite x.
    let (lo, hi) = x
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    let (centre, half_width) = (lo / 2.0 + hi / 2.0, hi / 2.0 - lo / 2.0);
    let t: Vec<f64> = x.iter().map(|v| (v - centre) / half_width).collect();
    // y enters linearly through a, so dividing it by its largest magnitude changes only a's
    // scale and keeps the normal equations finite for y near f64::MAX.
    let y_scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let u: Vec<f64> = y.iter().map(|v| v / y_scale).collect();

    let start = log_linear_start(&t, &u)?;
    let (c, d) = levenberg_marquardt(&t, &u, start)?;

    let b = d / half_width;
    let a = c * y_scale * (-b * centre).exp();
    if !(a.is_finite() && b.is_finite()) {
        return Err(StatsError::degenerate(format!(
            "the fitted curve is {:e}·exp({b:e}·(x − {centre:e})), whose value at x = 0 overflows",
            c * y_scale
        )));
    }
    let sse = sse(&t, &u, (c, d));
    let mean_u = u.iter().sum::<f64>() / n;
    let sst: f64 = u.iter().map(|v| (v - mean_u) * (v - mean_u)).sum();
    let rmse = (sse / n).sqrt() * y_scale;
    if !rmse.is_finite() {
        return Err(StatsError::degenerate(
            "the fit's residuals overflow the f64 range",
        ));
    }
    Ok(ExpFit {
        a,
        b,
        r_squared: 1.0 - sse / sst,
        rmse,
    })
}

/// (c, d) of ln y = ln c + d·t over the points with y > 0.
fn log_linear_start(t: &[f64], y: &[f64]) -> Result<(f64, f64), StatsError> {
    let pts: Vec<(f64, f64)> = t
        .iter()
        .zip(y)
        .filter(|(_, &v)| v > 0.0)
        .map(|(&t, &v)| (t, v.ln()))
        .collect();
    let no_start = || {
        StatsError::degenerate(
            "need at least two points with y > 0 at different x to start the exponential fit",
        )
    };
    if pts.len() < 2 {
        return Err(no_start());
    }
    let k = pts.len() as f64;
    let mt = pts.iter().map(|p| p.0).sum::<f64>() / k;
    let ml = pts.iter().map(|p| p.1).sum::<f64>() / k;
    let stt: f64 = pts.iter().map(|p| (p.0 - mt) * (p.0 - mt)).sum();
    if stt == 0.0 {
        return Err(no_start());
    }
    let d = pts.iter().map(|p| (p.0 - mt) * (p.1 - ml)).sum::<f64>() / stt;
    Ok(((ml - d * mt).exp(), d))
}

fn sse(t: &[f64], y: &[f64], (c, d): (f64, f64)) -> f64 {
    t.iter()
        .zip(y)
        .map(|(t, y)| (y - c * (d * t).exp()).powi(2))
        .sum()
}

fn levenberg_marquardt(t: &[f64], y: &[f64], start: (f64, f64)) -> Result<(f64, f64), StatsError> {
    let (mut c, mut d) = start;
    let mut current = sse(t, y, (c, d));
    if !current.is_finite() {
        return Err(StatsError::degenerate(
            "the starting exponential overflows at some x",
        ));
    }
    let mut damping = 1e-3;
    for _ in 0..MAX_ITERATIONS {
        // Normal equations of the model f = c·e^{d t}: ∂f/∂c = e^{d t}, ∂f/∂d = c t e^{d t}.
        let (mut h00, mut h01, mut h11, mut g0, mut g1) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (&t, &y) in t.iter().zip(y) {
            let e = (d * t).exp();
            let (j0, j1) = (e, c * t * e);
            let r = y - c * e;
            h00 += j0 * j0;
            h01 += j0 * j1;
            h11 += j1 * j1;
            g0 += j0 * r;
            g1 += j1 * r;
        }
        loop {
            let (a00, a11) = (h00 * (1.0 + damping), h11 * (1.0 + damping));
            let det = a00 * a11 - h01 * h01;
            let step = (det > 0.0 && det.is_finite())
                .then(|| ((a11 * g0 - h01 * g1) / det, (a00 * g1 - h01 * g0) / det));
            if let Some((dc, dd)) = step {
                let trial = sse(t, y, (c + dc, d + dd));
                if trial < current {
                    c += dc;
                    d += dd;
                    current = trial;
                    damping = (damping / 10.0).max(1e-15);
                    if dc.abs() <= STEP_TOL * c.abs() && dd.abs() <= STEP_TOL {
                        return Ok((c, d));
                    }
                    break;
                }
            }
            damping *= 10.0;
            if damping > MAX_DAMPING {
                return Ok((c, d));
            }
        }
    }
    Err(StatsError::degenerate(format!(
        "the exponential fit did not converge in {MAX_ITERATIONS} Levenberg–Marquardt iterations"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{close, is_non_finite, three_hundred_points};

    #[test]
    fn recovers_exact_exponentials() {
        for (a, b) in [(2.5, -0.8), (0.01, 0.45), (-3.0, 0.2)] {
            let x: Vec<f64> = (0..11).map(|i| i as f64).collect();
            let y: Vec<f64> = x.iter().map(|x| a * (b * x).exp()).collect();
            // a < 0 has no y > 0 to start from; it must be a clean error.
            if a < 0.0 {
                assert!(matches!(
                    fit_exponential(&x, &y),
                    Err(StatsError::Degenerate { .. })
                ));
                continue;
            }
            let f = fit_exponential(&x, &y).unwrap();
            assert!(close(f.a, a, 1e-12) && close(f.b, b, 1e-12), "{f:?}");
            assert!((f.r_squared - 1.0).abs() < 1e-12 && f.rmse < 1e-12 * a.abs().max(1.0));
        }
        // Confidence-like x far from 0: a = 3000, b = -0.01 on x = 50..500.
        let x: Vec<f64> = (0..10).map(|i| 50.0 + 50.0 * i as f64).collect();
        let y: Vec<f64> = x.iter().map(|x| 3000.0 * (-0.01 * x).exp()).collect();
        let f = fit_exponential(&x, &y).unwrap();
        assert!(
            close(f.a, 3000.0, 1e-11) && close(f.b, -0.01, 1e-11),
            "{f:?}"
        );
    }

    #[test]
    fn noisy_data_match_scipy_curve_fit() {
        let x = [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0];
        let y = [7.9, 6.1, 5.3, 3.6, 3.4, 2.1, 2.2, 1.1, 1.4, 0.6, 0.9, -0.2];
        // scipy 1.17.1 / numpy 2.4.6:
        //   p, _ = scipy.optimize.curve_fit(lambda x, a, b: a*numpy.exp(b*x), x, y, p0=(1, -0.1),
        //                                   ftol=1e-15, xtol=1e-15, gtol=1e-15)
        //   -> a = 10.204966409607357, b = -0.4896200284458644
        //   res = y - p[0]*numpy.exp(p[1]*x)
        //   1 - sum(res**2)/sum((y - mean(y))**2) = 0.978244561884001
        //   sqrt(mean(res**2)) = 0.34916336854136987
        let f = fit_exponential(&x, &y).unwrap();
        assert!(close(f.a, 10.204966409607357, 1e-6), "{f:?}");
        assert!(close(f.b, -0.4896200284458644, 1e-6), "{f:?}");
        assert!(close(f.r_squared, 0.978244561884001, 1e-6), "{f:?}");
        assert!(close(f.rmse, 0.34916336854136987, 1e-6), "{f:?}");
    }

    #[test]
    fn bad_input_is_an_error() {
        let e = fit_exponential(&[1.0, 2.0], &[1.0, 2.0]).unwrap_err();
        assert!(matches!(
            e,
            StatsError::TooFew {
                got: 2,
                need: 3,
                ..
            }
        ));
        let e = fit_exponential(&[1.0, 2.0, 3.0], &[1.0, 2.0]).unwrap_err();
        assert!(matches!(e, StatsError::Length { .. }));
        let e = fit_exponential(&[1.0, 2.0, f64::NAN], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(is_non_finite(&e, "x", 2), "{e}");
        let e = fit_exponential(&[2.0, 2.0, 2.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(e.to_string().contains("all x values equal 2"), "{e}");
        let e = fit_exponential(&[1.0, 2.0, 3.0], &[5.0, 5.0, 5.0]).unwrap_err();
        assert!(e.to_string().contains("all y values equal 5"), "{e}");
        // Only one positive y: no log-linear start.
        let e = fit_exponential(&[1.0, 2.0, 3.0], &[1.0, -2.0, 0.0]).unwrap_err();
        assert!(e.to_string().contains("two points with y > 0"), "{e}");
    }

    #[test]
    fn three_hundred_noisy_points_match_scipy_curve_fit() {
        // The paper-sized sample (x, y) of `three_hundred_points`.
        // scipy 1.17.1: scipy.optimize.curve_fit(lambda x, a, b: a*numpy.exp(b*x), x, y,
        //   p0=(1, -0.1), ftol=1e-15, xtol=1e-15, gtol=1e-15)
        //   -> a = 50.14426941745104, b = -0.020059745275502694
        let (x, y) = three_hundred_points();
        let f = fit_exponential(&x, &y).unwrap();
        assert!(close(f.a, 50.14426941745104, 1e-6), "{f:?}");
        assert!(close(f.b, -0.020059745275502694, 1e-6), "{f:?}");
    }
}
