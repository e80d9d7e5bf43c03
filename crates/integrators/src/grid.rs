//! The output grid and the options checked into the numbers the steppers use.

use super::{IntegrationError, Options};

/// `t0, t0 + dt, t0 + 2·dt, …, tf`: each point is `t0 + i·dt` (no accumulated rounding) and the
/// last is exactly `tf`, e.g. `(0, 5, 0.05)` gives 101 points. When `dt` does not divide
/// `tf − t0`, the last interval is shorter than `dt`.
///
/// Returns an empty grid (which [`super::solve_grid`] rejects) unless all inputs are finite, `dt > 0`
/// and `tf > t0`.
pub fn uniform_grid(t0: f64, tf: f64, dt: f64) -> Vec<f64> {
    if !(t0.is_finite() && tf.is_finite() && dt.is_finite() && dt > 0.0 && tf > t0) {
        return Vec::new();
    }
    let intervals = (tf - t0) / dt;
    // (tf − t0)/dt is off an integer by rounding (5/0.05 = 100.00000000000001): a relative slack
    // keeps that from adding a spurious extra point.
    let n = (intervals - 1e-9 * intervals.max(1.0)).ceil().max(1.0) as usize;
    (0..n)
        .map(|i| t0 + i as f64 * dt)
        .chain(std::iter::once(tf))
        .collect()
}

/// Options checked and turned into the numbers the stepper uses.
pub(super) struct Settings {
    pub(super) rtol: f64,
    pub(super) threshold: f64,
    pub(super) hmax: f64,
    pub(super) initial_step: Option<f64>,
    pub(super) max_steps: usize,
}

fn validate_grid(grid: &[f64]) -> Result<(), IntegrationError> {
    let invalid = |reason: String| Err(IntegrationError::InvalidGrid { reason });
    if grid.len() < 2 {
        return invalid(format!(
            "{} point(s) given, at least 2 are needed",
            grid.len()
        ));
    }
    if let Some((i, t)) = grid.iter().enumerate().find(|(_, t)| !t.is_finite()) {
        return invalid(format!("point {i} is {t}, not a finite time"));
    }
    if let Some(i) = (1..grid.len()).find(|&i| grid[i] <= grid[i - 1]) {
        return invalid(format!(
            "not strictly increasing: point {i} ({}) is not after point {} ({})",
            grid[i],
            i - 1,
            grid[i - 1]
        ));
    }
    Ok(())
}

pub(super) fn resolve(options: &Options, grid: &[f64]) -> Result<Settings, IntegrationError> {
    validate_grid(grid)?;
    let positive = |name: &str, value: f64| {
        if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(IntegrationError::InvalidOptions {
                reason: format!("{name} = {value} must be finite and > 0"),
            })
        }
    };
    // ode45 raises RelTol below 100·eps: tighter than that cannot be met in double precision.
    let rtol = positive("rtol", options.rtol)?.max(100.0 * f64::EPSILON);
    let atol = positive("atol", options.atol)?;
    let initial_step = options
        .initial_step
        .map(|h| positive("initial_step", h))
        .transpose()?;
    let span = grid[grid.len() - 1] - grid[0];
    let max_step = options
        .max_step
        .map(|h| positive("max_step", h))
        .transpose()?
        .unwrap_or(0.1 * span);
    if options.max_steps == 0 {
        return Err(IntegrationError::InvalidOptions {
            reason: "max_steps = 0 must be at least 1".into(),
        });
    }
    Ok(Settings {
        rtol,
        threshold: atol / rtol,
        hmax: max_step.min(span),
        initial_step,
        max_steps: options.max_steps,
    })
}

/// MATLAB's `eps(t)`: the distance from |t| to the next larger double (the steppers' `hmin` is
/// `16·eps(t)`).
#[inline]
pub(super) fn eps_at(t: f64) -> f64 {
    let a = t.abs();
    f64::from_bits(a.to_bits() + 1) - a
}
