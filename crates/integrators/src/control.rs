//! What DP5 and the Rosenbrock methods share of `ode45`'s control, written once: the first step
//! size, the weighted error norm and the step-size updates after an accepted or a rejected step
//! (Shampine & Reichelt 1997; `ode45.m`). `exponent` is 1/(order of the error estimate + 1),
//! 1/5 for both DP5 and Rodas5P.

use nalgebra::SVector;

use super::grid::{eps_at, Settings};
use super::options::{IntegrationError, Stats};

/// The first step size from `(t, y)` with `f = f(t, y)`: the caller's `given` step as
/// `min(hmax, max(hmin, h))`, else `ode45`'s heuristic `h = min(hmax, gap)` reduced to `1/rh`
/// when `h·rh > 1`, with `rh = ‖f ./ max(|y|, atol/rtol)‖_∞ / (0.8·rtol^exponent)`, then at
/// least `hmin = 16·eps(t)`. `gap` is the distance to the next output point.
#[inline]
pub(super) fn first_step<const D: usize>(
    given: Option<f64>,
    t: f64,
    y: &SVector<f64, D>,
    f: &SVector<f64, D>,
    gap: f64,
    s: &Settings,
    exponent: f64,
) -> f64 {
    let hmin = 16.0 * eps_at(t);
    match given {
        Some(h) => s.hmax.min(hmin.max(h)),
        None => {
            let scaled = f
                .iter()
                .zip(y.iter())
                .map(|(f, y)| (f / y.abs().max(s.threshold)).abs());
            let rh = scaled.fold(0.0, f64::max) / (0.8 * s.rtol.powf(exponent));
            let h = s.hmax.min(gap);
            if h * rh > 1.0 { 1.0 / rh } else { h }.max(hmin)
        }
    }
}

/// `ode45`'s weighted error `‖estimate ./ max(|y|, |y_new|, threshold)‖_∞` and whether the
/// estimate and `y_new` are finite (f64::max drops NaN, so finiteness cannot be read off the
/// norm). DP5 scales it by |h|; a Rosenbrock estimate is already a displacement.
#[inline(always)]
pub(super) fn error_norm<const D: usize>(
    y: &SVector<f64, D>,
    y_new: &SVector<f64, D>,
    estimate: &SVector<f64, D>,
    threshold: f64,
) -> (f64, bool) {
    let mut finite = true;
    let mut norm = 0.0f64;
    for i in 0..D {
        let (e, y_new) = (estimate[i], y_new[i]);
        finite &= e.is_finite() & y_new.is_finite();
        norm = norm.max((e / y[i].abs().max(y_new.abs()).max(threshold)).abs());
    }
    (norm, finite)
}

/// The step size to retry with after a rejected attempt of size `abs_h`: on the first failure
/// of a step with an error `err`, `max(hmin, h·max(0.1, 0.8·(rtol/err)^exponent))`; on a
/// repeated failure (the error model is unreliable here) or without an error (a singular
/// iteration matrix), `max(hmin, h/2)`.
#[inline]
pub(super) fn after_rejection(
    abs_h: f64,
    hmin: f64,
    err: Option<f64>,
    first_failure: bool,
    rtol: f64,
    exponent: f64,
) -> f64 {
    match err {
        Some(err) if first_failure => {
            hmin.max(abs_h * 0.1f64.max(0.8 * (rtol / err).powf(exponent)))
        }
        _ => hmin.max(0.5 * abs_h),
    }
}

/// The next step size after a step accepted at the first attempt with error `err`:
/// `h / max(0.2, 1.25·(err/rtol)^exponent)`, i.e. at most 5× (err may be 0).
#[inline]
pub(super) fn after_success(abs_h: f64, err: f64, rtol: f64, exponent: f64) -> f64 {
    let shrink = 1.25 * (err / rtol).powf(exponent);
    if shrink > 0.2 {
        abs_h / shrink
    } else {
        5.0 * abs_h
    }
}

/// The budget of step attempts ([`Settings::max_steps`]): [`IntegrationError::TooManySteps`] at
/// `(t, y)` with the step `abs_h` about to be tried once `stats` has used it up.
#[inline]
pub(super) fn attempts_left<const D: usize>(
    stats: &Stats,
    s: &Settings,
    t: f64,
    abs_h: f64,
    y: &SVector<f64, D>,
) -> Result<(), IntegrationError> {
    if stats.steps + stats.rejected >= s.max_steps {
        return Err(IntegrationError::TooManySteps {
            t,
            max_steps: s.max_steps,
            h: abs_h,
            state: y.as_slice().to_vec(),
        });
    }
    Ok(())
}
