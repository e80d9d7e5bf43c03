//! Ranking the user's own tools on the user's own task (`toolconf rank`).
//!
//! Two stages, as the paper suggests: the cheap one computes every tool's control confidence
//! Π^U = ∂²F/∂U² and ln|Π^U| in closed form (no simulation), streaming through the tools file
//! and keeping only the K most confident when screening ([`Screen`]), or the K whose episode
//! the linearised closed loop predicts cheapest ([`ScreenBy::Predicted`]); the expensive one simulates
//! the kept tools' episodes in parallel ([`simulate_all`]) and ranks them by ∫F dt, ∫J dt or
//! ln|Π^U| ([`ranking`]). A tool whose episode fails keeps its error and goes last.
//!
//! Determinism: the screen breaks ties by file order, episodes run in fixed chunks whose results
//! are handed on in file order, and every episode is deterministic, so results and streamed rows
//! are identical whatever the number of threads.

mod screen;
mod screen_by;
mod tasks;

pub use screen::{
    check_screened, screen_file, screen_file_with_validation, screen_rows, unpredicted_note,
    Candidate, EachRow, Screen, ScreenError, ScreenedBlock,
};
pub use screen_by::{predicted_cost, ScreenBy};
pub use tasks::{AnyEpisode, Linearisation, ModelTasks, TaskTrace, TrajectoryTable};

use std::cmp::Ordering;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::select::Objective;
use toolconf_model::inputs::tools_file::ToolRow;
use toolconf_model::model::{Metrics, ModelSimulationError};
use toolconf_model::prediction::{Prediction, PredictionError};
use toolconf_model::Error;

/// A simulated tool.
#[derive(Debug, Clone, PartialEq)]
pub struct RankedTool {
    pub row: ToolRow,
    pub logdet: Result<f64, Error>,
    pub episode: Result<Metrics, ModelSimulationError>,
    /// The episode's cost predicted by the linearised closed loop ([`toolconf_model::prediction`]).
    pub prediction: Result<Prediction, PredictionError>,
}

impl RankedTool {
    /// `m1=0.3 m2=0.4 …`, each value as the CSVs write it: the table's and the report's column.
    pub fn parameters_text(&self) -> String {
        let params: Vec<String> = self
            .row
            .tool
            .named_parameters()
            .iter()
            .map(|(n, v)| format!("{n}={}", toolconf_files::csv::format_number(*v)))
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
    done: impl FnMut(&RankedTool) -> Result<(), E>,
) -> Result<Vec<RankedTool>, E> {
    simulate_all_timed(candidates, tasks, done).map(|(results, _)| results)
}

/// [`simulate_all`], also timing the stage: its wall time and the sum of the episodes' own
/// times (each episode timed on its thread; `done` is outside both sums' episodes but inside
/// the wall time).
pub fn simulate_all_timed<E>(
    candidates: Vec<Candidate>,
    tasks: &ModelTasks,
    mut done: impl FnMut(&RankedTool) -> Result<(), E>,
) -> Result<(Vec<RankedTool>, SimulationTiming), E> {
    let start = Instant::now();
    let mut episode_time = Duration::ZERO;
    let mut results = Vec::with_capacity(candidates.len());
    for chunk in candidates.chunks(CHUNK) {
        let finished: Vec<(RankedTool, Duration)> = chunk
            .par_iter()
            .map(|c| {
                let t0 = Instant::now();
                let episode = tasks.simulate(&c.row.tool);
                let took = t0.elapsed();
                let r = RankedTool {
                    row: c.row.clone(),
                    logdet: c.logdet.clone(),
                    episode,
                    // The screen's prediction where it made one: the same value.
                    prediction: c
                        .prediction
                        .clone()
                        .unwrap_or_else(|| tasks.predict(&c.row.tool)),
                };
                (r, took)
            })
            .collect();
        for (r, took) in finished {
            episode_time += took;
            done(&r)?;
            results.push(r);
        }
    }
    let timing = SimulationTiming {
        episodes: results.len(),
        wall: start.elapsed(),
        episode_time,
        threads: rayon::current_num_threads(),
    };
    Ok((results, timing))
}

/// The cheap stage's time: every tool read, checked and given its ln|Π^U| (and the screen's
/// heap), reading and parsing the tools file included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfidenceTiming {
    /// Tools read (bad rows skipped are not counted).
    pub tools: usize,
    pub wall: Duration,
}

