//! Maximising ln|Π^U| over the feasible set: a feasible-point SQP whose QP subproblems go to
//! Clarabel (src/design/qp.rs), from several starts.
//!
//! Each iteration solves  min_d ½ dᵀB d − ∇φᵀd  s.t.  G(x + d) ≤ h  (box included), with B a
//! damped-BFGS approximation of −∇²φ (Powell's damping keeps it positive definite even where φ
//! is convex, as ln|Π^U| often is), then backtracks along d until φ rises by Armijo's rule.
//! x and x + d are feasible and the set is convex, so every iterate stays feasible. It stops
//! when the step is below `STEP_TOLERANCE` of the box, or when no step along d improves φ.
//! Why not argmin: its solvers take no linear inequality constraints; projected gradient
//! would need a projection onto the polytope, which is this same QP.
//!
//! Scaling: the parameters may span many decades (bounds [1e-6, 1e6]), so every measure is
//! relative to the iterate x rather than to the box: B starts as diag(c/x_j²) (the curvature of
//! c·ln x_j, so that the first step moves each parameter by at most about its own size), the
//! step test is max_j |d_j|/x_j, and the KKT residual is in ln|Π^U| per relative change of a
//! parameter. From the box's centre, [1e-6, 1e6] then reaches the light, short corner instead
//! of stopping where ln|Π^U| is flat.
//!
//! The KKT residual reported is, at the last QP, max(max_j x_j·|∇φ_j − (Gᵀz)_j|,
//! max_i z_i·slack_i) with z ≥ 0 the QP's multipliers: near zero at a constrained maximum. Above
//! [`KKT_TOLERANCE`] the optimum is reported as not converged.
//!
//! A parameter whose box holds 0 (a centre of mass, a tip offset) can sit at or near 0, where a
//! scale of x_j would freeze it (d_j = σ_j x_j = 0) and make c/x_j² infinite: its scale is
//! max(|x_j|, 10⁻³ of its box's width) instead ([`scales`]). The others keep x_j.

use super::polytope::Polytope;
use super::qp::{self, QpOutcome};
use toolconf_model::inputs::design_file::constraint::dot;

const MAX_ITERATIONS: usize = 200;
const STEP_TOLERANCE: f64 = 1e-10;
const ARMIJO: f64 = 1e-4;
/// The largest relative step |d_j|/x_j of one QP (a trust region that binds only far from a
/// maximum, where the next step goes on).
const MAX_RELATIVE_STEP: f64 = 1e6;
/// The largest KKT residual of an optimum called converged: to first order no feasible change
/// of 1 % in the parameters raises ln|Π^U| by more than 1e-7. (The QP's multipliers are good to
/// about 1e-6 of the largest, so a tighter tolerance calls some optima unconverged; in a search
/// of 240 random design files the optima that had not converged were at 0.6 to 2.)
pub const KKT_TOLERANCE: f64 = 1e-5;

/// A QP that failed: the solver's words and the rows of [`Polytope::all_rows`] active when it
/// did ([`QpOutcome::Failed`]).
#[derive(Debug, Clone, PartialEq)]
pub struct QpFailure {
    pub reason: String,
    pub tight: Vec<usize>,
}

impl From<&str> for QpFailure {
    fn from(reason: &str) -> Self {
        Self {
            reason: reason.into(),
            tight: Vec::new(),
        }
    }
}

/// φ and ∇φ at free parameters x, or None where φ is undefined (Π^U not positive definite).
pub type Objective<'a> = dyn FnMut(&[f64]) -> Option<(f64, Vec<f64>)> + 'a;

/// A local maximum found from one start.
#[derive(Debug, Clone, PartialEq)]
pub struct Optimum {
    /// Free parameters.
    pub x: Vec<f64>,
    pub value: f64,
    pub gradient: Vec<f64>,
    pub iterations: usize,
    pub evaluations: usize,
    pub kkt_residual: f64,
    /// Which start it came from (0: the centre).
    pub start: usize,
}

impl Optimum {
    /// Whether the KKT residual is within [`KKT_TOLERANCE`].
    pub fn converged(&self) -> bool {
        self.kkt_residual <= KKT_TOLERANCE
    }
}

