//! The Dormand–Prince 5(4) stepper with `ode45`'s step-size control and `ntrp45` dense output.

use nalgebra::SVector;

use super::control::{after_rejection, after_success, attempts_left, error_norm, first_step};
use super::stiffness::StiffnessDetector;
use super::{eps_at, IntegrationError, Settings, Stats};

// Tableau of Dormand & Prince (1980), as matrices A, B, E of ode45.m.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
// 5th-order weights (row 7 of the tableau, hence FSAL); b2 = b7 = 0.
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// 5th minus 4th-order weights; e2 = 0.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
/// 1/(order of the error estimate + 1): the estimate is O(h⁵).
const EXPONENT: f64 = 0.2;
// ntrp45's BI: row j gives the coefficients of s, s², s³, s⁴ multiplying k_j (row 2 is zero).
const BI1: [f64; 4] = [1.0, -183.0 / 64.0, 37.0 / 12.0, -145.0 / 128.0];
const BI3: [f64; 4] = [0.0, 1500.0 / 371.0, -1000.0 / 159.0, 1000.0 / 371.0];
const BI4: [f64; 4] = [0.0, -125.0 / 32.0, 125.0 / 12.0, -375.0 / 64.0];
const BI5: [f64; 4] = [0.0, 9477.0 / 3392.0, -729.0 / 106.0, 25515.0 / 6784.0];
const BI6: [f64; 4] = [0.0, -11.0 / 7.0, 11.0 / 3.0, -55.0 / 28.0];
const BI7: [f64; 4] = [0.0, 3.0 / 2.0, -4.0, 5.0 / 2.0];

/// One attempted step: what error control and dense output need.
struct Attempt<const D: usize> {
    t_new: f64,
    y_new: SVector<f64, D>,
    /// Stages k1, k3, k4, k5, k6, k7 (k2 has zero weight in the solution, estimate and interpolant).
    k: [SVector<f64, D>; 6],
    /// The point stage 6 was evaluated at, for the stiffness test.
    y6: SVector<f64, D>,
}

/// How a DP5 integration ended.
pub(super) enum Outcome<const D: usize> {
    /// `tf` reached.
    Finished(Stats),
    /// The stiffness detector fired on the step that ended at `Handoff::t`; the integration
    /// stopped there, with every grid point up to that time output.
    Stiff(Handoff<D>),
}

/// Where DP5 stopped when it found the problem stiff, for another method to carry on.
pub(super) struct Handoff<const D: usize> {
    pub t: f64,
    pub y: SVector<f64, D>,
    /// f(t, y).
    pub f: SVector<f64, D>,
    /// The step size DP5 would have tried next.
    pub abs_h: f64,
    /// The first grid point not yet output.
    pub next: usize,
    pub stats: Stats,
}

/// Takes a step of size `h` from `(t, y)` with `k1 = f(t, y)`, landing on `t_new`
/// (`t + h`, or `tf` exactly for the last step). Six right-hand-side evaluations.
#[inline(always)]
fn attempt<const D: usize, F>(
    rhs: &mut F,
    t: f64,
    y: &SVector<f64, D>,
    k1: &SVector<f64, D>,
    h: f64,
    t_new: f64,
) -> Attempt<D>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
{
    let k2 = rhs(t + C2 * h, &(y + k1 * (h * A21)));
    let k3 = rhs(t + C3 * h, &(y + (k1 * A31 + k2 * A32) * h));
    let k4 = rhs(t + C4 * h, &(y + (k1 * A41 + k2 * A42 + k3 * A43) * h));
    let k5 = rhs(
        t + C5 * h,
        &(y + (k1 * A51 + k2 * A52 + k3 * A53 + k4 * A54) * h),
    );
    let y6 = y + (k1 * A61 + k2 * A62 + k3 * A63 + k4 * A64 + k5 * A65) * h;
    let k6 = rhs(t + h, &y6);
    // ode45 "purifies" h to the representable t_new − t before forming y_new.
    let h = t_new - t;
    let y_new = y + (k1 * B1 + k3 * B3 + k4 * B4 + k5 * B5 + k6 * B6) * h;
    let k7 = rhs(t_new, &y_new);
    Attempt {
        t_new,
        y_new,
        k: [*k1, k3, k4, k5, k6, k7],
        y6,
    }
}

