//! Small dense QPs and LPs for the design search, solved by Clarabel (already the MPC's QP
//! solver, src/mpc/qp.rs): minimise ½ xᵀHx + qᵀx subject to G x ≤ h. The design problems have
//! a handful of variables and constraints, so the matrices are built dense and converted.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};

/// The outcome of one solve.
#[derive(Debug, Clone, PartialEq)]
pub enum QpOutcome {
    /// The minimiser and the multipliers z ≥ 0 of G x ≤ h (H x + q + Gᵀ z = 0 at the optimum).
    Solved { x: Vec<f64>, z: Vec<f64> },
    /// No x satisfies G x ≤ h.
    Infeasible,
    /// Every attempt failed: Clarabel's words, and the rows of G x ≤ h that were active (or
    /// violated) at its last iterate, the constraints to look at.
    Failed { reason: String, tight: Vec<usize> },
}

/// How one attempt differs from Clarabel's defaults.
#[derive(Debug, Clone, Copy)]
struct Attempt {
    /// What the failure message calls it.
    name: &'static str,
    tolerance: f64,
    max_iter: u32,
    /// Clarabel's remedies for a KKT system that loses accuracy (its settings'
    /// `static_regularization_constant`, `iterative_refinement_*`, `equilibrate_*`,
    /// `max_iter`, `direct_solve_method`).
    robust: bool,
    /// The problem rescaled first ([`Scaled`]).
    rescale: bool,
}

/// Tight tolerances first; a QP whose optimum is a degenerate vertex (every bound of a box
/// corner active, with zero slack) can stall there ("InsufficientProgress", or "AlmostSolved":
/// only to Clarabel's reduced accuracy, 5e-5), and Clarabel's own defaults (1e-8) then solve it.
/// A NumericalError (the KKT factorisation lost its accuracy) gets the robust settings, then
/// those on the rescaled problem. An almost-solved QP is the answer only if none solves it.
const ATTEMPTS: [Attempt; 4] = [
    Attempt {
        name: "tight tolerances",
        tolerance: 1e-11,
        max_iter: 200,
        robust: false,
        rescale: false,
    },
    Attempt {
        name: "Clarabel's defaults",
        tolerance: 1e-8,
        max_iter: 200,
        robust: false,
        rescale: false,
    },
    Attempt {
        name: "regularised",
        tolerance: 1e-8,
        max_iter: 1000,
        robust: true,
        rescale: false,
    },
    Attempt {
        name: "rescaled",
        tolerance: 1e-8,
        max_iter: 1000,
        robust: true,
        rescale: true,
    },
];

/// Minimises ½ xᵀHx + qᵀx subject to G x ≤ h; `hessian` is n×n symmetric (None: an LP).
/// With tight tolerances, then Clarabel's defaults.
pub fn solve(hessian: Option<&[Vec<f64>]>, q: &[f64], g: &[Vec<f64>], h: &[f64]) -> QpOutcome {
    solve_with(&ATTEMPTS[..2], hessian, q, g, h)
}

/// [`solve`], then the robust attempts (regularised, then rescaled) before it fails: for a QP
/// whose failure would end the run. (Not for every QP of the search: a climb that a failed QP
/// stops is ended by the best of the other starts, as it always was, and the designs that
/// solved stay the same.)
pub fn solve_robustly(
    hessian: Option<&[Vec<f64>]>,
    q: &[f64],
    g: &[Vec<f64>],
    h: &[f64],
) -> QpOutcome {
    solve_with(&ATTEMPTS, hessian, q, g, h)
}