impl ConfidenceTiming {
    /// Tools per second of wall time.
    pub fn tools_per_second(&self) -> f64 {
        per_second(self.tools, self.wall)
    }

    /// Mean wall time per tool, in ns.
    pub fn ns_per_tool(&self) -> f64 {
        per_item(self.wall, self.tools) * 1e9
    }
}

/// The expensive stage's time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulationTiming {
    /// Episodes simulated (failed ones included).
    pub episodes: usize,
    /// Wall time of the stage.
    pub wall: Duration,
    /// The episodes' own times added up (each measured on its thread): over `episodes`, the mean
    /// time per episode whatever the number of threads.
    pub episode_time: Duration,
    /// Rayon threads the stage ran on.
    pub threads: usize,
}

impl SimulationTiming {
    /// Episodes per second of wall time (on `threads` threads).
    pub fn episodes_per_second(&self) -> f64 {
        per_second(self.episodes, self.wall)
    }

    /// Mean time of one episode, in µs (its own time, not the wall time over the threads).
    pub fn us_per_episode(&self) -> f64 {
        per_item(self.episode_time, self.episodes) * 1e6
    }
}

/// Both stages' times, for the output and the report. Wall times vary from run to run: they
/// stay out of everything that is compared byte for byte.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageTimings {
    pub confidence: ConfidenceTiming,
    pub simulation: SimulationTiming,
}

fn per_second(n: usize, wall: Duration) -> f64 {
    let s = wall.as_secs_f64();
    if s > 0.0 {
        n as f64 / s
    } else {
        0.0
    }
}

fn per_item(wall: Duration, n: usize) -> f64 {
    if n > 0 {
        wall.as_secs_f64() / n as f64
    } else {
        0.0
    }
}

/// The value an objective minimises for a tool whose episode succeeded (∫F dt, ∫J dt, or
/// −ln|Π^U|); `None` for a failed episode.
pub fn score(objective: Objective, r: &RankedTool) -> Option<f64> {
    r.episode
        .as_ref()
        .ok()
        .map(|m| objective_value(objective, m))
}

/// What `objective` minimises in an episode's metrics: ∫F dt, ∫J dt, or −ln|Π^U|.
pub fn objective_value(objective: Objective, m: &Metrics) -> f64 {
    match objective {
        Objective::FreeEnergy => m.free_energy,
        Objective::CostJ => m.cost_j,
        Objective::Confidence => -m.logdet,
    }
}

/// Indices into `results` from best to worst by `objective`: ties keep file order, and tools
/// whose episode failed come last, in file order.
pub fn ranking(results: &[RankedTool], objective: Objective) -> Vec<usize> {
    let scored: Vec<(Option<f64>, usize)> = results
        .iter()
        .map(|r| (score(objective, r), r.row.row))
        .collect();
    order_by_score(&scored)
}

/// [`ranking`]'s order over `(score, row)` pairs, for tools held in another form (the Python
/// package's, gathered from Dask workers): the smaller score first, ties by row, tools without a
/// score (failed) last in row order.
pub fn order_by_score(scored: &[(Option<f64>, usize)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..scored.len()).collect();
    order.sort_by(|&a, &b| {
        let ((sa, ra), (sb, rb)) = (scored[a], scored[b]);
        match (sa, sb) {
            (Some(x), Some(y)) => x.total_cmp(&y),
            (Some(_), None) => Ordering::Less,
            (None, Some(_)) => Ordering::Greater,
            (None, None) => Ordering::Equal,
        }
        .then(ra.cmp(&rb))
    });
    order
}

#[cfg(test)]
mod tests {
    use super::screen::tests::candidate;
    use super::*;

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
            progress: None,
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
            prediction: Err(PredictionError::ZeroHorizon { t_end: 0.0 }),
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
}
