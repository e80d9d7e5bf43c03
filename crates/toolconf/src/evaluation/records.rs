//! Each tool's episodes: the work of an evaluation, tool by tool, in parallel and in order.
//!
//! A tool's record is a function of the tool and the [`Setup`] alone, so the records of a
//! population can be computed in blocks anywhere (`toolconf.dask.reproduce`'s workers) and put
//! back in order: [`ToolRecord::to_wire`] carries every number as its bits, so a record read
//! back ([`ToolRecord::from_wire`]) is the same to the last bit.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use toolconf_model::model::Metrics;
use toolconf_model::registry::AnyTool;

use super::Setup;

/// What the experiments read of one episode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numbers {
    pub task_error: f64,
    /// ∫F dt and ∫J dt.
    pub free_energy: f64,
    pub cost_j: f64,
    /// On a position task, 1 − e(T)/e(0) ([`Metrics::progress`]).
    pub progress: Option<f64>,
    pub rhs_evals: u64,
}

impl From<&Metrics> for Numbers {
    fn from(m: &Metrics) -> Self {
        Self {
            task_error: m.task_error,
            free_energy: m.free_energy,
            cost_j: m.cost_j,
            progress: m.progress,
            rhs_evals: m.rhs_evals as u64,
        }
    }
}

/// One episode's numbers, or why it failed.
pub type Run = Result<Numbers, String>;

/// One tool's confidence and episodes.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolRecord {
    /// Its place in the population (0-based).
    pub index: usize,
    /// ln|Π^U| (eq. control_conf), or why it has none.
    pub logdet: Result<f64, String>,
    /// Without ΔT.
    pub base: Run,
    /// With the task's ΔT.
    pub perturbed: Run,
    /// For the first `sweep_tools` tools, one per sweep level (the levels 0 and 1 copied from
    /// `base` and `perturbed`); empty for the others.
    pub sweep: Vec<Run>,
}

impl ToolRecord {
    pub fn logdet(&self) -> Option<f64> {
        self.logdet.as_ref().ok().copied()
    }

    pub fn task_error(&self) -> Option<f64> {
        self.base.as_ref().ok().map(|n| n.task_error)
    }

    pub fn perturbed_error(&self) -> Option<f64> {
        self.perturbed.as_ref().ok().map(|n| n.task_error)
    }

    /// |task error(ΔT) − task error(0)|: Fig. 4's reliability under ΔT.
    pub fn abs_change(&self) -> Option<f64> {
        Some((self.perturbed_error()? - self.task_error()?).abs()).filter(|v| v.is_finite())
    }

    /// |task error at sweep level k − task error(0)|.
    pub fn sweep_change(&self, k: usize) -> Option<f64> {
        let at = self.sweep.get(k)?.as_ref().ok()?.task_error;
        Some((at - self.task_error()?).abs()).filter(|v| v.is_finite())
    }

    /// The first reason something of this tool failed ("" if nothing did).
    pub fn error(&self) -> String {
        let runs = [&self.base, &self.perturbed];
        self.logdet
            .as_ref()
            .err()
            .or_else(|| runs.iter().find_map(|r| r.as_ref().err()))
            .or_else(|| self.sweep.iter().find_map(|r| r.as_ref().err()))
            .cloned()
            .unwrap_or_default()
    }

    /// Episodes simulated for this record and their right-hand-side evaluations.
    pub fn work(&self, setup: &Setup) -> (u64, u64) {
        let own = |k: &usize| setup.own_level(*k);
        let runs = [&self.base, &self.perturbed]
            .into_iter()
            .chain((0..self.sweep.len()).filter(own).map(|k| &self.sweep[k]));
        runs.fold((0, 0), |(e, r), run| {
            (e + 1, r + run.as_ref().map_or(0, |n| n.rhs_evals))
        })
    }
}

/// One tool: its ln|Π^U|, its episodes without and with ΔT, and the sweep if `sweep` is set.
fn run_tool(setup: &Setup, index: usize, tool: &AnyTool, sweep: bool) -> ToolRecord {
    let run = |tasks: &crate::rank::ModelTasks| -> Run {
        tasks
            .simulate(tool)
            .map(|m| Numbers::from(&m))
            .map_err(|e| e.to_string())
    };
    let base = run(&setup.base);
    let perturbed = run(&setup.perturbed);
    let sweep = match sweep {
        false => Vec::new(),
        true => (0..setup.scales.len())
            .map(|k| match (setup.own_level(k), setup.scales[k] == 0.0) {
                (true, _) => run(setup.level(k)),
                (false, true) => base.clone(),
                (false, false) => perturbed.clone(),
            })
            .collect(),
    };
    ToolRecord {
        index,
        logdet: setup.base.logdet(tool).map_err(|e| e.to_string()),
        base,
        perturbed,
        sweep,
    }
}

