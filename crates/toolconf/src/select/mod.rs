//! Decision-making: draw random tools, run every tool's episode (in parallel), and choose by
//! ∫F (the paper's confidence-aware objective), ∫J (classic optimal-control cost) and ln|Π^U|
//! alone (confidence, no simulation needed).
//!
//! Tools are drawn from a documented stream so that a seed names a tool set exactly: ChaCha8
//! (`rand_chacha::ChaCha8Rng::seed_from_u64(seed)`), each draw u = (next_u64 >> 11)·2⁻⁵³ ∈ [0, 1),
//! each parameter 0.1 + 0.5·u, in the order m1, m2, l1, l2, tool after tool. Draws happen before
//! any parallel work and every episode is independent and deterministic, so results are identical
//! whatever the number of threads.

pub mod mixed;

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::mpc::{MpcEpisodeError, MpcMetrics, MpcOptions, SimulateMpc};
use toolconf_model::closed_loop::{EpisodeOptions, Metrics, Plant, SimulationError};
use toolconf_model::confidence::control_confidence;
use toolconf_model::{Arm, Error, Task};

/// The paper's parameter domain for m1, m2, l1, l2 ("Implementation details").
pub const PARAMETER_RANGE: (f64, f64) = (0.1, 0.6);

/// A seeded stream of random tools.
pub struct ToolSampler {
    rng: ChaCha8Rng,
}

impl ToolSampler {
    pub fn new(seed: u64) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// The next tool, parameters uniform on [0.1, 0.6).
    pub fn next_tool(&mut self) -> Arm {
        let (lo, hi) = PARAMETER_RANGE;
        let mut p = [0.0; 4];
        for v in &mut p {
            *v = lo + (hi - lo) * self.uniform();
        }
        Arm::new(p).expect("parameters drawn from [0.1, 0.6) are valid")
    }

    pub fn tools(&mut self, n: usize) -> Vec<Arm> {
        (0..n).map(|_| self.next_tool()).collect()
    }
}

/// `n` tools drawn from `seed` (see the module docs for the stream).
pub fn draw_tools(n: usize, seed: u64) -> Vec<Arm> {
    ToolSampler::new(seed).tools(n)
}

/// One tool's evaluation: its confidence (no simulation needed) and its episode.
#[derive(Debug, Clone)]
pub struct ToolResult {
    pub index: usize,
    pub arm: Arm,
    pub logdet: Result<f64, Error>,
    pub episode: Result<Metrics, SimulationError>,
}

/// Runs every tool's episode on `plant` in parallel; the result order is the tools' order.
pub fn evaluate(
    tools: &[Arm],
    task: &Task,
    options: &EpisodeOptions,
    plant: Plant,
) -> Vec<ToolResult> {
    let options = EpisodeOptions {
        record_trajectory: false,
        ..*options
    };
    tools
        .par_iter()
        .enumerate()
        .map(|(index, arm)| ToolResult {
            index,
            arm: *arm,
            logdet: control_confidence(arm, task)
                .map(|c| c.logdet)
                .map_err(Error::from),
            episode: plant.simulate(arm, task, &options).map(|e| e.metrics),
        })
        .collect()
}

/// The MPC baseline's episode on `plant` for every tool, in parallel, in the tools' order: the
/// cost it achieves, ∫J dt, is the objective J* of the MPC baseline, the conventional optimal-control
/// ranking.
pub fn evaluate_mpc(
    tools: &[Arm],
    task: &Task,
    options: &EpisodeOptions,
    mpc: &MpcOptions,
    plant: Plant,
) -> Vec<Result<MpcMetrics, MpcEpisodeError>> {
    let options = EpisodeOptions {
        record_trajectory: false,
        ..*options
    };
    tools
        .par_iter()
        .map(|arm| {
            plant
                .simulate_mpc(arm, task, &options, mpc)
                .map(|e| e.metrics)
        })
        .collect()
}

/// argmin J* over the tools whose MPC episode succeeded; ties go to the earlier tool.
pub fn choose_by_mpc_cost(results: &[Result<MpcMetrics, MpcEpisodeError>]) -> Option<usize> {
    first_argmin(
        results
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.as_ref().ok().map(|m| (i, m.cost_j))),
    )
}

/// The index of the smallest score, the earlier index on ties: how every objective chooses
/// (tools without a score, e.g. failed episodes, are simply absent from `scores`).
pub fn first_argmin(scores: impl Iterator<Item = (usize, f64)>) -> Option<usize> {
    scores
        .fold(None, |best: Option<(usize, f64)>, (i, s)| match best {
            Some((_, b)) if b <= s => best,
            _ => Some((i, s)),
        })
        .map(|(i, _)| i)
}

/// An objective that ranks tools.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Objective {
    /// argmin ∫F dt: performance + control effort + confidence (the paper's criterion).
    FreeEnergy,
    /// argmin ∫J dt: performance + control effort (optimal control).
    CostJ,
    /// argmax ln|Π^U|: confidence alone, without simulating.
    Confidence,
}

impl Objective {
    pub const ALL: [Objective; 3] = [
        Objective::FreeEnergy,
        Objective::CostJ,
        Objective::Confidence,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Objective::FreeEnergy => "free_energy",
            Objective::CostJ => "cost_j",
            Objective::Confidence => "confidence",
        }
    }

    /// The value to minimise for a tool, if the tool has one.
    pub fn score(self, r: &ToolResult) -> Option<f64> {
        self.score_of(r.episode.as_ref().ok(), r.logdet.as_ref().ok())
    }

    /// The value to minimise for a tool with this episode's metrics and this ln|Π^U|, where the
    /// objective's one is there.
    pub(crate) fn score_of(self, episode: Option<&Metrics>, logdet: Option<&f64>) -> Option<f64> {
        match self {
            Objective::FreeEnergy => episode.map(|m| m.free_energy),
            Objective::CostJ => episode.map(|m| m.cost_j),
            Objective::Confidence => logdet.map(|l| -l),
        }
    }

    /// The index of the chosen tool; ties go to the earlier tool, failed tools are skipped.
    pub fn choose(self, results: &[ToolResult]) -> Option<usize> {
        first_argmin(
            results
                .iter()
                .filter_map(|r| Some((r.index, self.score(r)?))),
        )
    }
}
