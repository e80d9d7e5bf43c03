//! Ranking the user's own tools on the user's own task (`toolconf rank`).
//!
//! Two stages, as the paper suggests: the cheap one computes every tool's control confidence
//! Π^U = ∂²F/∂U² and ln|Π^U| in closed form (no simulation), streaming through the tools file
//! and keeping only the K most confident when screening ([`Screen`]); the expensive one simulates
//! the kept tools' episodes in parallel ([`simulate_all`]) and ranks them by ∫F dt, ∫J dt or
//! ln|Π^U| ([`ranking`]). A tool whose episode fails keeps its error and goes last.
//!
//! Determinism: the screen breaks ties by file order, episodes run in fixed chunks whose results
//! are handed on in file order, and every episode is deterministic, so results and streamed rows
//! are identical whatever the number of threads.

pub mod report;

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use rayon::prelude::*;

use crate::generated;
use crate::model::mixed::{AnyTool, ModelKind};
use crate::model::{
    episode, ArmModel, EpisodeOptionsN, Metrics, ModelSimulationError, ToolN, ValidatedTaskN,
};
use crate::select::Objective;
use crate::task_file::{TaskFileError, TaskSpec};
use crate::tools_file::ToolRow;
use crate::{Error, TaskKind};

/// A task bound to one model: checked goals and precisions, and the episode options.
#[derive(Debug, Clone, Copy)]
pub struct Bound<const N: usize, const NX: usize> {
    pub task: ValidatedTaskN<N>,
    pub options: EpisodeOptionsN<N, NX>,
}

fn bind<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    spec: &TaskSpec,
) -> Result<Bound<N, NX>, TaskFileError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let task = spec.task::<M, N, NX, NP, NZ>()?;
    let options = spec.episode::<M, N, NX, NP, NZ>()?;
    let task = task.validated().map_err(|e| TaskFileError {
        file: spec.file.clone(),
        place: "key precision".into(),
        message: e.to_string(),
    })?;
    Ok(Bound { task, options })
}

/// [`ModelTasks`] with one binding per generated model ([`crate::for_each_model!`]).
macro_rules! model_tasks {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        /// The task bound to every model. A task that does not fit a model (a goal of the
        /// wrong length) is an error only once a tool of that model turns up
        /// ([`ModelTasks::check`]).
        #[derive(Debug, Clone)]
        pub struct ModelTasks {
            pub kind: TaskKind,
            $($module: Result<
                Bound<{ generated::$module::DOF }, { generated::$module::STATE_DIM }>,
                TaskFileError,
            >,)*
        }

        impl ModelTasks {
            pub fn new(spec: &TaskSpec) -> Self {
                Self {
                    kind: spec.kind,
                    $($module: bind::<
                        crate::model::$marker,
                        { generated::$module::DOF },
                        { generated::$module::STATE_DIM },
                        { generated::$module::PARAMETER_COUNT },
                        { generated::$module::STATE_DIM + generated::$module::DOF },
                    >(spec),)*
                }
            }

            /// Whether the task fits `model`.
            pub fn check(&self, model: ModelKind) -> Result<(), TaskFileError> {
                match model {
                    $(ModelKind::$marker => self.$module.as_ref().map(|_| ()).map_err(Clone::clone),)*
                }
            }

            /// ln|Π^U| of `tool` (eq. control_conf): the cheap stage.
            pub fn logdet(&self, tool: &AnyTool) -> Result<f64, Error> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => b.task.control_confidence(t).map(|c| c.logdet),
                        Err(e) => Err(Error::Unsupported(e.to_string())),
                    },)*
                }
            }

            /// ln|Π^U| of `tool` and its gradient ∂ln|Π^U|/∂p (the generated closed form),
            /// in the model's parameter order: what `toolconf design` climbs.
            pub fn logdet_and_gradient(&self, tool: &AnyTool) -> Result<(f64, Vec<f64>), Error> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => b.task.control_confidence(t).map(|c| {
                            (c.logdet, b.task.logdet_gradient(t).as_slice().to_vec())
                        }),
                        Err(e) => Err(Error::Unsupported(e.to_string())),
                    },)*
                }
            }

            /// The episode's metrics.
            pub fn simulate(&self, tool: &AnyTool) -> Result<Metrics, ModelSimulationError> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => crate::model::simulate(t, b.task.task(), &b.options),
                        Err(e) => Err(unfit(e)),
                    },)*
                }
            }

            /// The task variable (θ, θ̇ or θ̈ as the task kind says) over time, with its goal.
            pub fn trace(&self, tool: &AnyTool) -> Result<TaskTrace, ModelSimulationError> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => trace_of(t, b, self.kind),
                        Err(e) => Err(unfit(e)),
                    },)*
                }
            }
        }
    };
}

