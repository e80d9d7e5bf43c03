//! The counts of an evaluation, the paper's by default, and the sweep's levels.

use serde::{Deserialize, Serialize};

/// The most tools one evaluation takes (a tools file's rows or `--sample N`): 10⁶ Panda tools are
/// about 2·10⁶ episodes, a quarter of an hour on two cores; more is a study for a cluster
/// (`toolconf.dask.reproduce`), in parts.
pub const MAX_TOOLS: usize = 1_000_000;
/// The most trials, tools per trial, sweep levels and resamples a flag takes.
pub const MAX_COUNT: usize = 100_000;

/// How many tools, trials, levels and resamples each experiment uses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The reduced counts of [`Plan::quick`] (for tests: seconds, not statistics).
    pub quick: bool,
    /// Fig. 3: the highest- and lowest-confidence tool of the first this many tools (paper: 20).
    pub highlight_sample: usize,
    /// Fig. 5: the first this many tools run at every level of the sweep (paper: 100).
    pub sweep_tools: usize,
    /// Fig. 5: the sweep's levels, ΔT scaled from 1.25 to −1.25 (paper: 11, its −1.0 … 1.0 N m
    /// in steps of 0.2 around its ΔT = −0.8 N m).
    pub sweep_levels: usize,
    /// Fig. 6: trials and tools per trial (paper: 25 × 5).
    pub grid_trials: usize,
    pub grid_tools: usize,
    /// Fig. 7: trials and tools per trial (paper: 50 × 10).
    pub trials: usize,
    pub trial_tools: usize,
    /// Bootstrap resamples per Spearman interval (2000).
    pub resamples: usize,
    /// Confidence level of the intervals (0.95).
    pub level: f64,
    /// Significance level of the paired test (0.05).
    pub alpha: f64,
}

impl Plan {
    /// The paper's counts (Results section; `toolconf reproduce` without `--model`).
    pub fn paper() -> Self {
        Self {
            quick: false,
            highlight_sample: 20,
            sweep_tools: 100,
            sweep_levels: 11,
            grid_trials: 25,
            grid_tools: 5,
            trials: 50,
            trial_tools: 10,
            resamples: 2000,
            level: 0.95,
            alpha: 0.05,
        }
    }

    /// Small counts for tests.
    pub fn quick() -> Self {
        Self {
            quick: true,
            highlight_sample: 6,
            sweep_tools: 6,
            grid_trials: 4,
            grid_tools: 3,
            trials: 6,
            trial_tools: 4,
            resamples: 200,
            ..Self::paper()
        }
    }

    /// Every count in its range: (flag, message) of the first that is not.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let counts = [
            ("--highlight-sample", self.highlight_sample, 1),
            ("--sweep-tools", self.sweep_tools, 0),
            ("--sweep-levels", self.sweep_levels, 2),
            ("--grid-trials", self.grid_trials, 1),
            ("--grid-tools", self.grid_tools, 2),
            ("--trials", self.trials, 1),
            ("--trial-tools", self.trial_tools, 2),
            ("--resamples", self.resamples, 1),
        ];
        for (flag, value, least) in counts {
            if value < least || value > MAX_COUNT {
                return Err((
                    flag,
                    format!("{value} must be a count in [{least}, {MAX_COUNT}]"),
                ));
            }
        }
        Ok(())
    }

    /// The sweep's scales of ΔT, largest first: 1.25·(L − 1 − 2j)/(L − 1) for j = 0 … L − 1,
    /// each one division of integers so that 1 and 0 are exact (the paper's levels
    /// −1.0, −0.8, …, 1.0 N m are its ΔT = −0.8 N m times these).
    pub fn sweep_scales(&self) -> Vec<f64> {
        let l = self.sweep_levels.max(2);
        let den = 4.0 * (l - 1) as f64;
        (0..l)
            .map(|j| 5.0 * (l as f64 - 1.0 - 2.0 * j as f64) / den)
            .collect()
    }
}

/// A count of tools within [1, [`MAX_TOOLS`]], or the message naming it.
pub fn check_population(n: usize, what: &str) -> Result<(), String> {
    if n == 0 {
        return Err(format!("{what}: no tools; an evaluation needs at least 1"));
    }
    if n > MAX_TOOLS {
        return Err(format!(
            "{what}: {n} tools, more than the {MAX_TOOLS} one evaluation takes (split the study, \
             or run it on a cluster with toolconf.dask.reproduce)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_sweep_is_its_levels_around_its_perturbation() {
        let s = Plan::paper().sweep_scales();
        assert_eq!(s.len(), 11);
        // The paper's ΔT levels −1.0 … 1.0 N m are −0.8 N m times these.
        let levels: Vec<f64> = s.iter().map(|k| -0.8 * k).collect();
        for (j, l) in levels.iter().enumerate() {
            assert!((l - (-1.0 + 0.2 * j as f64)).abs() < 1e-15, "{levels:?}");
        }
        assert_eq!((s[1], s[5]), (1.0, 0.0));
        assert!(Plan::paper().check().is_ok() && Plan::quick().check().is_ok());
        let plan = Plan {
            trial_tools: 1,
            ..Plan::paper()
        };
        assert_eq!(plan.check().unwrap_err().0, "--trial-tools");
        assert!(check_population(0, "--sample").is_err());
        assert!(check_population(1_000_000_000, "--sample").is_err());
    }
}
