//! The linear closed loop stepped exactly on the episode's output grid, and the sums the episode
//! forms there: z_{k+1} = e^{M h} z_k + ∫₀^h e^{M s} ds c, both from one matrix exponential of
//! the augmented matrix [[M, c], [0, 0]] (Van Loan's block form).

use nalgebra::{DMatrix, SMatrix, SVector};

use super::linear::LinearLoop;
use toolconf_generated::Term;

/// The step over `h` of the affine systems ż = M z + c_j, one per column c_j of `inputs`: the
/// transition e^{M h} and, per input, the response ∫₀^h e^{M s} ds c_j.
pub(crate) struct Step<const NZ: usize> {
    pub transition: SMatrix<f64, NZ, NZ>,
    pub responses: Vec<SVector<f64, NZ>>,
}

impl<const NZ: usize> Step<NZ> {
    /// exp(h [[M, C], [0, 0]]) = [[e^{Mh}, ∫₀^h e^{Ms} ds C], [0, I]].
    pub fn new(m: &SMatrix<f64, NZ, NZ>, inputs: &[SVector<f64, NZ>], h: f64) -> Self {
        let n = NZ + inputs.len();
        let mut augmented = DMatrix::<f64>::zeros(n, n);
        augmented.view_mut((0, 0), (NZ, NZ)).copy_from(&(m * h));
        for (j, c) in inputs.iter().enumerate() {
            augmented.view_mut((0, NZ + j), (NZ, 1)).copy_from(&(c * h));
        }
        let e = augmented.exp();
        Self {
            transition: SMatrix::from_fn(|i, j| e[(i, j)]),
            responses: (0..inputs.len())
                .map(|j| SVector::from_fn(|i, _| e[(i, NZ + j)]))
                .collect(),
        }
    }
}

/// The episode's sums along one predicted trajectory: Σ over the grid of the task's weighted
/// error, and ∫J dt, ∫F dt by the trapezoidal rule, as [`crate::model::simulate`] forms them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Sums {
    pub task_error: f64,
    pub cost_j: f64,
    pub free_energy: f64,
}

/// One term the sums read: its linearisation, its constant part under ΔT less its goal, its
/// precision, and whether it is the task's error term and part of J.
struct Read<'a, const N: usize, const NZ: usize> {
    c: &'a SMatrix<f64, N, NZ>,
    d: SVector<f64, N>,
    p: SMatrix<f64, N, N>,
    error: bool,
    cost: bool,
}

/// The terms the task's error and J read (the others add nothing), under ΔT.
fn reads<'a, const N: usize, const NX: usize, const NZ: usize>(
    linear: &'a LinearLoop<N, NX, NZ>,
    perturbation: &SVector<f64, N>,
) -> Vec<Read<'a, N, NZ>> {
    let task = &linear.controller.task;
    let error_term = task.kind.error_term();
    Term::COST_ORDER
        .iter()
        .filter(|&&term| term == error_term || task.kind.uses(term))
        .map(|&term| {
            let t = &linear.terms[term.index()];
            Read {
                c: &t.c,
                d: t.offset + t.gain_dt * perturbation - task.goal(term),
                p: *task.precision(term),
                error: term == error_term,
                cost: task.kind.uses(term),
            }
        })
        .collect()
}

/// Steps `z0` over `grid` with the steps of every interval (`steps`: the regular one, and the
/// last, shorter one where the horizon is not a whole number of output steps), input `which`
/// of each step, and forms the [`Sums`] of the observations under ΔT: at each point the task's
/// weighted error (e − e^g)ᵀP(e − e^g) and J = ½ Σ (e − e^g)ᵀP(e − e^g) over the task's terms,
/// as the controller forms them ([`crate::model::ActiveInferenceN::cost_j`]).
pub(crate) fn sums<const N: usize, const NX: usize, const NZ: usize>(
    linear: &LinearLoop<N, NX, NZ>,
    grid: &[f64],
    steps: (&Step<NZ>, &Step<NZ>),
    which: usize,
    z0: &SVector<f64, NZ>,
    perturbation: &SVector<f64, N>,
) -> Sums {
    let half_logdet = 0.5 * linear.controller.logdet;
    let reads = reads(linear, perturbation);
    let mut sums = Sums::default();
    let mut z = *z0;
    // (t, F, J) at the previous grid point, for the trapezoidal rule.
    let mut previous: Option<(f64, f64, f64)> = None;
    for (k, &t) in grid.iter().enumerate() {
        if k > 0 {
            let step = if k + 1 == grid.len() {
                steps.1
            } else {
                steps.0
            };
            z = step.transition * z + step.responses[which];
        }
        let mut j = 0.0;
        for r in &reads {
            let e = r.c * z + r.d;
            let v = e.dot(&(r.p * e));
            if r.error {
                sums.task_error += v;
            }
            if r.cost {
                j += v;
            }
        }
        let j = 0.5 * j;
        let f = j - half_logdet;
        if let Some((t_prev, f_prev, j_prev)) = previous {
            let h = t - t_prev;
            sums.free_energy += 0.5 * h * (f + f_prev);
            sums.cost_j += 0.5 * h * (j + j_prev);
        }
        previous = Some((t, f, j));
    }
    sums
}