crate::for_each_model!(model_tasks);

fn unfit(e: &TaskFileError) -> ModelSimulationError {
    ModelSimulationError::Input(Error::Unsupported(e.to_string()))
}

/// The task variable of one episode on the output grid, per joint, with the goal.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTrace {
    pub t: Vec<f64>,
    /// `value[j][i]`: joint j at `t[i]`.
    pub value: Vec<Vec<f64>>,
    pub goal: Vec<f64>,
}

fn trace_of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    bound: &Bound<N, NX>,
    kind: TaskKind,
) -> Result<TaskTrace, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let options = EpisodeOptionsN {
        record_trajectory: true,
        ..bound.options
    };
    let task = bound.task.task();
    let tr = episode(tool, task, &options)?
        .trajectory
        .expect("a recorded episode has a trajectory");
    let (series, goal) = match kind {
        TaskKind::Position => (&tr.theta, task.goal_theta),
        TaskKind::Velocity => (&tr.theta_dot, task.goal_theta_dot),
        TaskKind::Acceleration => (&tr.theta_ddot, task.goal_theta_ddot),
    };
    Ok(TaskTrace {
        t: tr.t.clone(),
        value: (0..N)
            .map(|j| series.iter().map(|v| v[j]).collect())
            .collect(),
        goal: goal.iter().copied().collect(),
    })
}

/// A tool that passed the cheap stage, with its confidence.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    pub row: ToolRow,
    pub logdet: Result<f64, Error>,
}

/// A candidate in the screen's heap, ordered by confidence; on a tie the later row is less.
struct Screened {
    logdet: f64,
    candidate: Candidate,
}

impl Ord for Screened {
    fn cmp(&self, other: &Self) -> Ordering {
        self.logdet
            .total_cmp(&other.logdet)
            .then(other.candidate.row.row.cmp(&self.candidate.row.row))
    }
}

impl PartialOrd for Screened {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Screened {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Screened {}

/// The cheap stage over a stream of tools: keeps every tool, or only the `k` most confident
/// (largest ln|Π^U|, the earlier row on ties) in O(k) memory.
pub struct Screen {
    limit: Option<usize>,
    heap: BinaryHeap<Reverse<Screened>>,
    all: Vec<Candidate>,
    /// Tools seen.
    pub read: usize,
    /// Tools whose Π^U is not positive definite (never kept by a screen), and the first reason.
    pub without_confidence: usize,
    pub first_confidence_error: Option<String>,
}

impl Screen {
    /// `limit`: keep only this many (the `--screen K`), or every tool.
    pub fn new(limit: Option<usize>) -> Self {
        Self {
            limit,
            heap: BinaryHeap::new(),
            all: Vec::new(),
            read: 0,
            without_confidence: 0,
            first_confidence_error: None,
        }
    }

    pub fn push(&mut self, candidate: Candidate) {
        self.read += 1;
        if let Err(e) = &candidate.logdet {
            self.without_confidence += 1;
            self.first_confidence_error
                .get_or_insert_with(|| e.to_string());
        }
        let Some(k) = self.limit else {
            self.all.push(candidate);
            return;
        };
        let Ok(logdet) = candidate.logdet else {
            return;
        };
        let entry = Screened { logdet, candidate };
        if self.heap.len() < k {
            self.heap.push(Reverse(entry));
        } else if self
            .heap
            .peek()
            .is_some_and(|Reverse(worst)| entry > *worst)
        {
            self.heap.pop();
            self.heap.push(Reverse(entry));
        }
    }

