//! The linear system a prediction steps, with run-time sizes, for an independent computation
//! (SciPy's `expm` in the Python tests) and for users who want to study it.

use nalgebra::{SMatrix, SVector};
use serde::Serialize;

use super::LinearLoop;
use crate::model::{EpisodeOptionsN, TaskN};
use toolconf_generated::Term;

/// One term of the cost: term ≈ `offset` + `c` z (ΔT included in `offset`), its goal and
/// precision, and whether the task's J uses it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExportedTerm {
    pub name: &'static str,
    pub c: Vec<Vec<f64>>,
    pub offset: Vec<f64>,
    pub goal: Vec<f64>,
    pub precision: Vec<Vec<f64>>,
    pub in_cost: bool,
}

/// ż = M z + c on the grid 0, dt, …, t_end from z0, the terms, the task's error term and
/// ln|Π^U|: everything the prediction's sums need.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearSystem {
    pub m: Vec<Vec<f64>>,
    pub c: Vec<f64>,
    pub z0: Vec<f64>,
    pub t_end: f64,
    pub dt: f64,
    pub terms: Vec<ExportedTerm>,
    pub error_term: &'static str,
    pub logdet: f64,
}

fn rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Vec<Vec<f64>> {
    (0..R)
        .map(|i| (0..C).map(|j| m[(i, j)]).collect())
        .collect()
}

impl LinearSystem {
    /// The system of `linear` for the episode `options` of `task`.
    pub fn new<const N: usize, const NX: usize, const NZ: usize>(
        linear: &LinearLoop<N, NX, NZ>,
        task: &TaskN<N>,
        options: &EpisodeOptionsN<N, NX>,
    ) -> Self {
        let dt = options.total_perturbation();
        let mut z0 = SVector::<f64, NZ>::zeros();
        z0.fixed_rows_mut::<NX>(0)
            .copy_from(&(options.x0 - linear.x_e));
        z0.fixed_rows_mut::<N>(NX).copy_from(&options.u0);
        let terms = Term::ALL
            .iter()
            .map(|&term| {
                let t = &linear.terms[term.index()];
                ExportedTerm {
                    name: term.name(),
                    c: rows(&t.c),
                    offset: (t.offset + t.gain_dt * dt).iter().copied().collect(),
                    goal: task.goal(term).iter().copied().collect(),
                    precision: rows(task.precision(term)),
                    in_cost: task.kind.uses(term),
                }
            })
            .collect();
        Self {
            m: rows(&linear.m),
            c: linear.input(&dt).iter().copied().collect(),
            z0: z0.iter().copied().collect(),
            t_end: options.t_end,
            dt: options.dt,
            terms,
            error_term: task.kind.error_term().name(),
            logdet: linear.controller.logdet,
        }
    }
}
