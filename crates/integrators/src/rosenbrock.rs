//! The stiffly accurate Rosenbrock methods' shared main loop (`rodas.f`'s transformed form)
//! with `ode45`'s error and step-size control; the method itself, Rodas5P, is `rodas5p`'s
//! tableau and step, and `rodas_lean`'s leaner step of the same method.
//!
//! # The step
//!
//! In the transformed variables of `rodas.f`, with `E = I/(h·γ) − J`, `J = ∂f/∂y(t, y)` and
//! `f_t = ∂f/∂t(t, y)`, stage i (i = 1…8) solves
//!
//! ```text
//! E·k_i = f(t + α_i·h, y + Σ_{j<i} a_ij·k_j) + Σ_{j<i} (c_ij/h)·k_j + d_i·h·f_t
//! ```
//!
//! (stage 1 reuses `f(t, y)`). Stages 6, 7 and 8 are evaluated at `t + h` on the successive
//! solutions `u_6 = y + Σ_{j≤5} a_6j·k_j`, `u_7 = u_6 + k_6`, `u_8 = u_7 + k_7` (the embedded
//! order-4 solution), and `y_new = u_8 + k_8`, so `k_8` is the error estimate. One Jacobian per
//! step (kept when the step is retried: `t` and `y` have not changed), one LU factorisation of
//! `E` per attempt, eight solves and seven new right-hand-side evaluations per attempt, plus
//! `f(t_new, y_new)` at the start of the next step.
//!
//! The LU factorisation (partial pivoting, on the stack) is the core's
//! [`toolconf_core::linalg::Lu`]: nalgebra's needs
//! the bound `Const<D>: DimMin<Const<D>>`, which would have to be added to [`super::solve_grid`]
//! and so to every caller generic over the dimension.
//!
//! # Error and step-size control: `ode45`'s conventions
//!
//! * `err = ‖k_8 ./ max(|y|, |y_new|, atol/rtol)‖_∞` (`k_8` is already a displacement, so unlike
//!   DP5's it is not multiplied by `|h|`); the step is accepted when `err <= rtol`.
//! * The exponent is 1/5 (the estimate is O(h⁵)): after a clean success
//!   `h ← h / max(0.2, 1.25·(err/rtol)^(1/5))`; after a first failure
//!   `h ← max(hmin, h·max(0.1, 0.8·(rtol/err)^(1/5)))`, after further failures of the same step
//!   `h ← max(hmin, h/2)`; a retried step does not grow the next one.
//! * `hmin = 16·eps(t)`, `hmax`, the 10 % stretch onto `tf`, the initial-step heuristic and
//!   output at the grid points are those of the DP5 stepper.
//! * A singular `E` (`1/(h·γ)` an eigenvalue of `J`) counts as a failed attempt and halves `h`.
//! * A non-finite stage, estimate or new state is [`IntegrationError::NonFinite`], as for DP5.
//!
//! # Dense output
//!
//! `y(t + s·h) = (1 − s)·y + s·(y_new + (1 − s)·(q_1 + s·(q_2 + s·q_3)))` with
//! `q_r = Σ_j h_rj·k_j`: order 4, exact at both ends.

use nalgebra::{SMatrix, SVector};

use super::control::{after_rejection, after_success, attempts_left, error_norm, first_step};
use super::{eps_at, IntegrationError, Settings, Stats};

/// What the stiff stepper needs of the problem.
pub(super) trait Problem<const D: usize> {
    fn rhs(&mut self, t: f64, y: &SVector<f64, D>) -> SVector<f64, D>;

    /// `(∂f/∂y, ∂f/∂t)` at `(t, y)`, where `f(t, y) = f`, and the right-hand-side evaluations
    /// spent on them (non-zero for finite differences).
    fn jacobian(
        &mut self,
        t: f64,
        y: &SVector<f64, D>,
        f: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SVector<f64, D>, usize);
}

/// Where the integration starts: `grid[0]`, or where DP5 handed over.
pub(super) struct Start<const D: usize> {
    pub t: f64,
    pub y: SVector<f64, D>,
    /// f(t, y).
    pub f: SVector<f64, D>,
    /// First step to try; `None` uses the initial-step heuristic.
    pub abs_h: Option<f64>,
    /// The first grid point not yet output.
    pub next: usize,
    /// The work done before `t`.
    pub stats: Stats,
}

/// A stiffly accurate Rosenbrock method with `S` stages in `rodas.f`'s transformed form: the
/// last stage is the error estimate and `y_new = y + Σ_j a_Sj·k_j + k_S`.
pub(super) struct Tableau<const S: usize> {
    pub(super) gamma: f64,
    /// Stage times α_i.
    pub(super) alpha: [f64; S],
    /// Row i: the coefficients of k_j (j < i) in the argument of stage i.
    pub(super) a: [[f64; S]; S],
    /// Row i: the coefficients of k_j/h (j < i) added to stage i's right-hand side.
    pub(super) c: [[f64; S]; S],
    /// The coefficients of h·∂f/∂t.
    pub(super) d: [f64; S],
    /// Rows of the dense output, `q_r = Σ_j h_rj·k_j`.
    pub(super) dense: [[f64; S]; 3],
    /// 1/(order of the embedded method + 1).
    pub(super) exponent: f64,
}