    /// The kept tools in file order.
    pub fn finish(self) -> Vec<Candidate> {
        if self.limit.is_none() {
            return self.all;
        }
        let mut kept: Vec<Candidate> = self
            .heap
            .into_iter()
            .map(|Reverse(s)| s.candidate)
            .collect();
        kept.sort_by_key(|c| c.row.row);
        kept
    }
}

/// A simulated tool.
#[derive(Debug, Clone, PartialEq)]
pub struct RankedTool {
    pub row: ToolRow,
    pub logdet: Result<f64, Error>,
    pub episode: Result<Metrics, ModelSimulationError>,
}

impl RankedTool {
    /// `m1=0.3 m2=0.4 …`, each value as the CSVs write it: the table's and the report's column.
    pub fn parameters_text(&self) -> String {
        let params: Vec<String> = self
            .row
            .tool
            .named_parameters()
            .iter()
            .map(|(n, v)| format!("{n}={}", crate::experiments::csv::format_number(*v)))
            .collect();
        params.join(" ")
    }
}

/// How many episodes run in parallel before their results are handed on, in file order.
const CHUNK: usize = 64;

/// Simulates every candidate (in parallel, chunk by chunk) and hands each result to `done` in
/// file order as its chunk finishes; returns all results in file order.
pub fn simulate_all<E>(
    candidates: Vec<Candidate>,
    tasks: &ModelTasks,
    mut done: impl FnMut(&RankedTool) -> Result<(), E>,
) -> Result<Vec<RankedTool>, E> {
    let mut results = Vec::with_capacity(candidates.len());
    for chunk in candidates.chunks(CHUNK) {
        let finished: Vec<RankedTool> = chunk
            .par_iter()
            .map(|c| RankedTool {
                row: c.row.clone(),
                logdet: c.logdet.clone(),
                episode: tasks.simulate(&c.row.tool),
            })
            .collect();
        for r in finished {
            done(&r)?;
            results.push(r);
        }
    }
    Ok(results)
}

/// The value an objective minimises for a tool whose episode succeeded (∫F dt, ∫J dt, or
/// −ln|Π^U|); `None` for a failed episode.
pub fn score(objective: Objective, r: &RankedTool) -> Option<f64> {
    let m = r.episode.as_ref().ok()?;
    Some(match objective {
        Objective::FreeEnergy => m.free_energy,
        Objective::CostJ => m.cost_j,
        Objective::Confidence => -m.logdet,
    })
}

/// Indices into `results` from best to worst by `objective`: ties keep file order, and tools
/// whose episode failed come last, in file order.
pub fn ranking(results: &[RankedTool], objective: Objective) -> Vec<usize> {
    let mut order: Vec<usize> = (0..results.len()).collect();
    order.sort_by(|&a, &b| {
        match (score(objective, &results[a]), score(objective, &results[b])) {
            (Some(x), Some(y)) => x.total_cmp(&y),
            (Some(_), None) => Ordering::Less,
            (None, Some(_)) => Ordering::Greater,
            (None, None) => Ordering::Equal,
        }
        .then(results[a].row.row.cmp(&results[b].row.row))
    });
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(row: usize, logdet: Result<f64, Error>) -> Candidate {
        Candidate {
            row: ToolRow {
                row,
                name: None,
                tool: AnyTool::new(ModelKind::Arm2, &[0.3, 0.3, 0.3, 0.3]).unwrap(),
            },
            logdet,
        }
    }

    #[test]
    fn failed_episodes_rank_last_in_file_order_and_ties_keep_file_order() {
        let metrics = |free_energy: f64| Metrics {
            task_error: 1.0,
            free_energy,
            cost_j: 2.0 * free_energy,
            logdet: -free_energy,
            rhs_evals: 0,
            steps: 0,
            rejected_steps: 0,
            jacobian_evals: 0,
            factorisations: 0,
            control_effort: 0.0,
        };
        let failed = Err(ModelSimulationError::Input(Error::Unsupported("x".into())));
        let results: Vec<RankedTool> = [
            (1, failed.clone()),
            (2, Ok(metrics(3.0))),
            (3, Ok(metrics(1.0))),
            (4, failed),
            (5, Ok(metrics(1.0))),
        ]
        .into_iter()
        .map(|(row, episode)| RankedTool {
            row: candidate(row, Ok(0.0)).row,
            logdet: Ok(0.0),
            episode,
        })
        .collect();
        let rows = |o: Objective| -> Vec<usize> {
            ranking(&results, o)
                .iter()
                .map(|&i| results[i].row.row)
                .collect()
        };
        assert_eq!(rows(Objective::FreeEnergy), [3, 5, 2, 1, 4]);
        assert_eq!(rows(Objective::CostJ), [3, 5, 2, 1, 4]);
        // Confidence ranks the largest ln|Π^U| (here −F) first.
        assert_eq!(rows(Objective::Confidence), [3, 5, 2, 1, 4]);
    }

    #[test]
    fn the_screen_keeps_the_most_confident_and_the_earlier_on_ties() {
        let mut screen = Screen::new(Some(2));
        let bad = Err(Error::NotPositiveDefinite { determinant: 0.0 });
        for (row, l) in [
            (1, Ok(1.0)),
            (2, Ok(3.0)),
            (3, bad),
            (4, Ok(2.0)),
            (5, Ok(3.0)),
            (6, Ok(0.5)),
        ] {
            screen.push(candidate(row, l));
        }
        assert_eq!((screen.read, screen.without_confidence), (6, 1));
        let rows: Vec<usize> = screen.finish().iter().map(|c| c.row.row).collect();
        assert_eq!(rows, [2, 5]);
        let mut screen = Screen::new(Some(1));
        for (row, l) in [(1, 2.0), (2, 2.0)] {
            screen.push(candidate(row, Ok(l)));
        }
        assert_eq!(screen.finish()[0].row.row, 1);
    }
}
