//! Parallel work in ordered chunks: each chunk runs on rayon, then its results are handed to a
//! sink (the CSV writer) in input order before the next chunk starts. Output is therefore the
//! same whatever the thread count, and rows reach the disk while the run goes on.

use indicatif::ProgressBar;
use rayon::prelude::*;

use toolconf_model::closed_loop::{EpisodeOptions, Metrics, Plant};
use toolconf_model::confidence::control_confidence;
use toolconf_model::{Arm, Task, TaskKind};

use super::figure_parts::arm_cells;
use super::{Context, ReproduceError};
use std::path::Path;
use toolconf_files::csv::{Cell, CsvWriter};

/// Maps `f` over `items` in parallel; `sink` sees every result, with its item's index, in input
/// order as soon as its chunk is done. The chunk size (4 per thread, at least 8) affects only when rows are written,
/// never what is written.
pub fn map_ordered<T, R, E, F, S>(
    items: &[T],
    progress: &ProgressBar,
    episodes_per_item: u64,
    f: F,
    mut sink: S,
) -> Result<Vec<R>, E>
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Sync + Send,
    S: FnMut(usize, &R) -> Result<(), E>,
{
    let chunk = (4 * rayon::current_num_threads()).max(8);
    let mut out = Vec::with_capacity(items.len());
    for part in items.chunks(chunk) {
        let results: Vec<R> = part
            .par_iter()
            .map(|item| {
                let r = f(item);
                progress.inc(episodes_per_item);
                r
            })
            .collect();
        for (k, r) in results.iter().enumerate() {
            sink(out.len() + k, r)?;
        }
        out.extend(results);
    }
    Ok(out)
}

/// One tool on one task: its confidence and one episode per option set.
#[derive(Debug, Clone)]
pub struct ToolRuns {
    pub arm: Arm,
    /// ln|Π^U|, or why it could not be computed.
    pub logdet: Result<f64, String>,
    /// One episode's metrics (or its error message) per option set, in the given order.
    pub episodes: Vec<Result<Metrics, String>>,
}

impl ToolRuns {
    pub fn logdet(&self) -> Option<f64> {
        self.logdet.as_ref().ok().copied()
    }

    pub fn metrics(&self, k: usize) -> Option<&Metrics> {
        self.episodes.get(k).and_then(|e| e.as_ref().ok())
    }

    pub fn task_error(&self, k: usize) -> Option<f64> {
        self.metrics(k).map(|m| m.task_error)
    }

    /// |task error of episode `k` − task error of episode 0| (0 is the unperturbed run).
    pub fn abs_change(&self, k: usize) -> Option<f64> {
        Some((self.task_error(k)? - self.task_error(0)?).abs()).filter(|v| v.is_finite())
    }

    /// The first error message, if any part failed ("" otherwise).
    pub fn error(&self) -> String {
        self.error_of(&(0..self.episodes.len()).collect::<Vec<_>>())
    }

    /// The first error message of the confidence or of the listed episodes.
    pub fn error_of(&self, episodes: &[usize]) -> String {
        if let Err(e) = &self.logdet {
            return e.clone();
        }
        episodes
            .iter()
            .find_map(|&k| self.episodes.get(k).and_then(|e| e.as_ref().err()))
            .cloned()
            .unwrap_or_default()
    }

    pub fn rhs_evals(&self) -> u64 {
        self.episodes
            .iter()
            .flatten()
            .map(|m| m.rhs_evals as u64)
            .sum()
    }
}

/// Runs `arm` on `task` on `plant` once per entry of `options` (sequentially: the parallelism
/// is across tools).
pub fn run_tool(arm: &Arm, task: &Task, options: &[EpisodeOptions], plant: Plant) -> ToolRuns {
    ToolRuns {
        arm: *arm,
        logdet: control_confidence(arm, task)
            .map(|c| c.logdet)
            .map_err(|e| e.to_string()),
        episodes: options
            .iter()
            .map(|o| {
                let o = EpisodeOptions {
                    record_trajectory: false,
                    ..*o
                };
                plant
                    .simulate(arm, task, &o)
                    .map(|e| e.metrics)
                    .map_err(|e| e.to_string())
            })
            .collect(),
    }
}

/// Every tool on every one of `tasks` under every option set, one row per (task, tool) written
/// to `path` as the episodes finish: the task, the tool's index, its parameters, then `cells` of
/// its runs. The results in (task, tool) order.
pub fn run_every_task(
    ctx: &Context,
    tools: &[Arm],
    tasks: &[TaskKind],
    (options, path, header): (&[EpisodeOptions], &Path, &[&str]),
    cells: impl Fn(&ToolRuns) -> Vec<Cell>,
) -> Result<Vec<(TaskKind, usize, ToolRuns)>, ReproduceError> {
    let items: Vec<(TaskKind, usize)> = tasks
        .iter()
        .flat_map(|&k| (0..tools.len()).map(move |i| (k, i)))
        .collect();
    let mut csv = CsvWriter::create(path, header)?;
    let results = map_ordered(
        &items,
        ctx.progress,
        options.len() as u64,
        |&(kind, i)| {
            let runs = run_tool(&tools[i], &Task::paper(kind), options, ctx.plant);
            (kind, i, runs)
        },
        |_, (kind, i, r)| {
            let mut row = vec![Cell::from(kind.name()), Cell::from(*i)];
            row.extend(arm_cells(&r.arm));
            row.extend(cells(r));
            csv.row(row).map_err(ReproduceError::from)
        },
    )?;
    csv.finish()?;
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_back_in_order_in_every_pool() {
        let items: Vec<u64> = (0..100).collect();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut seen = Vec::new();
                let out = map_ordered(
                    &items,
                    &ProgressBar::hidden(),
                    1,
                    |x| x * x,
                    |k, r| {
                        assert_eq!(items[k] * items[k], *r);
                        seen.push(*r);
                        Ok::<(), ()>(())
                    },
                )
                .unwrap();
                assert_eq!(out, seen);
                out
            })
        };
        assert_eq!(run(1), run(3));
        assert_eq!(run(1)[7], 49);
    }

    #[test]
    fn a_failed_episode_is_data_not_an_abort() {
        let arm = Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap();
        let task = Task::paper(toolconf_model::TaskKind::Position);
        let bad = EpisodeOptions {
            t_end: -1.0,
            ..EpisodeOptions::default()
        };
        let r = run_tool(&arm, &task, &[EpisodeOptions::default(), bad], Plant::Paper);
        assert!(r.logdet().is_some() && r.task_error(0).is_some());
        assert_eq!(r.task_error(1), None);
        assert_eq!(r.abs_change(1), None);
        assert!(r.error().contains("t_end"), "{}", r.error());
        assert_eq!(r.error_of(&[0]), "");
    }
}
