//! The selection experiments (Figs. 6 and 7): trials that each draw a few tools of the population
//! and let ∫F dt, ∫J dt and ln|Π^U| choose one.
//!
//! Trial k of experiment `fig7` draws its tools from the stream seeded by
//! `derive_seed(seed, "fig7/trial/<k>")` (ChaCha8): each draw an index uniform on the
//! population, drawn again if the trial holds it already, until it has `min(T, N)` tools, in
//! the order drawn. The trials choose among the population's own episodes, so they need none of
//! their own; with a small population (a tools file of a dozen tools) they overlap, and the
//! paired test's trials are then not independent (the report says so).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::records::ToolRecord;
use super::seeds::derive_seed;
use crate::select::{first_argmin, Objective};

/// The rules, in the order of [`Trial::chosen`]: the paper's three.
pub const RULES: [Objective; 3] = Objective::ALL;

/// One trial: the tools it drew (population indices, in draw order) and each rule's choice (a
/// position in `tools`).
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    pub tools: Vec<usize>,
    pub chosen: [Option<usize>; 3],
}

impl Trial {
    /// The population index of the tool rule `r` chose.
    pub fn chosen_tool(&self, r: usize) -> Option<usize> {
        self.chosen[r].map(|i| self.tools[i])
    }
}

/// The tools of trial `k` of `experiment` (`"fig6"`, `"fig7"`).
pub fn draw(
    population: usize,
    per_trial: usize,
    seed: u64,
    experiment: &str,
    k: usize,
) -> Vec<usize> {
    let m = per_trial.min(population);
    let mut rng = ChaCha8Rng::seed_from_u64(derive_seed(seed, &format!("{experiment}/trial/{k}")));
    let mut tools = Vec::with_capacity(m);
    while tools.len() < m {
        let i = rng.random_range(0..population);
        if !tools.contains(&i) {
            tools.push(i);
        }
    }
    tools
}

/// Every rule's choice among `tools` (ties: the earlier in the trial; a tool without the
/// rule's number is passed over, as `select` does).
pub fn choose(records: &[ToolRecord], tools: &[usize]) -> [Option<usize>; 3] {
    RULES.map(|rule| {
        first_argmin(tools.iter().enumerate().filter_map(|(pos, &i)| {
            let r = &records[i];
            let score = match rule {
                Objective::FreeEnergy => r.base.as_ref().ok().map(|n| n.free_energy),
                Objective::CostJ => r.base.as_ref().ok().map(|n| n.cost_j),
                Objective::Confidence => r.logdet().map(|l| -l),
            }?;
            Some((pos, score))
        }))
    })
}

/// `count` trials of `per_trial` tools of `experiment`, with their choices.
pub fn run(
    records: &[ToolRecord],
    count: usize,
    per_trial: usize,
    seed: u64,
    experiment: &str,
) -> Vec<Trial> {
    (0..count)
        .map(|k| {
            let tools = draw(records.len(), per_trial, seed, experiment, k);
            let chosen = choose(records, &tools);
            Trial { tools, chosen }
        })
        .collect()
}

/// The measures of a chosen tool Fig. 7 compares: its confidence, task error and sensitivity.
pub const MEASURES: [&str; 3] = ["confidence", "task error", "sensitivity"];

/// Measure `m` of tool `i`.
pub fn measure(records: &[ToolRecord], m: usize, i: usize) -> Option<f64> {
    let r = &records[i];
    match m {
        0 => r.logdet(),
        1 => r.task_error(),
        _ => r.abs_change(),
    }
}

/// `values[m][r][k]`: measure m of the tool rule r chose in trial k.
pub fn chosen_values(records: &[ToolRecord], trials: &[Trial]) -> Vec<Vec<Vec<Option<f64>>>> {
    (0..MEASURES.len())
        .map(|m| {
            (0..RULES.len())
                .map(|r| {
                    trials
                        .iter()
                        .map(|t| t.chosen_tool(r).and_then(|i| measure(records, m, i)))
                        .collect()
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trials_draw_distinct_tools_and_follow_their_own_seed() {
        let t = draw(100, 10, 7, "fig7", 3);
        assert_eq!(t.len(), 10);
        let mut sorted = t.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 10);
        assert_eq!(t, draw(100, 10, 7, "fig7", 3));
        assert_ne!(t, draw(100, 10, 7, "fig7", 4));
        assert_eq!(draw(3, 10, 7, "fig7", 0).len(), 3);
    }
}