/// The step an attempt takes: from `(t, y)`, where f = `f0` and ∂f/∂t = `dfdt`, to `t_new`
/// (its size `h = t_new − t`).
#[derive(Clone, Copy)]
pub(super) struct Span<'a, const D: usize> {
    pub t: f64,
    pub t_new: f64,
    pub y: &'a SVector<f64, D>,
    pub f0: &'a SVector<f64, D>,
    pub dfdt: &'a SVector<f64, D>,
}

/// What a Rosenbrock stepper does inside the shared main loop [`run`]: factor the iteration
/// matrix `E = I/(h·γ) − J`, take an attempt with it, and interpolate inside an accepted step.
/// `rodas5p`'s `Standard` is `rodas.f`'s form for any [`Tableau`]; `rodas_lean` is the other.
pub(super) trait Stepper<const D: usize, const S: usize> {
    type Lu;
    /// An attempt's stages, its new solution and whatever its dense output keeps.
    type Step;
    fn factor(e: SMatrix<f64, D, D>) -> Option<Self::Lu>;
    /// The stages of the step `span`; `S − 1` right-hand-side evaluations.
    fn attempt<P: Problem<D>>(&self, problem: &mut P, lu: &Self::Lu, span: Span<D>) -> Self::Step;
    fn y_new(step: &Self::Step) -> &SVector<f64, D>;
    /// The last stage, the error estimate.
    fn estimate(step: &Self::Step) -> &SVector<f64, D>;
    /// The continuous extension at `t_out` inside the step `[t, t + h]`.
    fn interpolate(
        &self,
        step: &mut Self::Step,
        t: f64,
        y: &SVector<f64, D>,
        h: f64,
        t_out: f64,
    ) -> SVector<f64, D>;
}

/// The main loop of any stiffly accurate method in the form of [`Tableau`], its steps taken by
/// `stepper`: `ode45`'s step-size rules, `hmin`, the stretch onto `tf`, singular matrices and
/// output at the grid points.
// A transcription of Hairer & Wanner's RODAS (rodas.f) / Steinebach's Rodas5P: kept whole to be read beside it.
pub(super) fn run<const D: usize, const S: usize, P, O, M>(
    tab: &Tableau<S>,
    stepper: &M,
    problem: &mut P,
    start: Start<D>,
    grid: &[f64],
    s: &Settings,
    mut output: O,
) -> Result<Stats, IntegrationError>
where
    P: Problem<D>,
    O: FnMut(usize, f64, &SVector<f64, D>),
    M: Stepper<D, S>,
{
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

    let mut abs_h = first_step(abs_h, t, &y, &f0, grid[next] - t, s, exponent);

    loop {
        let hmin = 16.0 * eps_at(t);
        abs_h = s.hmax.min(hmin.max(abs_h));
        let mut done = false;
        if 1.1 * abs_h >= tf - t {
            abs_h = tf - t;
            done = true;
        }

        let (jacobian, dfdt, evals) = problem.jacobian(t, &y, &f0);
        stats.jacobian_evals += 1;
        stats.rhs_evals += evals;

        let mut no_failures = true;
        let (t_new, mut step, err) = loop {
            attempts_left(&stats, s, t, abs_h, &y)?;
            let t_new = if done { tf } else { t + abs_h };
            // The matrix uses the step actually taken, t_new − t.
            let mut e = -jacobian;
            let diagonal = 1.0 / ((t_new - t) * tab.gamma);
            for i in 0..D {
                e[(i, i)] += diagonal;
            }
            stats.factorisations += 1;
            let attempted = if let Some(lu) = M::factor(e) {
                let span = Span {
                    t,
                    t_new,
                    y: &y,
                    f0: &f0,
                    dfdt: &dfdt,
                };
                let step = stepper.attempt(problem, &lu, span);
                stats.rhs_evals += S - 1;
                let (err, finite) = error_norm(&y, M::y_new(&step), M::estimate(&step), threshold);
                if !finite {
                    return Err(IntegrationError::NonFinite { t: t_new });
                }
                if err <= rtol {
                    break (t_new, step, err);
                }
                Some(err)
            } else {
                None
            };
            stats.rejected += 1;
            if abs_h <= hmin {
                return Err(IntegrationError::StepSizeTooSmall { t, h: abs_h });
            }
            // A singular iteration matrix (no error) halves the step.
            abs_h = after_rejection(abs_h, hmin, attempted, no_failures, rtol, exponent);
            no_failures = false;
            done = false;
        };
        stats.steps += 1;

        let h = t_new - t;
        while next < grid.len() && grid[next] <= t_new {
            let t_out = grid[next];
            if t_out == t_new {
                output(next, t_out, M::y_new(&step));
            } else {
                output(
                    next,
                    t_out,
                    &stepper.interpolate(&mut step, t, &y, h, t_out),
                );
            }
            next += 1;
        }
        if done {
            return Ok(stats);
        }

        if no_failures {
            abs_h = after_success(abs_h, err, rtol, exponent);
        }
        t = t_new;
        y = *M::y_new(&step);
        f0 = problem.rhs(t, &y);
        stats.rhs_evals += 1;
        if !f0.iter().all(|v| v.is_finite()) {
            return Err(IntegrationError::NonFinite { t });
        }
    }
}