/// The best local maximum over `starts` (ties: the earlier start); `Ok(None)` if φ is undefined
/// at every start, `Err` with the QP solver's words if it failed from every start where φ is
/// defined.
pub fn maximise(
    polytope: &Polytope,
    starts: &[Vec<f64>],
    objective: &mut Objective,
) -> Result<Option<Optimum>, QpFailure> {
    match climb_all(polytope, starts, objective, false) {
        // Every start's climb failed: once more, with the QP solver's fallbacks.
        Err(_) => climb_all(polytope, starts, objective, true),
        found => found,
    }
}

/// [`maximise`] with the QPs solved by [`qp::solve`], or also its fallbacks (`robust`).
fn climb_all(
    polytope: &Polytope,
    starts: &[Vec<f64>],
    objective: &mut Objective,
    robust: bool,
) -> Result<Option<Optimum>, QpFailure> {
    let mut best: Option<Optimum> = None;
    let mut failure = None;
    for (k, x0) in starts.iter().enumerate() {
        match climb_with(polytope, x0, objective, robust) {
            Ok(Some(mut o)) => {
                o.start = k;
                if best.as_ref().map_or(true, |b| o.value > b.value) {
                    best = Some(o);
                }
            }
            Ok(None) => {}
            Err(reason) => failure = failure.or(Some(reason)),
        }
    }
    match (best, failure) {
        (None, Some(reason)) => Err(reason),
        (best, _) => Ok(best),
    }
}

/// The SQP from one feasible start: `Ok(None)` where φ is undefined at the start, `Err` with
/// the QP solver's words if its first QP fails (a later failure ends the climb where it is,
/// reported by the KKT residual of the last QP solved).
pub fn climb(
    polytope: &Polytope,
    x0: &[f64],
    objective: &mut Objective,
) -> Result<Option<Optimum>, QpFailure> {
    climb_with(polytope, x0, objective, false)
}

fn climb_with(
    polytope: &Polytope,
    x0: &[f64],
    objective: &mut Objective,
    robust: bool,
) -> Result<Option<Optimum>, QpFailure> {
    let n = polytope.dim();
    let (g_rows, h) = polytope.all_rows();
    let Some((mut value, mut grad)) = objective(x0) else {
        return Ok(None);
    };
    let mut x = x0.to_vec();
    let mut evaluations = 1;
    if n == 0 {
        return Ok(Some(optimum(x, value, grad, (0, evaluations), Some(0.0))));
    }
    let mut b = log_curvature(&scales(polytope, &x), &grad);
    let mut fresh = true;
    let mut kkt = None;
    let mut iterations = 0;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let scale = scales(polytope, &x);
        let step = match scaled_step(&b, &x, &scale, &grad, &g_rows, &h, robust) {
            Ok(step) => step,
            Err(reason) if kkt.is_none() => return Err(reason),
            // As for a failed line search below: restart B once, then stop.
            Err(_) if !fresh => {
                b = log_curvature(&scale, &grad);
                fresh = true;
                continue;
            }
            Err(_) => break,
        };
        kkt = Some(step.kkt_residual);
        if step.relative <= STEP_TOLERANCE {
            break;
        }
        let slope = dot(&grad, &step.d);
        let accepted = line_search(&x, &step.d, (value, slope), objective, &mut evaluations);
        let Some((trial, v, g, alpha)) = accepted else {
            // A BFGS matrix that no longer points uphill (it learnt the curvature of a region
            // left behind, decades away): restart it once from the local scale, then stop.
            if fresh {
                break;
            }
            b = log_curvature(&scale, &grad);
            fresh = true;
            continue;
        };
        fresh = false;
        let s: Vec<f64> = trial.iter().zip(&x).map(|(a, b)| a - b).collect();
        // −∇φ changes by y: the curvature pair of the minimised −φ.
        let y: Vec<f64> = grad.iter().zip(&g).map(|(old, new)| old - new).collect();
        damped_bfgs(&mut b, &s, &y);
        let improved = v - value;
        x = trial;
        value = v;
        grad = g;
        if improved <= 1e-15 * value.abs().max(1.0) && alpha < 1.0 {
            break;
        }
    }
    snap_to_bounds(
        polytope,
        objective,
        (&mut x, &mut value, &mut grad),
        &mut evaluations,
    );
    let kkt = final_kkt(kkt, polytope, (&x, &grad), (&g_rows, &h));
    Ok(Some(optimum(
        x,
        value,
        grad,
        (iterations, evaluations),
        kkt,
    )))
}