fn solve_with(
    attempts: &[Attempt],
    hessian: Option<&[Vec<f64>]>,
    q: &[f64],
    g: &[Vec<f64>],
    h: &[f64],
) -> QpOutcome {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let hessian_finite = hessian.map_or(true, |hm| hm.iter().all(|r| finite(r)));
    if !(finite(q) && finite(h) && g.iter().all(|r| finite(r)) && hessian_finite) {
        let tight = (0..h.len())
            .filter(|&i| !(finite(&g[i]) && h[i].is_finite()))
            .collect();
        return QpOutcome::Failed {
            reason: "the QP's data is not finite".into(),
            tight,
        };
    }
    let mut almost = None;
    let mut failures: Vec<String> = Vec::new();
    let mut last_x = None;
    for attempt in attempts {
        if attempt.robust && almost.is_some() {
            break;
        }
        let scaled = Scaled::new(hessian, q, g, h, attempt.rescale);
        match scaled.solve(attempt) {
            Ok((SolverStatus::Solved, x, z)) => return QpOutcome::Solved { x, z },
            Ok((SolverStatus::AlmostSolved, x, z)) => {
                almost = almost.or(Some(QpOutcome::Solved { x, z }))
            }
            Ok((SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible, ..)) => {
                return QpOutcome::Infeasible
            }
            Ok((status, x, _)) => {
                failures.push(format!("{status:?}"));
                last_x = Some(x);
            }
            Err(e) => failures.push(e),
        }
    }
    if let Some(solved) = almost {
        return solved;
    }
    failures.dedup();
    QpOutcome::Failed {
        reason: format!(
            "Clarabel: {} after {} attempts ({})",
            failures.join(", then "),
            attempts.len(),
            attempts
                .iter()
                .map(|a| a.name)
                .collect::<Vec<_>>()
                .join(", ")
        ),
        tight: last_x.map_or_else(Vec::new, |x| tight_rows(g, h, &x)),
    }
}

/// The rows active or violated at `x` (slack within 1e-6 of the row's scale), none for a
/// non-finite `x`.
fn tight_rows(g: &[Vec<f64>], h: &[f64], x: &[f64]) -> Vec<usize> {
    if !x.iter().all(|v| v.is_finite()) {
        return Vec::new();
    }
    (0..h.len())
        .filter(|&i| {
            let gx: f64 = g[i].iter().zip(x).map(|(a, b)| a * b).sum();
            let scale = g[i].iter().fold(h[i].abs(), |m, a| m.max(a.abs())).max(1.0);
            gx >= h[i] - 1e-6 * scale
        })
        .collect()
}

/// The QP in y = x ./ d with every row divided by r: H̃ = DHD, q̃ = Dq, G̃ = R⁻¹GD, h̃ = R⁻¹h.
/// d_j = 1/√H_jj (1 for an LP or H_jj = 0) puts H's diagonal on 1, r_i the largest |G̃_ij|,
/// so Clarabel's equilibration starts from data on one scale. Without rescaling d = r = 1.
struct Scaled {
    n: usize,
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b: Vec<f64>,
    d: Vec<f64>,
    r: Vec<f64>,
}

