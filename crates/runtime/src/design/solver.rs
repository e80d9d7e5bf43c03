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
//! The KKT residual reported is, at the last QP, max(‖∇φ − Gᵀz‖∞, max_i z_i·slack_i) with z ≥ 0
//! the QP's multipliers: near zero at a constrained maximum.

use super::constraint::dot;
use super::polytope::Polytope;
use super::qp::{self, QpOutcome};

const MAX_ITERATIONS: usize = 200;
const STEP_TOLERANCE: f64 = 1e-10;
const ARMIJO: f64 = 1e-4;

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

/// The best local maximum over `starts` (ties: the earlier start), or None if φ is undefined at
/// every start.
pub fn maximise(
    polytope: &Polytope,
    starts: &[Vec<f64>],
    objective: &mut Objective,
) -> Option<Optimum> {
    let mut best: Option<Optimum> = None;
    for (k, x0) in starts.iter().enumerate() {
        if let Some(mut o) = climb(polytope, x0, objective) {
            o.start = k;
            if best.as_ref().map_or(true, |b| o.value > b.value) {
                best = Some(o);
            }
        }
    }
    best
}

/// The SQP from one feasible start.
pub fn climb(polytope: &Polytope, x0: &[f64], objective: &mut Objective) -> Option<Optimum> {
    let n = polytope.dim();
    let (g_rows, h) = polytope.all_rows();
    let (mut value, mut grad) = objective(x0)?;
    let mut x = x0.to_vec();
    let mut evaluations = 1;
    if n == 0 {
        return Some(Optimum {
            x,
            value,
            gradient: grad,
            iterations: 0,
            evaluations,
            kkt_residual: 0.0,
            start: 0,
        });
    }
    let width = (0..n)
        .map(|j| polytope.hi[j] - polytope.lo[j])
        .fold(0.0, f64::max)
        .max(1e-12);
    let mut b = identity(
        n,
        grad.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(1.0) / width,
    );
    let mut kkt = f64::INFINITY;
    let mut iterations = 0;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let slack: Vec<f64> = g_rows
            .iter()
            .zip(&h)
            .map(|(r, hi)| hi - dot(r, &x))
            .collect();
        let q: Vec<f64> = grad.iter().map(|v| -v).collect();
        let (d, z) = match qp::solve(
            Some(&b),
            &q,
            &g_rows,
            &slack.iter().map(|s| s.max(0.0)).collect::<Vec<_>>(),
        ) {
            QpOutcome::Solved { x: d, z } => (d, z),
            _ => break,
        };
        kkt = kkt_residual(&grad, &g_rows, &z, &slack);
        if d.iter().fold(0.0_f64, |m, v| m.max(v.abs())) <= STEP_TOLERANCE * width {
            break;
        }
        let slope = dot(&grad, &d);
        let mut alpha = 1.0;
        let mut accepted = None;
        while alpha > 1e-12 {
            let trial: Vec<f64> = x.iter().zip(&d).map(|(xi, di)| xi + alpha * di).collect();
            evaluations += 1;
            if let Some((v, g)) = objective(&trial) {
                if v >= value + ARMIJO * alpha * slope && v >= value {
                    accepted = Some((trial, v, g));
                    break;
                }
            }
            alpha *= 0.5;
        }
        let Some((trial, v, g)) = accepted else { break };
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
    // The QP's interior-point solution sits ~1e-14 inside an active bound: put it on the
    // bound, so a design at the box's corner reads 0.1, not 0.10000000000000249.
    let snapped: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(j, &v)| {
            let near = 1e-9 * width;
            if (v - polytope.lo[j]).abs() <= near {
                polytope.lo[j]
            } else if (v - polytope.hi[j]).abs() <= near {
                polytope.hi[j]
            } else {
                v
            }
        })
        .collect();
    if snapped != x && polytope.contains(&snapped) {
        if let Some((v, g)) = objective(&snapped) {
            evaluations += 1;
            if v >= value - 1e-9 * value.abs().max(1.0) {
                x = snapped;
                value = v;
                grad = g;
            }
        }
    }
    Some(Optimum {
        x,
        value,
        gradient: grad,
        iterations,
        evaluations,
        kkt_residual: kkt,
        start: 0,
    })
}

/// max(‖∇φ − Gᵀz‖∞, max_i |z_i·slack_i|): stationarity and complementarity of the maximum.
fn kkt_residual(grad: &[f64], g_rows: &[Vec<f64>], z: &[f64], slack: &[f64]) -> f64 {
    let n = grad.len();
    let mut stationarity = 0.0_f64;
    for j in 0..n {
        let r = grad[j]
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

fn identity(n: usize, scale: f64) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| (0..n).map(|j| if i == j { scale } else { 0.0 }).collect())
        .collect()
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
        };
        let mut f = |x: &[f64]| -> Option<(f64, Vec<f64>)> {
            Some((
                x.iter().map(|v| v.ln()).sum(),
                x.iter().map(|v| 1.0 / v).collect(),
            ))
        };
        let start = polytope.centre("test").unwrap();
        let o = maximise(&polytope, &[start], &mut f).unwrap();
        for (xi, wi) in o.x.iter().zip(w) {
            assert!((xi - 1.0 / (3.0 * wi)).abs() < 1e-7, "{:?}", o.x);
        }
        assert!(o.kkt_residual < 1e-6, "kkt {}", o.kkt_residual);
    }
}
