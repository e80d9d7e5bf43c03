//! The main loop of the lean Rodas5P: [`super::super::rosenbrock`]'s, step for step (step-size
//! rules, `hmin`, the stretch onto `tf`, singular matrices, output at the grid points), with the
//! lean attempt and a dense output formed once per step.

use nalgebra::SVector;

use super::{attempt, dense_rows, eps_at, error_norm, Lu, Problem, Start, RODAS5P};
use super::{IntegrationError, Settings, Stats};

/// Rodas5P from `start` over a validated grid and settings.
pub(in crate::integrate) fn integrate<const D: usize, P, O>(
    problem: &mut P,
    start: Start<D>,
    grid: &[f64],
    s: &Settings,
    mut output: O,
) -> Result<Stats, IntegrationError>
where
    P: Problem<D>,
    O: FnMut(usize, f64, &SVector<f64, D>),
{
    let tab = &RODAS5P;
    let tf = grid[grid.len() - 1];
    let (rtol, threshold, exponent) = (s.rtol, s.threshold, tab.exponent);
    let Start {
        mut t,
        mut y,
        f: mut f0,
        abs_h,
        mut next,
        mut stats,
    } = start;

    let mut hmin = 16.0 * eps_at(t);
    let mut abs_h = match abs_h {
        Some(h) => s.hmax.min(hmin.max(h)),
        None => {
            let scaled = f0
                .iter()
                .zip(y.iter())
                .map(|(f, y)| (f / y.abs().max(threshold)).abs());
            let rh = scaled.fold(0.0, f64::max) / (0.8 * rtol.powf(exponent));
            let h = s.hmax.min(grid[next] - t);
            if h * rh > 1.0 { 1.0 / rh } else { h }.max(hmin)
        }
    };

    loop {
        hmin = 16.0 * eps_at(t);
        abs_h = s.hmax.min(hmin.max(abs_h));
        let mut done = false;
        if 1.1 * abs_h >= tf - t {
            abs_h = tf - t;
            done = true;
        }

        let (jacobian, dfdt, evals) = problem.jacobian(t, &y, &f0);
        stats.jacobian_evals += 1;
        stats.rhs_evals += evals;
        let dfdt = (!dfdt.iter().all(|&v| v == 0.0)).then_some(dfdt);

        let mut no_failures = true;
        let (t_new, k, y_new, err) = loop {
            if stats.steps + stats.rejected >= s.max_steps {
                return Err(IntegrationError::TooManySteps {
                    t,
                    max_steps: s.max_steps,
                });
            }
            let t_new = if done { tf } else { t + abs_h };
            let mut e = -jacobian;
            let diagonal = 1.0 / ((t_new - t) * tab.gamma);
            for i in 0..D {
                e[(i, i)] += diagonal;
            }
            stats.factorisations += 1;
            let attempted = if let Some(lu) = Lu::new(e) {
                let (k, y_new) = attempt(problem, &lu, t, &y, &f0, dfdt.as_ref(), t_new);
                stats.rhs_evals += super::S - 1;
                let (err, finite) = error_norm(&y, &y_new, &k[super::S - 1], threshold);
                if !finite {
                    return Err(IntegrationError::NonFinite { t: t_new });
                }
                if err <= rtol {
                    break (t_new, k, y_new, err);
                }
                Some(err)
            } else {
                None
            };
            stats.rejected += 1;
            if abs_h <= hmin {
                return Err(IntegrationError::StepSizeTooSmall { t, h: abs_h });
            }
            abs_h = match attempted {
                Some(err) if no_failures => {
                    hmin.max(abs_h * 0.1f64.max(0.8 * (rtol / err).powf(exponent)))
                }
                _ => hmin.max(0.5 * abs_h),
            };
            no_failures = false;
            done = false;
        };
        stats.steps += 1;

        let h = t_new - t;
        let mut q: Option<[SVector<f64, D>; 3]> = None;
        while next < grid.len() && grid[next] <= t_new {
            let t_out = grid[next];
            if t_out == t_new {
                output(next, t_out, &y_new);
            } else {
                let [q1, q2, q3] = q.get_or_insert_with(|| dense_rows(&k));
                let s = (t_out - t) / h;
                let y_out = y * (1.0 - s) + (y_new + (*q1 + (*q2 + *q3 * s) * s) * (1.0 - s)) * s;
                output(next, t_out, &y_out);
            }
            next += 1;
        }
        if done {
            return Ok(stats);
        }

        if no_failures {
            let shrink = 1.25 * (err / rtol).powf(exponent);
            abs_h = if shrink > 0.2 {
                abs_h / shrink
            } else {
                5.0 * abs_h
            };
        }
        t = t_new;
        y = y_new;
        f0 = problem.rhs(t, &y);
        stats.rhs_evals += 1;
        if !f0.iter().all(|v| v.is_finite()) {
            return Err(IntegrationError::NonFinite { t });
        }
    }
}
