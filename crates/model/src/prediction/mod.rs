//! The predicted cost of an episode: the closed loop linearised at the equilibrium X^e, in
//! closed form, with no integration of the nonlinear episode.
//!
//! The plant linearised at X^e (the A, B of Π^U), the controller's own law
//! U̇ = −γ Σ_i K_i (term_i − goal_i) with K_i = S_iᵀ P_i, and the observed terms linearised at
//! X^e make the closed loop affine in z = [X − X^e; U] ([`LinearLoop`]):
//!
//! ```text
//! ż = M z + c(ΔT),    term_i ≈ o_i(ΔT) + C_i z
//! ```
//!
//! Stepped exactly on the episode's output grid, z_{k+1} = e^{M h} z_k + ∫₀^h e^{M s} ds c
//! (one matrix exponential of [[M, c], [0, 0]], Van Loan's block form), from the episode's
//! z_0 = [X0 − X^e; U0], the predicted task error is the same sum the episode forms,
//! Σ_k (e_k − e^g)ᵀ P (e_k − e^g) over the grid, and ∫J dt, ∫F dt = ∫(J − ½ ln|Π^U|) dt the
//! same trapezoidal sums ([`crate::model::simulate`]). Goals are the episode's, a relative tip
//! goal resolved at the tool's own initial tip as the episode resolves it.
//!
//! The prediction is refused ([`PredictionError`]) where it means nothing: a horizon of 0, or
//! an unstable linearised loop (an eigenvalue of M with a positive real part), whose
//! linearisation the episode leaves at once.

pub mod derivative;
mod export;
mod linear;
mod propagate;
#[cfg(test)]
mod tests;

use nalgebra::{DMatrix, SVector};

use crate::model::{ArmModel, EpisodeOptionsN, TaskN, ToolN};
use crate::Error;
use toolconf_integrators::uniform_grid;

pub use export::{ExportedTerm, LinearSystem};
pub use linear::{LinearLoop, LinearTerm};
use propagate::{sums, Step};

/// An eigenvalue of M whose real part passes this many times max(1, |M|) is unstable: rounding
/// in the eigenvalues of a loop with a marginal mode (a joint nothing steers) stays below it.
const INSTABILITY_TOLERANCE: f64 = 1e-9;

/// The predicted cost of one episode ([`predict`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// Σ over the output grid of (e − e^g)ᵀ P (e − e^g) on the task's error term.
    pub task_error: f64,
    /// ∫F dt, F = J − ½ ln|Π^U| (eq. free_energy), trapezoidal on the grid.
    pub free_energy: f64,
    /// ∫J dt, trapezoidal on the grid.
    pub cost_j: f64,
    /// The task error under the episode's ΔT less the task error without it: what the
    /// perturbation costs the task (0 when ΔT = 0).
    pub perturbation_effect: f64,
    /// max Re λ(M) (1/s): how fast the slowest mode of the linearised loop settles.
    pub abscissa: f64,
}

/// Why there is no prediction.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PredictionError {
    #[error(transparent)]
    Input(#[from] Error),
    #[error("no prediction over a horizon of 0: t_end = {t_end} s")]
    ZeroHorizon { t_end: f64 },
    #[error("no prediction: the closed loop linearised at the equilibrium is unstable (an eigenvalue of M has real part {abscissa:.6e} 1/s > 0)")]
    Unstable { abscissa: f64 },
    #[error("no prediction: the eigenvalues of the linearised closed loop did not converge")]
    NoEigenvalues,
    #[error("no prediction: the predicted {what} is not finite")]
    NotFinite { what: &'static str },
}

impl PredictionError {
    /// The reason in a few words, for a JSON `null`'s `reason` and a table's note.
    pub fn reason(&self) -> String {
        self.to_string()
            .trim_start_matches("no prediction: ")
            .to_string()
    }
}

/// The predicted cost of the episode of `tool` on `task` (goals resolved) with `options`: see
/// the module's documentation.
pub fn predict<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<Prediction, PredictionError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let linear = linearise(tool, task, options)?;
    let abscissa = spectral_abscissa(&linear)?;
    predict_linear(&linear, options, abscissa)
}

