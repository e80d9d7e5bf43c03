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
    /// Anything else, in Clarabel's words.
    Failed(String),
}

/// Minimises ½ xᵀHx + qᵀx subject to G x ≤ h; `hessian` is n×n symmetric (None: an LP).
pub fn solve(hessian: Option<&[Vec<f64>]>, q: &[f64], g: &[Vec<f64>], h: &[f64]) -> QpOutcome {
    let n = q.len();
    let mut p = (Vec::new(), Vec::new(), Vec::new());
    if let Some(hm) = hessian {
        for (i, row) in hm.iter().enumerate() {
            for (j, &v) in row.iter().enumerate().skip(i) {
                if v != 0.0 {
                    p.0.push(i);
                    p.1.push(j);
                    p.2.push(v);
                }
            }
        }
    }
    let p = CscMatrix::new_from_triplets(n, n, p.0, p.1, p.2);
    let mut a = (Vec::new(), Vec::new(), Vec::new());
    for (i, row) in g.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            if v != 0.0 {
                a.0.push(i);
                a.1.push(j);
                a.2.push(v);
            }
        }
    }
    let a = CscMatrix::new_from_triplets(g.len(), n, a.0, a.1, a.2);
    let cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(h.len())];
    // Tight tolerances first; a QP whose optimum is a degenerate vertex (every bound of a box
    // corner active, with zero slack) can stall there ("InsufficientProgress", or
    // "AlmostSolved": only to Clarabel's reduced accuracy, 5e-5), and Clarabel's own defaults
    // (1e-8) then solve it. An almost-solved QP is the answer only if neither solves it.
    let mut outcome = QpOutcome::Failed(String::new());
    let mut almost = None;
    for tolerance in [1e-11, 1e-8] {
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(tolerance)
            .tol_gap_rel(tolerance)
            .tol_feas(tolerance)
            .build()
            .expect("valid Clarabel settings");
        let mut solver = match DefaultSolver::new(&p, q, &a, h, &cones, settings) {
            Ok(s) => s,
            Err(e) => return QpOutcome::Failed(format!("Clarabel setup: {e}")),
        };
        solver.solve();
        let s = &solver.solution;
        let solved = || QpOutcome::Solved {
            x: s.x.clone(),
            z: s.z.clone(),
        };
        match s.status {
            SolverStatus::Solved => return solved(),
            SolverStatus::AlmostSolved => almost = almost.or_else(|| Some(solved())),
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                return QpOutcome::Infeasible
            }
            other => outcome = QpOutcome::Failed(format!("Clarabel: {other:?}")),
        }
    }
    almost.unwrap_or(outcome)
}