/// The KKT residual at the climb's end: the last QP's, or the active rows' own where smaller.
/// At a degenerate vertex (a box corner, every bound active) the QP's multipliers, an interior
/// point's, are good to only about 1e-5 of the largest; the active rows' give it exactly.
fn final_kkt(
    qp: Option<f64>,
    polytope: &Polytope,
    (x, grad): (&[f64], &[f64]),
    (g_rows, h): (&[Vec<f64>], &[f64]),
) -> Option<f64> {
    match (
        qp,
        active_set_residual(x, &scales(polytope, x), grad, g_rows, h),
    ) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// The climb's end from the first start: x, φ(x), ∇φ(x), (iterations, evaluations), and the
/// KKT residual (infinite where none could be formed).
fn optimum(
    x: Vec<f64>,
    value: f64,
    gradient: Vec<f64>,
    (iterations, evaluations): (usize, usize),
    kkt: Option<f64>,
) -> Optimum {
    Optimum {
        x,
        value,
        gradient,
        iterations,
        evaluations,
        kkt_residual: kkt.unwrap_or(f64::INFINITY),
        start: 0,
    }
}

/// Backtracking from α = 1 along d: the first trial point that rises by Armijo's rule (and not
/// below φ(x)), with φ, ∇φ there and its α, given (φ(x), ∇φ(x)·d); every objective call
/// counts in `evaluations`.
fn line_search(
    x: &[f64],
    d: &[f64],
    (value, slope): (f64, f64),
    objective: &mut Objective,
    evaluations: &mut usize,
) -> Option<(Vec<f64>, f64, Vec<f64>, f64)> {
    let mut alpha = 1.0;
    while alpha > 1e-12 {
        let trial: Vec<f64> = x.iter().zip(d).map(|(xi, di)| xi + alpha * di).collect();
        *evaluations += 1;
        if let Some((v, g)) = objective(&trial) {
            if v >= value + ARMIJO * alpha * slope && v >= value {
                return Some((trial, v, g, alpha));
            }
        }
        alpha *= 0.5;
    }
    None
}

/// The QP's interior-point solution sits ~1e-14 (relative) inside an active bound: put it on
/// the bound, so a design at the box's corner reads 0.1, not 0.10000000000000249, where φ there
/// is no worse (to 1e-9 relative). (x, φ(x), ∇φ(x)) are updated in place.
fn snap_to_bounds(
    polytope: &Polytope,
    objective: &mut Objective,
    (x, value, grad): (&mut Vec<f64>, &mut f64, &mut Vec<f64>),
    evaluations: &mut usize,
) {
    let snapped: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(j, &v)| {
            let (lo, hi) = (polytope.lo[j], polytope.hi[j]);
            if (v - lo).abs() <= 1e-9 * lo {
                lo
            } else if (v - hi).abs() <= 1e-9 * hi {
                hi
            } else {
                v
            }
        })
        .collect();
    if snapped == *x || !polytope.contains(&snapped) {
        return;
    }
    if let Some((v, g)) = objective(&snapped) {
        *evaluations += 1;
        if v >= *value - 1e-9 * value.abs().max(1.0) {
            *x = snapped;
            *value = v;
            *grad = g;
        }
    }
}

