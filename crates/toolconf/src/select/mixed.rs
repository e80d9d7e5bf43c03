//! Tool sets that mix models: a seeded draw, parallel evaluation, and choices by ∫F, ∫J, ln|Π^U|
//! and the normalised confidence ln|Π^U|/n (docs/explanation/mixed-tools.md).
//!
//! # The stream
//!
//! The draws extend [`crate::select::ToolSampler`]'s documented mapping: ChaCha8
//! (`ChaCha8Rng::seed_from_u64(seed)`), each draw u = (next_u64 >> 11)·2⁻⁵³ ∈ [0, 1). Per tool,
//! first the model: with k models in the set, index min(⌊k·u⌋, k − 1) into the set as given
//! (no draw when k = 1, so a set of only `arm2` is exactly `select::draw_tools`); then the
//! model's parameters, each lo + (hi − lo)·u from the model's sampling box
//! (`generated::validity`: [0.1, 0.6], so 0.1 + 0.5·u, for the planar arms' masses and lengths;
//! a URDF tool's description gives its own), in the model's parameter order (arm2: m1 m2 l1 l2;
//! arm3: m1 m2 m3 l1 l2 l3). A draw that breaks the model's rule (a URDF tool whose principal
//! moments violate the triangle inequality) is drawn again, all its parameters; the planar arms
//! have no such rule and never redraw. Draws happen before any parallel work, so results do not
//! depend on the number of threads.
//!
//! # The task
//!
//! Each tool runs its own model's paper-style task ([`ArmModel::paper_task`]): the paper's
//! precisions (P = value·I of the model's size) and the model's goals from
//! `derive/models/<model>.toml`. arm2 and arm2_exact use the paper's goals; arm3's extend them
//! (position θ^g = [π/3, π/3, π/6]: the end joint keeps the 2-link end goal π/6 and the middle
//! joint follows link 1; velocity θ̇^g = [0, 0, 2] and acceleration θ̈^g = [0, 0, 0.1] on the
//! last joint). Every episode starts at its model's hanging equilibrium with U0 = 0.1 on every
//! joint.

use super::Objective;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Draws of one tool before [`MixedSampler`] takes the sampling box's centre instead.
const MAX_REDRAWS: usize = 10_000;
use toolconf_model::closed_loop::{EpisodeOptions, Metrics, Plant};
use toolconf_model::model::{
    control_confidence, simulate_on, Arm2, Arm2Exact, ModelSimulationError, TaskN,
};
use toolconf_model::registry::{paper_options, AnyTool, ModelKind};
use toolconf_model::{Error, TaskKind};

/// A seeded stream of tools of several models (see the module docs for the mapping).
pub struct MixedSampler {
    rng: ChaCha8Rng,
    models: Vec<ModelKind>,
}

impl MixedSampler {
    /// Errors if `models` is empty.
    pub fn new(models: &[ModelKind], seed: u64) -> Result<Self, Error> {
        if models.is_empty() {
            return Err(Error::InvalidOption {
                name: "number of models",
                value: 0.0,
            });
        }
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            models: models.to_vec(),
        })
    }

    fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A tool of `model`: each parameter lo + (hi − lo)·u in the model's order, from its
    /// sampling box ([`ModelKind::sample_box`]); a draw that breaks the model's rule (a URDF
    /// tool's triangle inequality) is drawn again, whole.
    fn draw(&mut self, model: ModelKind) -> AnyTool {
        let sample = model.sample_box();
        for _ in 0..MAX_REDRAWS {
            let p: Vec<f64> = sample
                .iter()
                .map(|&(lo, hi)| lo + (hi - lo) * self.uniform())
                .collect();
            if let Ok(tool) = AnyTool::new(model, &p) {
                return tool;
            }
        }
        // The box's centre satisfies the rule (derive checks it), so this is never reached in
        // practice; it keeps the stream finite whatever a description's box is.
        let centre: Vec<f64> = sample.iter().map(|&(lo, hi)| 0.5 * (lo + hi)).collect();
        AnyTool::new(model, &centre)
            .expect("derive checks that the sampling box's centre is a valid tool")
    }

    /// The next tool: its model (if the set has more than one), then its parameters.
    pub fn next_tool(&mut self) -> AnyTool {
        let k = self.models.len();
        let model = if k == 1 {
            self.models[0]
        } else {
            let i = ((k as f64) * self.uniform()) as usize;
            self.models[i.min(k - 1)]
        };
        self.draw(model)
    }

    pub fn tools(&mut self, n: usize) -> Vec<AnyTool> {
        (0..n).map(|_| self.next_tool()).collect()
    }
}

