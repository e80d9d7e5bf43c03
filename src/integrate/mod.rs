//! Dormand–Prince 5(4) integration that reproduces MATLAB's `ode45`, the solver the paper used
//! for its 5 s closed-loop simulations sampled every 0.05 s, and the Rosenbrock method Rodas5P
//! for stiff problems, with an automatic switch from the first to the second.
//!
//! States are fixed-size `nalgebra::SVector<f64, D>`, so the stepping loop allocates nothing and
//! the right-hand side is called through a generic closure (no dynamic dispatch).
//!
//! # Methods ([`Options::method`])
//!
//! * [`Method::Explicit`]: DP5, exactly `ode45` (below).
//! * [`Method::Stiff`]: Rodas5P (Steinebach 2023), a stiffly accurate L-stable Rosenbrock
//!   method of order 5(4) with a dense output of order 4, one Jacobian per step and one LU
//!   factorisation per attempt, with `ode45`'s error norm and step-size rules (see the
//!   `rosenbrock` module). The Jacobian comes from the caller
//!   ([`solve_grid_with_jacobian`]) or from forward differences ([`solve_grid`]).
//! * [`Method::Auto`] (the default): DP5 with Hairer's stiffness detection (`DOPRI5`'s test:
//!   `h·|λ| > 3.25`, |λ| estimated as `‖k7 − k6‖/‖y7 − y6‖`, on 15 accepted steps, the count
//!   cleared by 6 consecutive steps below), then Rodas5P from the end of the step the test
//!   fired on to `tf` (no switch back), starting with the step DP5 would have tried next and
//!   DP5's `f(t, y)`. Until the test fires, the steps, output and [`Stats`] are exactly those
//!   of [`Method::Explicit`]: a problem never found stiff is integrated by DP5 bit for bit.
//! * [`Method::Fast`] (the command line's default, for throughput on populations of tools):
//!   as `Auto` with a test that fires after 10 steps at the boundary instead of 15, then the
//!   same Rodas5P with less work per step (the `rodas_lean` module).
//!
//! # What DP5 follows of `ode45`
//!
//! Sources: L. F. Shampine & M. W. Reichelt, "The MATLAB ODE Suite", SIAM J. Sci. Comput. 18(1),
//! 1997; MATLAB's `ode45.m`, `ntrp45.m` and `odearguments.m`; J. R. Dormand & P. J. Prince,
//! "A family of embedded Runge–Kutta formulae", J. Comput. Appl. Math. 6(1), 1980; Hairer,
//! Nørsett & Wanner, "Solving ODEs I", §II.6 (dense output).
//!
//! * Dormand–Prince 5(4) tableau (`A`, `B`, `E` of `ode45.m`), local extrapolation (the 5th-order
//!   solution is propagated), FSAL: `f(t_new, y_new)` is reused as the next step's first stage.
//! * Error estimate `err = |h| · ‖(E·k) ./ max(max(|y|, |y_new|), atol/rtol)‖_∞`; a step is
//!   accepted when `err <= rtol`.
//! * After a rejection `h ← max(hmin, h·max(0.1, 0.8·(rtol/err)^(1/5)))` on the first failure of a
//!   step and `h ← max(hmin, h/2)` on further failures of the same step (as `ode45.m` does); a step
//!   that needed a retry does not grow the next one. After a clean success
//!   `h ← h / max(0.2, 1.25·(err/rtol)^(1/5))`, i.e. at most 5×.
//! * `hmin = 16·eps(t)` (the spacing of doubles at `t`, MATLAB's `eps(t)`), recomputed every
//!   step; a rejection with `h <= hmin` is [`IntegrationError::StepSizeTooSmall`] (where `ode45`
//!   warns "Unable to meet integration tolerances" and stops).
//! * `hmax = min(|tf − t0|, max_step)`, default `0.1·|tf − t0|`.
//! * Initial step: `h = min(hmax, |grid[1] − grid[0]|)`, reduced to `1/rh` when `h·rh > 1` with
//!   `rh = ‖f0 ./ max(|y0|, atol/rtol)‖_∞ / (0.8·rtol^(1/5))`, then at least `hmin`. An explicit
//!   [`Options::initial_step`] is used as `min(hmax, max(hmin, h))`.
//! * A step within 10 % of the end is stretched to land on `tf` exactly.
//! * Output at the requested points: a point equal to a step end gets that step's solution,
//!   points inside a step get the free 4th-order continuous extension (`ntrp45`, matrix `BI`).
//! * `rtol` below `100·eps` is raised to `100·eps` (silently; `ode45` warns).
//!
//! # Where it differs
//!
//! * A non-finite stage, error estimate or new state stops the integration with
//!   [`IntegrationError::NonFinite`]; `ode45` would accept a NaN step (NaN fails `err > rtol`)
//!   and return NaNs.
//! * Only forward integration on strictly increasing grids, scalar `atol`, no `NormControl`,
//!   `NonNegative`, events, or `Refine` (irrelevant when output is requested at grid points).
//! * [`Options::max_steps`] bounds attempted steps (`ode45` has no such limit).