/// The KKT residual at x with the multipliers of the active rows (relative slack ≤ 1e-9)
/// solved for directly, least squares in the scaled space of [`scaled_step`]:
/// max(‖s∘∇φ − G̃_Aᵀz‖∞, max_i max(−z_i, 0), max_i z_i·s̃_i), s the [`scales`]. None without
/// active rows.
fn active_set_residual(
    x: &[f64],
    s: &[f64],
    grad: &[f64],
    g_rows: &[Vec<f64>],
    h: &[f64],
) -> Option<f64> {
    let n = x.len();
    let mut active: Vec<(Vec<f64>, f64)> = Vec::new();
    for (r, hi) in g_rows.iter().zip(h) {
        let row: Vec<f64> = r.iter().zip(s).map(|(a, sj)| a * sj).collect();
        let scale = row.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        if scale == 0.0 {
            continue;
        }
        let slack = ((hi - dot(r, x)) / scale).max(0.0);
        if slack <= 1e-9 {
            active.push((row.iter().map(|v| v / scale).collect(), slack));
        }
    }
    if active.is_empty() {
        return None;
    }
    let k = active.len();
    // Columns: the active rows; G̃_Aᵀ z = s∘∇φ.
    let at = nalgebra::DMatrix::from_fn(n, k, |j, i| active[i].0[j]);
    let target = nalgebra::DVector::from_fn(n, |j, _| s[j] * grad[j]);
    let z = at.clone().svd(true, true).solve(&target, 1e-12).ok()?;
    let stationarity = (&at * &z - &target).amax();
    let negative = z.iter().fold(0.0_f64, |m, zi| m.max(-zi));
    let complementarity = z
        .iter()
        .zip(&active)
        .fold(0.0_f64, |m, (zi, (_, s))| m.max((zi * s).abs()));
    Some(stationarity.max(negative).max(complementarity))
}

/// Each free parameter's scale at x: x_j, or for a parameter whose box holds 0,
/// max(|x_j|, 10⁻³ of the box's width), so that it can leave 0 (module doc, "Scaling").
fn scales(polytope: &Polytope, x: &[f64]) -> Vec<f64> {
    x.iter()
        .enumerate()
        .map(|(j, &v)| {
            let (lo, hi) = (polytope.lo[j], polytope.hi[j]);
            if lo <= 0.0 && hi >= 0.0 {
                v.abs().max(1e-3 * (hi - lo))
            } else {
                v
            }
        })
        .collect()
}

/// diag(c/s_j²), c = max_j |s_j ∂φ/∂x_j| (at least 1), s the [`scales`]: the curvature of
/// c·ln x_j, a first model of the BFGS matrix on the scale of each parameter.
fn log_curvature(x: &[f64], grad: &[f64]) -> Vec<Vec<f64>> {
    let c = x
        .iter()
        .zip(grad)
        .fold(0.0_f64, |m, (xj, gj)| m.max((xj * gj).abs()))
        .max(1.0);
    let n = x.len();
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| if i == j { c / (x[i] * x[i]) } else { 0.0 })
                .collect()
        })
        .collect()
}

/// One SQP step d from x, and the KKT residual of the QP that gave it.
struct Step {
    d: Vec<f64>,
    /// max_j |d_j| / x_j.
    relative: f64,
    kkt_residual: f64,
}

/// The QP  min ½ dᵀB d − ∇φᵀd  s.t.  G(x + d) ≤ h, solved in the relative step σ = d/s
/// (d = Dσ, D = diag(s), s the [`scales`]) with every row scaled to a largest coefficient of 1
/// and |σ| at most [`MAX_RELATIVE_STEP`]: the same step, but data Clarabel sees on one scale however many
/// decades the parameters span. The multipliers z̃ of the scaled rows then give the residual of
/// [`kkt_residual`] directly.
#[allow(clippy::too_many_arguments)]
fn scaled_step(
    b: &[Vec<f64>],
    x: &[f64],
    s: &[f64],
    grad: &[f64],
    g_rows: &[Vec<f64>],
    h: &[f64],
    robust: bool,
) -> Result<Step, QpFailure> {
    let n = x.len();
    let scaled_b: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| s[i] * b[i][j] * s[j]).collect())
        .collect();
    let q: Vec<f64> = (0..n).map(|j| -s[j] * grad[j]).collect();
    let mut rows = Vec::with_capacity(g_rows.len());
    let mut rhs = Vec::with_capacity(g_rows.len());
    for (r, hi) in g_rows.iter().zip(h) {
        let row: Vec<f64> = r.iter().zip(s).map(|(a, sj)| a * sj).collect();
        let scale = row.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let scale = if scale > 0.0 { scale } else { 1.0 };
        rows.push(row.iter().map(|v| v / scale).collect::<Vec<f64>>());
        // A row this far away cannot bind a step of at most MAX_RELATIVE_STEP, and its slack
        // of up to 1e12 (x = 1e-6 under hi = 1e6) would set the solver's scale.
        rhs.push(((hi - dot(r, x)) / scale).clamp(0.0, MAX_RELATIVE_STEP));
    }
    let solve = if robust {
        qp::solve_robustly
    } else {
        qp::solve
    };
    let (sigma, z) = match solve(Some(&scaled_b), &q, &rows, &rhs) {
        QpOutcome::Solved { x: sigma, z } => (sigma, z),
        QpOutcome::Infeasible => return Err("the QP is infeasible".into()),
        QpOutcome::Failed { reason, tight } => return Err(QpFailure { reason, tight }),
    };
    Ok(Step {
        d: sigma.iter().zip(s).map(|(sigma, sj)| sigma * sj).collect(),
        relative: sigma.iter().fold(0.0_f64, |m, s| m.max(s.abs())),
        kkt_residual: kkt_residual(&q, &rows, &z, &rhs),
    })
}