/// `n` tools of the given models drawn from `seed`.
pub fn draw_mixed_tools(models: &[ModelKind], n: usize, seed: u64) -> Result<Vec<AnyTool>, Error> {
    Ok(MixedSampler::new(models, seed)?.tools(n))
}

/// One tool's evaluation in a mixed set.
#[derive(Debug, Clone)]
pub struct MixedResult {
    pub index: usize,
    pub tool: AnyTool,
    /// ln|Π^U| on the tool's own task.
    pub logdet: Result<f64, Error>,
    pub episode: Result<Metrics, ModelSimulationError>,
}

impl MixedResult {
    pub fn model(&self) -> ModelKind {
        self.tool.model()
    }

    /// ln|Π^U|/n, n the tool's control dimension: the comparable confidence.
    pub fn logdet_per_joint(&self) -> Option<f64> {
        self.logdet
            .as_ref()
            .ok()
            .map(|l| l / self.model().dof() as f64)
    }
}

/// Evaluates every tool on its own model's paper-style `kind` task, in parallel; the result
/// order is the tools' order. `common` gives the horizon, grid, perturbation, learning rate and
/// integrator (`options_for`); `plant` [`Plant::Exact`] simulates the arm2 tools on the exact
/// 2-link dynamics (as `--plant exact` does for 2-link selection), other models always on their
/// own dynamics.
pub fn evaluate_mixed(
    tools: &[AnyTool],
    kind: TaskKind,
    common: &EpisodeOptions,
    plant: Plant,
) -> Vec<MixedResult> {
    tools
        .par_iter()
        .enumerate()
        .map(|(index, tool)| {
            // The paper's 2-link arm on the exact plant: the typed 2-link runtime.
            let exact = match plant {
                Plant::Exact => tool.downcast::<Arm2, 2, 4, 4, 6>(),
                Plant::Paper => None,
            };
            let (logdet, episode) = match exact {
                Some(t) => {
                    let task = TaskN::paper(kind);
                    let options = paper_options::<Arm2, 2, 4, 4, 6>(common);
                    (
                        control_confidence(&t, &task)
                            .map(|c| c.logdet)
                            .map_err(Error::from),
                        simulate_on::<Arm2, Arm2Exact, 2, 4, 4, 6>(&t, &task, &options),
                    )
                }
                None => tool
                    .model()
                    .model()
                    .paper_evaluation(tool.parameters(), kind, common),
            };
            MixedResult {
                index,
                tool: *tool,
                logdet,
                episode,
            }
        })
        .collect()
}

/// An objective that ranks tools of a mixed set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MixedObjective {
    /// argmin ∫F dt.
    FreeEnergy,
    /// argmin ∫J dt.
    CostJ,
    /// argmax ln|Π^U| (raw: favours more joints, see docs/explanation/mixed-tools.md).
    Confidence,
    /// argmax ln|Π^U|/n, the per-joint (geometric-mean) confidence.
    NormalisedConfidence,
}

impl MixedObjective {
    pub const ALL: [MixedObjective; 4] = [
        MixedObjective::FreeEnergy,
        MixedObjective::CostJ,
        MixedObjective::Confidence,
        MixedObjective::NormalisedConfidence,
    ];

    /// The objective of the same name among the 2-link selection's ([`Objective`]), for all but
    /// the per-joint confidence.
    fn shared(self) -> Option<Objective> {
        match self {
            MixedObjective::FreeEnergy => Some(Objective::FreeEnergy),
            MixedObjective::CostJ => Some(Objective::CostJ),
            MixedObjective::Confidence => Some(Objective::Confidence),
            MixedObjective::NormalisedConfidence => None,
        }
    }

    pub fn name(self) -> &'static str {
        self.shared()
            .map_or("normalised_confidence", Objective::name)
    }

    /// The value to minimise for a tool, if the tool has one.
    pub fn score(self, r: &MixedResult) -> Option<f64> {
        match self.shared() {
            Some(o) => o.score_of(r.episode.as_ref().ok(), r.logdet.as_ref().ok()),
            None => r.logdet_per_joint().map(|l| -l),
        }
    }

    /// The index of the chosen tool; ties go to the earlier tool, failed tools are skipped
    /// (as [`crate::select::Objective::choose`]).
    pub fn choose(self, results: &[MixedResult]) -> Option<usize> {
        super::first_argmin(
            results
                .iter()
                .filter_map(|r| Some((r.index, self.score(r)?))),
        )
    }
}