/// The linearised loop of the episode, its options checked as the episode checks them.
pub fn linearise<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
) -> Result<LinearLoop<N, NX, NZ>, PredictionError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    if !(options.t_end > 0.0) {
        return Err(PredictionError::ZeroHorizon {
            t_end: options.t_end,
        });
    }
    crate::model::check_episode_options(options)?;
    Ok(LinearLoop::<N, NX, NZ>::new(
        tool,
        task,
        options.learning_rate,
    )?)
}

/// max Re λ(M), or [`PredictionError::Unstable`].
fn spectral_abscissa<const N: usize, const NX: usize, const NZ: usize>(
    linear: &LinearLoop<N, NX, NZ>,
) -> Result<f64, PredictionError> {
    let m = DMatrix::from_column_slice(NZ, NZ, linear.m.as_slice());
    if !m.iter().all(|v| v.is_finite()) {
        return Err(PredictionError::NotFinite {
            what: "closed-loop matrix M",
        });
    }
    let schur =
        nalgebra::Schur::try_new(m, 1e-11, 100_000).ok_or(PredictionError::NoEigenvalues)?;
    let abscissa = schur
        .complex_eigenvalues()
        .iter()
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max);
    let scale = linear.m.amax().max(1.0);
    if abscissa > INSTABILITY_TOLERANCE * scale {
        return Err(PredictionError::Unstable { abscissa });
    }
    Ok(abscissa)
}

/// The sums along the linear loop's trajectory on `options`' grid, with ΔT and (for the
/// perturbation's effect) without it.
pub fn predict_linear<const N: usize, const NX: usize, const NZ: usize>(
    linear: &LinearLoop<N, NX, NZ>,
    options: &EpisodeOptionsN<N, NX>,
    abscissa: f64,
) -> Result<Prediction, PredictionError> {
    let grid = uniform_grid(0.0, options.t_end, options.dt);
    if grid.len() < 2 {
        return Err(PredictionError::ZeroHorizon {
            t_end: options.t_end,
        });
    }
    let perturbation = options.total_perturbation();
    let perturbed = perturbation.iter().any(|v| *v != 0.0);
    let mut inputs = vec![linear.input(&perturbation)];
    if perturbed {
        inputs.push(linear.input(&SVector::zeros()));
    }
    let regular = Step::new(&linear.m, &inputs, options.dt);
    let h_last = grid[grid.len() - 1] - grid[grid.len() - 2];
    // 5/0.05 leaves a last interval of 0.04999999999999982 s: the same step to rounding.
    let regular_last = (h_last - options.dt).abs() <= 1e-12 * options.dt;
    let last = (!regular_last).then(|| Step::new(&linear.m, &inputs, h_last));
    let steps = (&regular, last.as_ref().unwrap_or(&regular));
    let mut z0 = SVector::<f64, NZ>::zeros();
    z0.fixed_rows_mut::<NX>(0)
        .copy_from(&(options.x0 - linear.x_e));
    z0.fixed_rows_mut::<N>(NX).copy_from(&options.u0);
    let with = sums(linear, &grid, steps, 0, &z0, &perturbation);
    let without = match perturbed {
        true => sums(linear, &grid, steps, 1, &z0, &SVector::zeros()).task_error,
        false => with.task_error,
    };
    let prediction = Prediction {
        task_error: with.task_error,
        free_energy: with.free_energy,
        cost_j: with.cost_j,
        perturbation_effect: with.task_error - without,
        abscissa,
    };
    for (what, v) in [
        ("task error", prediction.task_error),
        ("free energy", prediction.free_energy),
        ("cost J", prediction.cost_j),
        ("perturbation effect", prediction.perturbation_effect),
    ] {
        if !v.is_finite() {
            return Err(PredictionError::NotFinite { what });
        }
    }
    Ok(prediction)
}