/// max(max_j |x_j ∂φ/∂x_j − (G̃ᵀz̃)_j|, max_i |z̃_i·s̃_i|) for the rows G̃ and slacks s̃ of the
/// scaled QP (`q` = −D∇φ): stationarity per relative change of each parameter, and
/// complementarity, of the maximum.
fn kkt_residual(q: &[f64], g_rows: &[Vec<f64>], z: &[f64], slack: &[f64]) -> f64 {
    let n = q.len();
    let mut stationarity = 0.0_f64;
    for j in 0..n {
        let r = -q[j]
            - g_rows
                .iter()
                .zip(z)
                .map(|(row, zi)| row[j] * zi)
                .sum::<f64>();
        stationarity = stationarity.max(r.abs());
    }
    let complementarity = z
        .iter()
        .zip(slack)
        .map(|(zi, s)| (zi * s).abs())
        .fold(0.0, f64::max);
    stationarity.max(complementarity)
}

/// Powell's damped BFGS update of B with step s and gradient change y (of the minimised
/// function): B stays symmetric positive definite whatever the curvature.
fn damped_bfgs(b: &mut [Vec<f64>], s: &[f64], y: &[f64]) {
    let n = s.len();
    let bs: Vec<f64> = (0..n).map(|i| dot(&b[i], s)).collect();
    let sbs = dot(s, &bs);
    if sbs <= 1e-300 {
        return;
    }
    let sy = dot(s, y);
    let theta = if sy >= 0.2 * sbs {
        1.0
    } else {
        0.8 * sbs / (sbs - sy)
    };
    let r: Vec<f64> = (0..n)
        .map(|i| theta * y[i] + (1.0 - theta) * bs[i])
        .collect();
    let sr = dot(s, &r);
    if sr <= 1e-300 {
        return;
    }
    for i in 0..n {
        for j in 0..n {
            b[i][j] += r[i] * r[j] / sr - bs[i] * bs[j] / sbs;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// max Σ ln x_i  s.t.  Σ w_i x_i ≤ 1, x in [0.01, 10]: the optimum is x_i = 1/(n w_i)
    /// (Lagrange: 1/x_i = λ w_i, and the constraint binds with λ = n).
    #[test]
    fn weighted_log_sum_has_its_closed_form_optimum() {
        let w = [1.0, 2.0, 4.0];
        let polytope = Polytope {
            free: vec![0, 1, 2],
            base: vec![0.0; 3],
            lo: vec![0.01; 3],
            hi: vec![10.0; 3],
            g: vec![w.to_vec()],
            h: vec![1.0],
            text: vec!["x + 2y + 4z <= 1".into()],
            names: vec!["x", "y", "z"],
        };
        let mut f = |x: &[f64]| -> Option<(f64, Vec<f64>)> {
            Some((
                x.iter().map(|v| v.ln()).sum(),
                x.iter().map(|v| 1.0 / v).collect(),
            ))
        };
        let start = polytope.centre("test").unwrap();
        let o = maximise(&polytope, &[start], &mut f).unwrap().unwrap();
        for (xi, wi) in o.x.iter().zip(w) {
            assert!((xi - 1.0 / (3.0 * wi)).abs() < 1e-7, "{:?}", o.x);
        }
        assert!(o.kkt_residual < 1e-6, "kkt {}", o.kkt_residual);
    }
}
