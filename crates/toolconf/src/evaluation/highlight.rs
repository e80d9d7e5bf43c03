//! Fig. 3: the most and the least confident of the first few tools, each run without and with
//! ΔT with its trajectory recorded (the task variable over time and, on a tip task, the tip's
//! path).

use rayon::prelude::*;

use crate::rank::TaskTrace;

use super::records::ToolRecord;
use super::{Population, Setup};

/// One of the four runs.
#[derive(Debug, Clone, PartialEq)]
pub struct HighlightRun {
    /// "high" or "low" confidence.
    pub role: &'static str,
    /// The tool's population index and its ln|Π^U|.
    pub tool: usize,
    pub logdet: f64,
    /// With ΔT (else without).
    pub perturbed: bool,
    pub trace: Result<TaskTrace, String>,
}

impl HighlightRun {
    /// |value − goal| over time: the distance of the task variable to its goal.
    pub fn distance(&self) -> Option<Vec<(f64, f64)>> {
        let tr = self.trace.as_ref().ok()?;
        Some(
            tr.t.iter()
                .enumerate()
                .map(|(i, t)| {
                    let d2: f64 = tr
                        .value
                        .iter()
                        .zip(&tr.goal)
                        .map(|(v, g)| (v[i] - g) * (v[i] - g))
                        .sum();
                    (*t, d2.sqrt())
                })
                .collect(),
        )
    }
}

/// The picks and their runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Highlight {
    /// The tools the two were picked from (the population's first).
    pub sample: usize,
    pub runs: Vec<HighlightRun>,
}

/// (index, ln|Π^U|) of the tool among `records` whose confidence is `better` than every other's
/// (the first on ties).
fn extreme(records: &[ToolRecord], better: fn(f64, f64) -> bool) -> Option<(usize, f64)> {
    records
        .iter()
        .filter_map(|r| Some((r.index, r.logdet()?)))
        .fold(None, |best, (i, l)| match best {
            Some((_, b)) if !better(l, b) => best,
            _ => Some((i, l)),
        })
}

/// The most and least confident of the first `sample` tools, each traced without and with ΔT.
pub fn highlight(
    setup: &Setup,
    population: &Population,
    records: &[ToolRecord],
    sample: usize,
) -> Highlight {
    let first = &records[..sample.min(records.len())];
    let picks: Vec<(&'static str, (usize, f64))> = [
        ("high", extreme(first, |a, b| a > b)),
        ("low", extreme(first, |a, b| a < b)),
    ]
    .into_iter()
    .filter_map(|(role, pick)| Some((role, pick?)))
    .collect();
    let items: Vec<(&'static str, (usize, f64), bool)> = picks
        .iter()
        .flat_map(|&(role, pick)| [false, true].map(|p| (role, pick, p)))
        .collect();
    let runs = items
        .par_iter()
        .map(|&(role, (tool, logdet), perturbed)| {
            let tasks = if perturbed {
                &setup.perturbed
            } else {
                &setup.base
            };
            HighlightRun {
                role,
                tool,
                logdet,
                perturbed,
                trace: tasks
                    .trace(&population.tools[tool])
                    .map_err(|e| e.to_string()),
            }
        })
        .collect();
    Highlight {
        sample: first.len(),
        runs,
    }
}