impl Scaled {
    fn new(
        hessian: Option<&[Vec<f64>]>,
        q: &[f64],
        g: &[Vec<f64>],
        h: &[f64],
        rescale: bool,
    ) -> Self {
        let n = q.len();
        let diagonal = |j: usize| hessian.map_or(0.0, |hm| hm[j][j]);
        let d: Vec<f64> = (0..n)
            .map(|j| match diagonal(j) {
                v if rescale && v > 0.0 => 1.0 / v.sqrt(),
                _ => 1.0,
            })
            .collect();
        let r: Vec<f64> = g
            .iter()
            .map(|row| {
                let m = row
                    .iter()
                    .zip(&d)
                    .fold(0.0_f64, |m, (a, dj)| m.max((a * dj).abs()));
                if rescale && m > 0.0 {
                    m
                } else {
                    1.0
                }
            })
            .collect();
        let mut p = (Vec::new(), Vec::new(), Vec::new());
        if let Some(hm) = hessian {
            for (i, row) in hm.iter().enumerate() {
                for (j, &v) in row.iter().enumerate().skip(i) {
                    if v != 0.0 {
                        p.0.push(i);
                        p.1.push(j);
                        p.2.push(d[i] * v * d[j]);
                    }
                }
            }
        }
        let mut a = (Vec::new(), Vec::new(), Vec::new());
        for (i, row) in g.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    a.0.push(i);
                    a.1.push(j);
                    a.2.push(v * d[j] / r[i]);
                }
            }
        }
        Self {
            n,
            p: CscMatrix::new_from_triplets(n, n, p.0, p.1, p.2),
            q: q.iter().zip(&d).map(|(v, dj)| v * dj).collect(),
            a: CscMatrix::new_from_triplets(g.len(), n, a.0, a.1, a.2),
            b: h.iter().zip(&r).map(|(v, ri)| v / ri).collect(),
            d,
            r,
        }
    }

    /// Clarabel's status and (x, z) of the original problem.
    fn solve(&self, attempt: &Attempt) -> Result<(SolverStatus, Vec<f64>, Vec<f64>), String> {
        let mut builder = DefaultSettingsBuilder::default();
        builder
            .verbose(false)
            .tol_gap_abs(attempt.tolerance)
            .tol_gap_rel(attempt.tolerance)
            .tol_feas(attempt.tolerance)
            .max_iter(attempt.max_iter);
        if attempt.robust {
            builder
                .static_regularization_constant(1e-7)
                .iterative_refinement_max_iter(50)
                .iterative_refinement_reltol(1e-14)
                .equilibrate_max_iter(50)
                .equilibrate_min_scaling(1e-6)
                .equilibrate_max_scaling(1e6)
                .direct_solve_method("qdldl".to_string());
        }
        let settings = builder.build().expect("valid Clarabel settings");
        let cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(self.b.len())];
        let mut solver = DefaultSolver::new(&self.p, &self.q, &self.a, &self.b, &cones, settings)
            .map_err(|e| format!("setup: {e}"))?;
        solver.solve();
        let s = &solver.solution;
        let x = (0..self.n).map(|j| s.x[j] * self.d[j]).collect();
        let z = s.z.iter().zip(&self.r).map(|(zi, ri)| zi / ri).collect();
        Ok((s.status, x, z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// min ½(x² + 100y²) − 2x − 200y s.t. x + y ≤ 1, x, y ≥ 0: the minimiser (0, 1) with
    /// multipliers (100, 98, 0) (stationarity: x − 2 + z₀ − z₁ = 0, 100y − 200 + z₀ − z₂ = 0),
    /// the same from every attempt, rescaled or not.
    #[test]
    fn every_attempt_gives_the_same_answer() {
        let hessian = vec![vec![1.0, 0.0], vec![0.0, 100.0]];
        let (q, g, h) = (
            vec![-2.0, -200.0],
            vec![vec![1.0, 1.0], vec![-1.0, 0.0], vec![0.0, -1.0]],
            vec![1.0, 0.0, 0.0],
        );
        for attempt in ATTEMPTS {
            match solve_with(&[attempt], Some(&hessian), &q, &g, &h) {
                QpOutcome::Solved { x, z } => {
                    assert!(
                        x[0].abs() < 1e-6 && (x[1] - 1.0).abs() < 1e-6,
                        "{attempt:?}: {x:?}"
                    );
                    let want = [100.0, 98.0, 0.0];
                    assert!(
                        z.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-4),
                        "{attempt:?}: {z:?}"
                    );
                }
                other => panic!("{attempt:?}: {other:?}"),
            }
        }
    }

    /// The fallbacks run in turn: a QP whose first attempts are cut short (one iteration) is
    /// solved by the last; when every attempt is cut short, the failure lists what each said
    /// and the rows active at the last iterate.
    #[test]
    fn the_fallbacks_run_and_a_failure_names_the_tight_rows() {
        let hessian = vec![vec![1.0]];
        let (g, h) = (vec![vec![1.0], vec![-1.0]], vec![1.0, 0.0]);
        let short = |a: Attempt| Attempt { max_iter: 1, ..a };
        let ladder = [short(ATTEMPTS[0]), short(ATTEMPTS[2]), ATTEMPTS[3]];
        match solve_with(&ladder, Some(&hessian), &[-5.0], &g, &h) {
            QpOutcome::Solved { x, .. } => assert!((x[0] - 1.0).abs() < 1e-6, "{x:?}"),
            other => panic!("{other:?}"),
        }
        let all_short = ATTEMPTS.map(short);
        match solve_with(&all_short, Some(&hessian), &[-5.0], &g, &h) {
            QpOutcome::Failed { reason, .. } => {
                assert_eq!(
                    reason,
                    "Clarabel: MaxIterations after 4 attempts (tight tolerances, Clarabel's \
                     defaults, regularised, rescaled)"
                );
            }
            other => panic!("{other:?}"),
        }
        match solve_with(&ATTEMPTS, None, &[f64::NAN], &g, &h) {
            QpOutcome::Failed { reason, tight } => {
                assert_eq!(reason, "the QP's data is not finite");
                assert!(tight.is_empty());
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(tight_rows(&g, &h, &[1.0]), vec![0]);
        assert_eq!(tight_rows(&g, &h, &[-0.5]), vec![1]);
        assert!(tight_rows(&g, &h, &[0.5]).is_empty());
        assert!(tight_rows(&g, &h, &[f64::NAN]).is_empty());
    }
}