mod dopri5;
mod rodas_lean;
mod rosenbrock;
mod stiffness;

use nalgebra::{SMatrix, SVector};

/// Which integration method runs (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// Dormand–Prince 5(4), `ode45`.
    Explicit,
    /// Rodas5P, a Rosenbrock (linearly implicit) method, using the Jacobian.
    Stiff,
    /// DP5 until its stiffness detection fires, Rodas5P from there on.
    #[default]
    Auto,
    /// Throughput on populations of tools (issue 14): DP5 with a quicker stiffness test
    /// (10 steps at the stability boundary instead of `DOPRI5`'s 15), then Rodas5P with less
    /// work per step (the `rodas_lean` module, the same method as [`Method::Stiff`] up to
    /// rounding). Not `ode45`'s numbers once the test fires: [`Method::Explicit`] keeps those.
    Fast,
}

impl Method {
    /// Every method, in the order the command line lists them.
    pub const ALL: [Method; 4] = [Method::Fast, Method::Explicit, Method::Auto, Method::Stiff];

    /// The method's name on the command line (`--method`) and in Python (`method=`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Explicit => "explicit",
            Method::Stiff => "stiff",
            Method::Auto => "auto",
            Method::Fast => "fast",
        }
    }

    /// The method in words, for reports and command-line output.
    pub fn describe(self) -> &'static str {
        match self {
            Method::Explicit => "explicit: Dormand-Prince 5(4) exactly as MATLAB ode45 (the paper's numerics)",
            Method::Stiff => "stiff: Rodas5P throughout",
            Method::Auto => "auto: ode45 on tasks 1-2, ode45 then Rodas5P after Hairer's stiffness test on task 3",
            Method::Fast => "fast: ode45's steps until a 10-step stiffness test fires, then a lean Rodas5P",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;

    /// A method by [`Method::name`].
    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
                format!("'{s}': expected {}", names.join(", "))
            })
    }
}

/// Error control, step-size limits and method. The tolerances and limits default to `ode45`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Relative tolerance (`RelTol`), finite and > 0.
    pub rtol: f64,
    /// Absolute tolerance (`AbsTol`), finite and > 0, the same for every component.
    pub atol: f64,
    /// First step to try (`InitialStep`); `None` uses `ode45`'s heuristic.
    pub initial_step: Option<f64>,
    /// Largest step (`MaxStep`); `None` means `0.1·|tf − t0|`.
    pub max_step: Option<f64>,
    /// Most step attempts (accepted + rejected) before giving up, ≥ 1.
    pub max_steps: usize,
    /// The method, [`Method::Auto`] by default.
    pub method: Method,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: 1e-3,
            atol: 1e-6,
            initial_step: None,
            max_step: None,
            max_steps: 1_000_000,
            method: Method::default(),
        }
    }
}

/// Work done by one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Right-hand-side evaluations, `f(t0, y0)` included. DP5: `6·(steps + rejected) + 1`
    /// thanks to FSAL; Rodas5P from `t0`: `steps + 7·(steps + rejected)` (an attempt with a
    /// singular iteration matrix costs none), plus `D + 1` per Jacobian formed by finite
    /// differences.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts.
    pub rejected: usize,
    /// Jacobian evaluations, one per Rodas5P step (0 for DP5).
    pub jacobian_evals: usize,
    /// LU factorisations of the iteration matrix, one per Rodas5P attempt (0 for DP5).
    pub factorisations: usize,
}

