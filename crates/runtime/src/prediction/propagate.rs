//! The linear closed loop stepped exactly on the episode's output grid, and the sums the episode
//! forms there: z_{k+1} = e^{M h} z_k + ∫₀^h e^{M s} ds c, both from one matrix exponential of
//! the augmented matrix [[M, c], [0, 0]] (Van Loan's block form).

use nalgebra::{DMatrix, SMatrix, SVector};

use super::linear::LinearLoop;

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

/// Steps `z0` over `grid` with the steps of every interval (`steps`: the regular one, and the
/// last, shorter one where the horizon is not a whole number of output steps), input `which`
/// of each step, and forms the [`Sums`] of the observations under ΔT.
pub(crate) fn sums<const N: usize, const NX: usize, const NZ: usize>(
    linear: &LinearLoop<N, NX, NZ>,
    grid: &[f64],
    steps: (&Step<NZ>, &Step<NZ>),
    which: usize,
    z0: &SVector<f64, NZ>,
    perturbation: &SVector<f64, N>,
) -> Sums {
    let controller = &linear.controller;
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
        let observed = linear.observe(&z, perturbation);
        sums.task_error += controller.task_error(&observed);
        let j = controller.cost_j(&observed);
        let f = j - 0.5 * controller.logdet;
        if let Some((t_prev, f_prev, j_prev)) = previous {
            let h = t - t_prev;
            sums.free_energy += 0.5 * h * (f + f_prev);
            sums.cost_j += 0.5 * h * (j + j_prev);
        }
        previous = Some((t, f, j));
    }
    sums
}