/// DP5's error estimate `E·k` (to be weighted by [`error_norm`] and scaled by |h|).
#[inline(always)]
fn estimate<const D: usize>(step: &Attempt<D>) -> SVector<f64, D> {
    let k = &step.k;
    k[0] * E1 + k[1] * E3 + k[2] * E4 + k[3] * E5 + k[4] * E6 + k[5] * E7
}

/// `ntrp45`: the 4th-order continuous extension at `t_out` inside the step `[t, t + h]`.
#[inline]
fn interpolate<const D: usize>(
    t: f64,
    y: &SVector<f64, D>,
    h: f64,
    k: &[SVector<f64, D>; 6],
    t_out: f64,
) -> SVector<f64, D> {
    let s = (t_out - t) / h;
    let (s2, s3, s4) = (s * s, s * s * s, (s * s) * (s * s));
    let w = |b: &[f64; 4]| h * (b[0] * s + b[1] * s2 + b[2] * s3 + b[3] * s4);
    y + k[0] * w(&BI1)
        + k[1] * w(&BI3)
        + k[2] * w(&BI4)
        + k[3] * w(&BI5)
        + k[4] * w(&BI6)
        + k[5] * w(&BI7)
}

/// The `ode45` main loop over a validated grid and settings. With a `detector`, the steps are
/// also tested for stiffness and the integration stops at the end of the step the detector
/// fires on (the steps taken until then are exactly those without a detector).
// A transcription of Dormand–Prince with MATLAB ode45's control (ode45.m): kept whole to be read beside it.
pub(super) fn integrate<const D: usize, F, O>(
    mut rhs: F,
    y0: &SVector<f64, D>,
    grid: &[f64],
    s: &Settings,
    mut detector: Option<&mut StiffnessDetector>,
    mut output: O,
) -> Result<Outcome<D>, IntegrationError>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
    O: FnMut(usize, f64, &SVector<f64, D>),
{
    let (t0, tf) = (grid[0], grid[grid.len() - 1]);
    let (rtol, threshold) = (s.rtol, s.threshold);
    let mut stats = Stats::default();
    let (mut t, mut y) = (t0, *y0);
    output(0, t, &y);
    let mut k1 = rhs(t, &y);
    stats.rhs_evals = 1;
    if !k1.iter().all(|v| v.is_finite()) {
        return Err(IntegrationError::NonFinite { t });
    }

    let mut abs_h = first_step(s.initial_step, t, &y, &k1, grid[1] - t0, s, EXPONENT);

    let mut next = 1;
    loop {
        let hmin = 16.0 * eps_at(t);
        abs_h = s.hmax.min(hmin.max(abs_h));
        let mut h = abs_h;
        let mut done = false;
        // Stretch a step within 10% of the end so no sliver of a step is left over.
        if 1.1 * abs_h >= tf - t {
            h = tf - t;
            abs_h = h;
            done = true;
        }

        let mut no_failures = true;
        let (step, err) = loop {
            attempts_left(&stats, s, t, abs_h, &y)?;
            let t_new = if done { tf } else { t + h };
            let step = attempt(&mut rhs, t, &y, &k1, h, t_new);
            stats.rhs_evals += 6;
            let (norm, finite) = error_norm(&y, &step.y_new, &estimate(&step), threshold);
            if !finite {
                return Err(IntegrationError::NonFinite { t: t_new });
            }
            // ode45 scales by |h| before the purification of h, i.e. the step as tried.
            let err = abs_h * norm;
            if err <= rtol {
                break (step, err);
            }
            stats.rejected += 1;
            if abs_h <= hmin {
                return Err(IntegrationError::StepSizeTooSmall { t, h: abs_h });
            }
            abs_h = after_rejection(abs_h, hmin, Some(err), no_failures, rtol, EXPONENT);
            no_failures = false;
            h = abs_h;
            done = false;
        };
        stats.steps += 1;

        let h = step.t_new - t;
        while next < grid.len() && grid[next] <= step.t_new {
            let t_out = grid[next];
            if t_out == step.t_new {
                output(next, t_out, &step.y_new);
            } else {
                output(next, t_out, &interpolate(t, &y, h, &step.k, t_out));
            }
            next += 1;
        }
        if done {
            return Ok(Outcome::Finished(stats));
        }
        let stiff = detector
            .as_mut()
            .is_some_and(|d| d.stiff_after(h, &step.y6, &step.y_new, &step.k[4], &step.k[5]));

        if no_failures {
            abs_h = after_success(abs_h, err, rtol, EXPONENT);
        }
        t = step.t_new;
        y = step.y_new;
        k1 = step.k[5];
        if stiff {
            return Ok(Outcome::Stiff(Handoff {
                t,
                y,
                f: k1,
                abs_h,
                next,
                stats,
            }));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{solve_grid, uniform_grid, IntegrationError, Method, Options, Stats};
    use nalgebra::{vector, SVector};

    type V1 = SVector<f64, 1>;
    type V2 = SVector<f64, 2>;

    fn decay(_t: f64, y: &V1) -> V1 {
        -y
    }

    /// x'' = −x from (1, 0): x = cos t, v = −sin t.
    fn oscillator(_t: f64, y: &V2) -> V2 {
        vector![y[1], -y[0]]
    }

    fn tol(rtol: f64, atol: f64) -> Options {
        Options {
            rtol,
            atol,
            ..Options::default()
        }
    }

    /// Largest |y_i(t) − exact(t)| over the grid, and the stats.
    fn max_error<const D: usize>(
        rhs: fn(f64, &SVector<f64, D>) -> SVector<f64, D>,
        exact: fn(f64) -> SVector<f64, D>,
        grid: &[f64],
        options: &Options,
    ) -> (f64, Stats) {
        let mut worst = 0.0f64;
        let stats = solve_grid(rhs, &exact(grid[0]), grid, options, |_, t, y| {
            worst = worst.max((y - exact(t)).amax());
        })
        .unwrap();
        (worst, stats)
    }

    fn exp_exact(t: f64) -> V1 {
        vector![(-t).exp()]
    }

    fn osc_exact(t: f64) -> V2 {
        vector![t.cos(), -t.sin()]
    }

    #[test]
    fn decay_and_oscillator_match_closed_form() {
        let grid = uniform_grid(0.0, 5.0, 0.05);
        let (e, _) = max_error(decay, exp_exact, &grid, &Options::default());
        assert!(e < 1e-3 && e > 1e-9, "decay, default tolerances: {e:e}");
        let (e, _) = max_error(decay, exp_exact, &grid, &tol(1e-10, 1e-10));
        assert!(e < 1e-8, "decay, 1e-10: {e:e}");

        let grid = uniform_grid(0.0, 10.0, 0.05);
        let (e, _) = max_error(oscillator, osc_exact, &grid, &Options::default());
        assert!(
            e < 5e-3 && e > 1e-9,
            "oscillator, default tolerances: {e:e}"
        );
        let (e, _) = max_error(oscillator, osc_exact, &grid, &tol(1e-10, 1e-10));
        assert!(e < 1e-8, "oscillator, 1e-10: {e:e}");
    }

    #[test]
    fn error_falls_with_tolerance() {
        let grid = uniform_grid(0.0, 10.0, 0.1);
        let errors: Vec<f64> = [1e-4, 1e-6, 1e-8]
            .iter()
            .map(|&r| max_error(oscillator, osc_exact, &grid, &tol(r, r * 1e-3)).0)
            .collect();
        assert!(
            errors[1] < errors[0] / 10.0 && errors[2] < errors[1] / 10.0,
            "{errors:?}"
        );
    }

    #[test]
    fn fixed_steps_converge_at_fifth_order() {
        // A loose tolerance never rejects, and max_step pins every step to h.
        let fixed = |h: f64| Options {
            rtol: 0.1,
            atol: 0.1,
            initial_step: Some(h),
            max_step: Some(h),
            max_steps: 10_000,
            method: Method::Explicit,
        };
        let grid = [0.0, 10.0];
        let (coarse, s) = max_error(oscillator, osc_exact, &grid, &fixed(0.2));
        assert_eq!((s.steps, s.rejected), (50, 0));
        let (fine, s) = max_error(oscillator, osc_exact, &grid, &fixed(0.1));
        assert_eq!((s.steps, s.rejected), (100, 0));
        let order = (coarse / fine).log2();
        assert!(
            (4.7..5.3).contains(&order),
            "observed order {order} ({coarse:e} -> {fine:e})"
        );
    }

    #[test]
    fn dense_output_is_accurate_between_steps() {
        let grid = uniform_grid(0.0, 4.0, 0.02);
        let options = Options {
            max_step: Some(4.0),
            ..tol(1e-6, 1e-9)
        };
        let (e, stats) = max_error(decay, exp_exact, &grid, &options);
        // Several grid points per step, so most values come from the interpolant; linear
        // interpolation over such steps would be off by ~1e-3.
        assert!(stats.steps * 4 < grid.len(), "{stats:?}");
        assert!(e < 2e-6, "{e:e}");
        let (e, stats) = max_error(oscillator, osc_exact, &grid, &options);
        assert!(stats.steps * 4 < grid.len(), "{stats:?}");
        assert!(e < 2e-6, "{e:e}");
    }

    #[test]
    fn last_point_is_the_step_solution_at_tf() {
        let mut last = None;
        solve_grid(
            decay,
            &vector![1.0],
            &[0.0, 0.37, 1.0],
            &Options::default(),
            |i, t, y| last = Some((i, t, y[0])),
        )
        .unwrap();
        let (i, t, y) = last.unwrap();
        assert_eq!((i, t), (2, 1.0));
        assert!((y - (-1.0f64).exp()).abs() < 1e-4);
    }

    #[test]
    fn blow_up_stops_with_an_error_not_nan() {
        let rhs = |_t: f64, y: &V1| vector![y[0] * y[0]];
        let mut outputs = Vec::new();
        let result = solve_grid(
            rhs,
            &vector![1.0],
            &uniform_grid(0.0, 2.0, 0.1),
            &Options::default(),
            |_, t, y| outputs.push((t, y[0])),
        );
        match result {
            Err(
                IntegrationError::StepSizeTooSmall { t, .. } | IntegrationError::NonFinite { t },
            ) => {
                assert!(t > 0.99 && t <= 1.0 + 1e-6, "stopped at {t}")
            }
            other => panic!("expected a step-size or non-finite error, got {other:?}"),
        }
        assert!(
            outputs.iter().all(|&(t, y)| t < 1.0 && y.is_finite()),
            "{outputs:?}"
        );
        assert_eq!(outputs.len(), 10);
    }

    #[test]
    fn nan_derivative_is_reported_where_it_appears() {
        let rhs = |t: f64, y: &V1| if t > 1.0 { vector![f64::NAN] } else { -y };
        let result = solve_grid(
            rhs,
            &vector![1.0],
            &uniform_grid(0.0, 2.0, 0.1),
            &Options::default(),
            |_, _, y| assert!(y[0].is_finite()),
        );
        match result {
            Err(IntegrationError::NonFinite { t }) => assert!(t > 1.0 && t < 1.3, "{t}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn step_limit_is_enforced() {
        let options = Options {
            max_steps: 5,
            ..Options::default()
        };
        let result = solve_grid(decay, &vector![1.0], &[0.0, 10.0], &options, |_, _, _| {});
        match result {
            Err(IntegrationError::TooManySteps {
                t, max_steps: 5, ..
            }) => assert!(t > 0.0 && t < 10.0),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn constant_solution_takes_hmax_steps_with_fsal_counting() {
        // f ≡ 0: rh = 0, so h = hmax = 0.1 and no step can fail; the 10th step is stretched onto tf.
        let stats = solve_grid(
            |_, _: &V2| V2::zeros(),
            &vector![1.0, -2.0],
            &[0.0, 1.0],
            &Options::default(),
            |_, _, y| assert_eq!(*y, vector![1.0, -2.0]),
        )
        .unwrap();
        assert_eq!(
            stats,
            Stats {
                rhs_evals: 61,
                steps: 10,
                rejected: 0,
                jacobian_evals: 0,
                factorisations: 0,
            }
        );
    }

    #[test]
    fn rejected_attempts_count_six_evaluations_each() {
        let mut calls = 0;
        let rhs = |_t: f64, y: &V1| {
            calls += 1;
            y * -50.0
        };
        // y' = −50y turns stiff once y has decayed: Auto would switch to Rodas5P.
        let options = Options {
            initial_step: Some(1.0),
            max_step: Some(1.0),
            method: Method::Explicit,
            ..Options::default()
        };
        let stats = solve_grid(rhs, &vector![1.0], &[0.0, 3.0], &options, |_, _, _| {}).unwrap();
        assert!(stats.rejected >= 2, "{stats:?}");
        assert_eq!(stats.rhs_evals, 6 * (stats.steps + stats.rejected) + 1);
        assert_eq!(stats.rhs_evals, calls);
    }
}
