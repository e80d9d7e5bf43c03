//! Tool sets that mix models: a seeded draw, parallel evaluation, and choices by ∫F, ∫J, ln|Π^U|
//! and the normalised confidence ln|Π^U|/n (docs/mixed-tools.md).
//!
//! # The stream
//!
//! The draws extend [`crate::select::ToolSampler`]'s documented mapping: ChaCha8
//! (`ChaCha8Rng::seed_from_u64(seed)`), each draw u = (next_u64 >> 11)·2⁻⁵³ ∈ [0, 1). Per tool,
//! first the model: with k models in the set, index min(⌊k·u⌋, k − 1) into the set as given
//! (no draw when k = 1, so a set of only `arm2` is exactly `select::draw_tools`); then the
//! model's parameters, each 0.1 + 0.5·u, in the model's parameter order (arm2: m1 m2 l1 l2;
//! arm3: m1 m2 m3 l1 l2 l3). Draws happen before any parallel work, so results do not depend on
//! the number of threads.
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

use std::fmt;
use std::str::FromStr;

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::*;
use crate::closed_loop::{EpisodeOptions, Metrics, Plant};
use crate::generated;
use crate::select::PARAMETER_RANGE;
use crate::{Error, TaskKind};

/// The mixed-set types over every generated model ([`crate::for_each_model!`]): [`ModelKind`]
/// names a model, [`AnyTool`] holds a tool of any of them, and each dispatches by model.
macro_rules! mixed_models {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        /// The models a mixed set can draw from: every generated model.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum ModelKind {
            $(#[doc = $title] $marker,)*
        }

        impl ModelKind {
            pub const ALL: [ModelKind; generated::MODEL_NAMES.len()] = [$(ModelKind::$marker,)*];

            /// The generated module's name.
            pub fn name(self) -> &'static str {
                match self { $(ModelKind::$marker => generated::$module::NAME,)* }
            }

            /// The control dimension n (joints).
            pub fn dof(self) -> usize {
                match self { $(ModelKind::$marker => generated::$module::DOF,)* }
            }

            /// The tool parameters' names, in the order a tool takes them.
            pub fn parameter_names(self) -> &'static [&'static str] {
                match self { $(ModelKind::$marker => &generated::$module::PARAMETER_NAMES,)* }
            }
        }

        /// A tool of any model.
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum AnyTool {
            $($marker($tool),)*
        }

        impl AnyTool {
            pub fn model(&self) -> ModelKind {
                match self { $(AnyTool::$marker(_) => ModelKind::$marker,)* }
            }

            /// (name, value) of every parameter, in the model's order.
            pub fn named_parameters(&self) -> Vec<(&'static str, f64)> {
                match self { $(AnyTool::$marker(t) => t.named_parameters().to_vec(),)* }
            }

            /// Builds a validated tool of `model` from its parameters in the model's order.
            pub fn new(model: ModelKind, params: &[f64]) -> Result<Self, Error> {
                let count = || Error::ParameterCount {
                    model: model.name(),
                    expected: model.parameter_names().len(),
                    names: model.parameter_names().join(","),
                    found: params.len(),
                };
                Ok(match model {
                    $(ModelKind::$marker => {
                        AnyTool::$marker(ToolN::new(params.try_into().map_err(|_| count())?)?)
                    })*
                })
            }

            /// ln|Π^U| and the episode on the tool's own paper-style `kind` task.
            fn evaluate(&self, kind: TaskKind, common: &EpisodeOptions) -> Evaluation {
                match self { $(AnyTool::$marker(t) => evaluate_one(t, kind, common),)* }
            }
        }

        impl fmt::Display for AnyTool {
            /// `model(m1=… m2=… …)`.
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match self { $(AnyTool::$marker(t) => write!(f, "{t:?}"),)* }
            }
        }

        impl MixedSampler {
            fn draw(&mut self, model: ModelKind) -> AnyTool {
                let valid = "parameters drawn from [0.1, 0.6) are valid";
                match model {
                    $(ModelKind::$marker => AnyTool::$marker(ToolN::new(self.parameters()).expect(valid)),)*
                }
            }
        }
    };
}

crate::for_each_model!(mixed_models);

/// ln|Π^U| and the episode's metrics of one tool.
type Evaluation = (Result<f64, Error>, Result<Metrics, ModelSimulationError>);

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim().to_ascii_lowercase();
        ModelKind::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown model '{s}': expected one of {}",
                    generated::MODEL_NAMES.join(", ")
                )
            })
    }
}

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

    fn parameters<const NP: usize>(&mut self) -> [f64; NP] {
        let (lo, hi) = PARAMETER_RANGE;
        let mut p = [0.0; NP];
        for v in &mut p {
            *v = lo + (hi - lo) * self.uniform();
        }
        p
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

fn evaluate_one<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    kind: TaskKind,
    common: &EpisodeOptions,
) -> Evaluation
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let task = TaskN::paper::<M, NX, NP, NZ>(kind);
    let options = EpisodeOptionsN::from_common::<M, NP, NZ>(common);
    (
        control_confidence(tool, &task).map(|c| c.logdet),
        simulate(tool, &task, &options),
    )
}

/// Evaluates every tool on its own model's paper-style `kind` task, in parallel; the result
/// order is the tools' order. `common` gives the horizon, grid, perturbation, learning rate and
/// integrator ([`EpisodeOptionsN::from_common`]); `common.plant == Plant::Exact` simulates the
/// arm2 tools on the exact 2-link dynamics (as `--plant exact` does for 2-link selection), other
/// models always on their own dynamics.
pub fn evaluate_mixed(
    tools: &[AnyTool],
    kind: TaskKind,
    common: &EpisodeOptions,
) -> Vec<MixedResult> {
    tools
        .par_iter()
        .enumerate()
        .map(|(index, tool)| {
            let (logdet, episode) = match tool {
                AnyTool::Arm2(t) if common.plant == Plant::Exact => {
                    let task = TaskN::paper::<Arm2, 4, 4, 6>(kind);
                    let options = EpisodeOptionsN::from_common::<Arm2, 4, 6>(common);
                    (
                        control_confidence(t, &task).map(|c| c.logdet),
                        simulate_on::<Arm2, super::Arm2Exact, 2, 4, 4, 6>(t, &task, &options),
                    )
                }
                other => other.evaluate(kind, common),
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
    /// argmax ln|Π^U| (raw: favours more joints, see docs/mixed-tools.md).
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

    pub fn name(self) -> &'static str {
        match self {
            MixedObjective::FreeEnergy => "free_energy",
            MixedObjective::CostJ => "cost_j",
            MixedObjective::Confidence => "confidence",
            MixedObjective::NormalisedConfidence => "normalised_confidence",
        }
    }

    /// The value to minimise for a tool, if the tool has one.
    pub fn score(self, r: &MixedResult) -> Option<f64> {
        match self {
            MixedObjective::FreeEnergy => r.episode.as_ref().ok().map(|m| m.free_energy),
            MixedObjective::CostJ => r.episode.as_ref().ok().map(|m| m.cost_j),
            MixedObjective::Confidence => r.logdet.as_ref().ok().map(|l| -l),
            MixedObjective::NormalisedConfidence => r.logdet_per_joint().map(|l| -l),
        }
    }

    /// The index of the chosen tool; ties go to the earlier tool, failed tools are skipped
    /// (as [`crate::select::Objective::choose`]).
    pub fn choose(self, results: &[MixedResult]) -> Option<usize> {
        crate::select::first_argmin(
            results
                .iter()
                .filter_map(|r| self.score(r).map(|s| (r.index, s))),
        )
    }
}
