//! # toolconf-integrators
//!
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
//!   `rosenbrock` and `rodas5p` modules). The Jacobian comes from the caller
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

mod control;
mod dopri5;
mod grid;
mod options;
mod problem;
mod rodas5p;
mod rodas_lean;
mod rosenbrock;
mod stiffness;
#[cfg(test)]
mod tests;

use nalgebra::{SMatrix, SVector};

pub use grid::uniform_grid;
use grid::{eps_at, resolve, Settings};
pub use options::{IntegrationError, Method, Options, Stats};
use problem::{Analytic, FiniteDifference};

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
            return rodas5p::integrate(&mut problem, start, grid, settings, output, false);
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
            let lean = method == Method::Fast;
            rodas5p::integrate(&mut problem, start, grid, settings, output, lean)
        }
    }
}