/// Why an integration stopped early or could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrationError {
    /// The state or its derivative became NaN or infinite; `t` is the end of the step in which
    /// that happened (or `grid[0]` when `y0` or `f(t0, y0)` is not finite).
    #[error("integration failed at t = {t} s: state became non-finite")]
    NonFinite { t: f64 },
    /// The step size fell to `16·eps(t)` and the tolerances still could not be met, typically
    /// a singularity (finite-time blow-up) near `t`.
    #[error(
        "integration failed at t = {t} s: step size {h:e} s reached the minimum 16·eps(t) without meeting the tolerances"
    )]
    StepSizeTooSmall { t: f64, h: f64 },
    /// More than `max_steps` step attempts.
    #[error("integration failed at t = {t} s: exceeded the limit of {max_steps} step attempts")]
    TooManySteps { t: f64, max_steps: usize },
    /// The output grid is unusable.
    #[error("invalid time grid: {reason}")]
    InvalidGrid { reason: String },
    /// An option is out of its domain.
    #[error("invalid integrator options: {reason}")]
    InvalidOptions { reason: String },
}

impl IntegrationError {
    /// The time the integration failed at, for failures during the integration.
    pub fn time(&self) -> Option<f64> {
        match self {
            IntegrationError::NonFinite { t }
            | IntegrationError::StepSizeTooSmall { t, .. }
            | IntegrationError::TooManySteps { t, .. } => Some(*t),
            IntegrationError::InvalidGrid { .. } | IntegrationError::InvalidOptions { .. } => None,
        }
    }
}

/// Integrates from `grid[0]` to `grid.last()` with `options.method` and calls
/// `output(i, t_i, &y_i)` for every grid point (i = 0 included, with y0), in order, values
/// between steps taken from the method's dense-output interpolant.
///
/// `grid` must have at least two finite, strictly increasing points. The step sizes are chosen
/// by error control, not by the grid (as in `ode45` with more than two `tspan` entries), except
/// that the default initial step is at most `grid[1] − grid[0]`. On error, `output` has already
/// been called for the grid points reached before the failure.
///
/// When Rodas5P runs, its Jacobian is formed by forward differences (`D + 1` evaluations of `rhs`
/// per step, ∂f/∂t included, counted in [`Stats::rhs_evals`]); [`solve_grid_with_jacobian`]
/// takes an analytic one.
pub fn solve_grid<const D: usize, F, O>(
    rhs: F,
    y0: &SVector<f64, D>,
    grid: &[f64],
    options: &Options,
    output: O,
) -> Result<Stats, IntegrationError>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
    O: FnMut(usize, f64, &SVector<f64, D>),
{
    let settings = resolve(options, grid)?;
    let problem = FiniteDifference {
        rhs,
        threshold: settings.threshold,
    };
    solve(problem, y0, grid, options.method, &settings, output)
}

/// [`solve_grid`] with an analytic Jacobian: `jacobian(t, y)` returns `(∂f/∂y, ∂f/∂t)` at
/// `(t, y)` (∂f/∂t is zero for an autonomous problem). It is called once per Rodas5P step, so
/// never when DP5 runs.
pub fn solve_grid_with_jacobian<const D: usize, F, J, O>(
    rhs: F,
    jacobian: J,
    y0: &SVector<f64, D>,
    grid: &[f64],
    options: &Options,
    output: O,
) -> Result<Stats, IntegrationError>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
    J: FnMut(f64, &SVector<f64, D>) -> (SMatrix<f64, D, D>, SVector<f64, D>),
    O: FnMut(usize, f64, &SVector<f64, D>),
{
    let settings = resolve(options, grid)?;
    solve(
        Analytic { rhs, jacobian },
        y0,
        grid,
        options.method,
        &settings,
        output,
    )
}

/// Runs `method` on a validated grid and settings.
fn solve<const D: usize, P, O>(
    mut problem: P,
    y0: &SVector<f64, D>,
    grid: &[f64],
    method: Method,
    settings: &Settings,
    mut output: O,
) -> Result<Stats, IntegrationError>
where
    P: rosenbrock::Problem<D>,
    O: FnMut(usize, f64, &SVector<f64, D>),
{
    if !y0.iter().all(|v| v.is_finite()) {
        return Err(IntegrationError::NonFinite { t: grid[0] });
    }
    let mut detector = match method {
        Method::Explicit => None,
        Method::Auto => Some(stiffness::StiffnessDetector::default()),
        Method::Fast => Some(stiffness::StiffnessDetector::with_patience(
            stiffness::FAST_STIFF_STEPS,
        )),
        Method::Stiff => {
            let t0 = grid[0];
            output(0, t0, y0);
            let f = problem.rhs(t0, y0);
            if !f.iter().all(|v| v.is_finite()) {
                return Err(IntegrationError::NonFinite { t: t0 });
            }
            let start = rosenbrock::Start {
                t: t0,
                y: *y0,
                f,
                abs_h: settings.initial_step,
                next: 1,
                stats: Stats {
                    rhs_evals: 1,
                    ..Stats::default()
                },
            };
            return rosenbrock::integrate(&mut problem, start, grid, settings, output);
        }
    };
    let rhs = |t: f64, y: &SVector<f64, D>| problem.rhs(t, y);
    match dopri5::integrate(rhs, y0, grid, settings, detector.as_mut(), &mut output)? {
        dopri5::Outcome::Finished(stats) => Ok(stats),
        dopri5::Outcome::Stiff(at) => {
            let start = rosenbrock::Start {
                t: at.t,
                y: at.y,
                f: at.f,
                abs_h: Some(at.abs_h),
                next: at.next,
                stats: at.stats,
            };
            if method == Method::Fast {
                rodas_lean::integrate(&mut problem, start, grid, settings, output)
            } else {
                rosenbrock::integrate(&mut problem, start, grid, settings, output)
            }
        }
    }
}