/// The records of `tools`, the population's tools `first`, `first + 1`, …: each simulated on
/// rayon's threads, the sweep for those among the first `sweep_tools`. `done` hears of each
/// finished tool's episodes (a progress bar). Results are in order whatever the thread count.
pub fn run_tools(
    setup: &Setup,
    tools: &[AnyTool],
    first: usize,
    sweep_tools: usize,
    done: &(dyn Fn(u64) + Sync),
) -> Vec<ToolRecord> {
    tools
        .par_iter()
        .enumerate()
        .map(|(i, tool)| {
            let index = first + i;
            let sweep = index < sweep_tools;
            let record = run_tool(setup, index, tool, sweep);
            done(2 + if sweep { setup.own_levels() as u64 } else { 0 });
            record
        })
        .collect()
}

/// A record as it travels between processes: every number as its IEEE-754 bits.
#[derive(Serialize, Deserialize)]
struct Wire {
    index: usize,
    logdet: Result<u64, String>,
    runs: Vec<Result<[u64; 5], String>>,
}

/// The bits of an absent progress: a NaN, which no progress is.
const NO_PROGRESS: u64 = 0x7ff8_dead_0000_0001;

fn pack(run: &Run) -> Result<[u64; 5], String> {
    run.as_ref().map_err(Clone::clone).map(|n| {
        [
            n.task_error.to_bits(),
            n.free_energy.to_bits(),
            n.cost_j.to_bits(),
            n.progress.map_or(NO_PROGRESS, f64::to_bits),
            n.rhs_evals,
        ]
    })
}

fn unpack(run: Result<[u64; 5], String>) -> Run {
    run.map(|b| Numbers {
        task_error: f64::from_bits(b[0]),
        free_energy: f64::from_bits(b[1]),
        cost_j: f64::from_bits(b[2]),
        progress: (b[3] != NO_PROGRESS).then(|| f64::from_bits(b[3])),
        rhs_evals: b[4],
    })
}

impl ToolRecord {
    /// The record as JSON text whose numbers are bits: exact across processes.
    pub fn to_wire(&self) -> String {
        let runs = [&self.base, &self.perturbed]
            .into_iter()
            .chain(&self.sweep)
            .map(pack)
            .collect();
        let wire = Wire {
            index: self.index,
            logdet: self
                .logdet
                .as_ref()
                .map(|v| v.to_bits())
                .map_err(Clone::clone),
            runs,
        };
        serde_json::to_string(&wire).expect("a record is plain data")
    }

    /// A record from [`ToolRecord::to_wire`]'s text.
    pub fn from_wire(text: &str) -> Result<Self, String> {
        let wire: Wire = serde_json::from_str(text)
            .map_err(|e| format!("not a record of an evaluation: {e}"))?;
        let mut runs = wire.runs.into_iter().map(unpack);
        let (Some(base), Some(perturbed)) = (runs.next(), runs.next()) else {
            return Err("not a record of an evaluation: fewer than two runs".into());
        };
        Ok(Self {
            index: wire.index,
            logdet: wire.logdet.map(f64::from_bits),
            base,
            perturbed,
            sweep: runs.collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record read back from its wire text is the record, to the last bit (NaN-free numbers,
    /// a missing progress, failed runs and an empty sweep included).
    #[test]
    fn a_record_travels_exactly() {
        let n = |x: f64| Numbers {
            task_error: x,
            free_energy: x / 3.0,
            cost_j: -x * 1e-300,
            progress: (x > 1.0).then_some(x.sqrt()),
            rhs_evals: 12345,
        };
        let record = ToolRecord {
            index: 7,
            logdet: Ok(-7.912606123456789),
            base: Ok(n(0.1 + 0.2)),
            perturbed: Err("simulation of panda(…) diverged".into()),
            sweep: vec![Ok(n(2.0f64.sqrt())), Err("x".into()), Ok(n(5e-324))],
        };
        let back = ToolRecord::from_wire(&record.to_wire()).unwrap();
        assert_eq!(back, record);
        let bits = |r: &Run| {
            r.as_ref()
                .map(|n| (n.task_error.to_bits(), n.cost_j.to_bits()))
                .ok()
        };
        assert_eq!(bits(&back.base), bits(&record.base));
        let plain = ToolRecord {
            logdet: Err("no Π^U".into()),
            sweep: vec![],
            ..record
        };
        assert_eq!(ToolRecord::from_wire(&plain.to_wire()).unwrap(), plain);
        assert!(ToolRecord::from_wire("{}").is_err());
    }
}