/// A problem with its analytic Jacobian.
struct Analytic<F, J> {
    rhs: F,
    jacobian: J,
}

impl<const D: usize, F, J> rosenbrock::Problem<D> for Analytic<F, J>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
    J: FnMut(f64, &SVector<f64, D>) -> (SMatrix<f64, D, D>, SVector<f64, D>),
{
    #[inline]
    fn rhs(&mut self, t: f64, y: &SVector<f64, D>) -> SVector<f64, D> {
        (self.rhs)(t, y)
    }

    #[inline]
    fn jacobian(
        &mut self,
        t: f64,
        y: &SVector<f64, D>,
        _f: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SVector<f64, D>, usize) {
        let (dfdy, dfdt) = (self.jacobian)(t, y);
        (dfdy, dfdt, 0)
    }
}

/// A problem whose Jacobian is formed by forward differences, as `rodas.f` does without one:
/// column j with the increment `√eps·max(|y_j|, atol/rtol)`, ∂f/∂t with `√(eps·max(|t|, 1e-5))`.
struct FiniteDifference<F> {
    rhs: F,
    threshold: f64,
}

impl<const D: usize, F> rosenbrock::Problem<D> for FiniteDifference<F>
where
    F: FnMut(f64, &SVector<f64, D>) -> SVector<f64, D>,
{
    #[inline]
    fn rhs(&mut self, t: f64, y: &SVector<f64, D>) -> SVector<f64, D> {
        (self.rhs)(t, y)
    }

    fn jacobian(
        &mut self,
        t: f64,
        y: &SVector<f64, D>,
        f: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SVector<f64, D>, usize) {
        let sqrt_eps = f64::EPSILON.sqrt();
        let mut dfdy = SMatrix::<f64, D, D>::zeros();
        for j in 0..D {
            let mut shifted = *y;
            shifted[j] += sqrt_eps * y[j].abs().max(self.threshold);
            // The increment as represented, not as intended.
            let delta = shifted[j] - y[j];
            dfdy.set_column(j, &(((self.rhs)(t, &shifted) - f) / delta));
        }
        let t_shifted = t + (f64::EPSILON * t.abs().max(1e-5)).sqrt();
        let dfdt = ((self.rhs)(t_shifted, y) - f) / (t_shifted - t);
        (dfdy, dfdt, D + 1)
    }
}

/// `t0, t0 + dt, t0 + 2·dt, …, tf`: each point is `t0 + i·dt` (no accumulated rounding) and the
/// last is exactly `tf`, e.g. `(0, 5, 0.05)` gives 101 points. When `dt` does not divide
/// `tf − t0`, the last interval is shorter than `dt`.
///
/// Returns an empty grid (which [`solve_grid`] rejects) unless all inputs are finite, `dt > 0`
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
struct Settings {
    rtol: f64,
    threshold: f64,
    hmax: f64,
    initial_step: Option<f64>,
    max_steps: usize,
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

fn resolve(options: &Options, grid: &[f64]) -> Result<Settings, IntegrationError> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::vector;

    fn decay(_t: f64, y: &SVector<f64, 1>) -> SVector<f64, 1> {
        -y
    }

    fn solve_err(grid: &[f64], options: &Options) -> IntegrationError {
        solve_grid(decay, &vector![1.0], grid, options, |_, _, _| {}).unwrap_err()
    }

    #[test]
    fn uniform_grid_hits_tf_exactly_without_accumulation() {
        let g = uniform_grid(0.0, 5.0, 0.05);
        assert_eq!(g.len(), 101);
        assert_eq!(g[0], 0.0);
        assert_eq!(*g.last().unwrap(), 5.0);
        assert_eq!(g[37], 37.0 * 0.05);
        assert!(g.windows(2).all(|w| w[1] > w[0]));
        assert_eq!(
            uniform_grid(0.0, 1.0, 0.3),
            vec![0.0, 0.3, 0.6, 0.3 * 3.0, 1.0]
        );
        assert_eq!(uniform_grid(1.0, 1.5, 2.0), vec![1.0, 1.5]);
        assert!(uniform_grid(0.0, 1.0, 0.0).is_empty());
        assert!(uniform_grid(1.0, 0.0, 0.1).is_empty());
        assert!(uniform_grid(0.0, f64::NAN, 0.1).is_empty());
    }

    #[test]
    fn invalid_grids_are_rejected() {
        let o = Options::default();
        for grid in [
            &[][..],
            &[0.0],
            &[0.0, 1.0, 1.0],
            &[0.0, 2.0, 1.0],
            &[0.0, f64::NAN],
            &[0.0, f64::INFINITY],
        ] {
            assert!(
                matches!(solve_err(grid, &o), IntegrationError::InvalidGrid { .. }),
                "{grid:?}"
            );
        }
        assert!(matches!(
            solve_grid(
                decay,
                &vector![1.0],
                &uniform_grid(1.0, 0.0, 0.1),
                &o,
                |_, _, _| {}
            ),
            Err(IntegrationError::InvalidGrid { .. })
        ));
    }

    #[test]
    fn invalid_options_are_rejected() {
        let d = Options::default();
        let bad = [
            Options { rtol: 0.0, ..d },
            Options { rtol: -1e-3, ..d },
            Options {
                rtol: f64::NAN,
                ..d
            },
            Options { atol: 0.0, ..d },
            Options {
                atol: f64::INFINITY,
                ..d
            },
            Options {
                initial_step: Some(0.0),
                ..d
            },
            Options {
                max_step: Some(-0.1),
                ..d
            },
            Options {
                max_step: Some(f64::NAN),
                ..d
            },
            Options { max_steps: 0, ..d },
        ];
        for o in bad {
            assert!(
                matches!(
                    solve_err(&[0.0, 1.0], &o),
                    IntegrationError::InvalidOptions { .. }
                ),
                "{o:?}"
            );
        }
    }

    #[test]
    fn non_finite_initial_state_is_an_error() {
        let e = solve_grid(
            decay,
            &vector![f64::NAN],
            &[0.5, 1.0],
            &Options::default(),
            |_, _, _| {},
        );
        assert_eq!(e, Err(IntegrationError::NonFinite { t: 0.5 }));
    }

    #[test]
    fn messages_name_time_and_reason() {
        let e = IntegrationError::NonFinite { t: 1.234 };
        assert_eq!(
            e.to_string(),
            "integration failed at t = 1.234 s: state became non-finite"
        );
        let e = IntegrationError::StepSizeTooSmall { t: 0.5, h: 1e-15 };
        assert!(e
            .to_string()
            .starts_with("integration failed at t = 0.5 s: step size 1e-15 s"));
        let e = IntegrationError::TooManySteps {
            t: 2.0,
            max_steps: 7,
        };
        assert_eq!(
            e.to_string(),
            "integration failed at t = 2 s: exceeded the limit of 7 step attempts"
        );
        let e = solve_err(&[0.0, 0.0], &Options::default());
        assert!(
            e.to_string()
                .starts_with("invalid time grid: not strictly increasing"),
            "{e}"
        );
        let e = solve_err(
            &[0.0, 1.0],
            &Options {
                rtol: -1.0,
                ..Options::default()
            },
        );
        assert_eq!(
            e.to_string(),
            "invalid integrator options: rtol = -1 must be finite and > 0"
        );
    }

    #[test]
    fn output_is_called_once_per_grid_point_in_order() {
        let grid = uniform_grid(0.0, 2.0, 0.1);
        let y0 = vector![1.0];
        let mut seen = Vec::new();
        solve_grid(
            decay,
            &y0,
            &grid,
            &Options::default(),
            |i, t, y: &SVector<f64, 1>| seen.push((i, t, y[0])),
        )
        .unwrap();
        assert_eq!(seen.len(), grid.len());
        for (k, &(i, t, _)) in seen.iter().enumerate() {
            assert_eq!((i, t), (k, grid[k]));
        }
        assert_eq!(seen[0].2, 1.0);
        assert!((seen[grid.len() - 1].2 - (-2.0f64).exp()).abs() < 1e-3);
    }
}
