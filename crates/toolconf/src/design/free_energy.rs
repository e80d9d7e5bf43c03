//! The ∫F dt objective: minimise the free energy of a simulated episode over the feasible set,
//! started from the confidence optimum (the option asked for beside the confidence design: minimise ∫F by simulation).
//!
//! ∫F dt comes from an adaptive integrator, so it is only piecewise smooth in the parameters
//! (its step sequence changes discretely) and has no derived gradient: a compass search, which
//! needs only comparisons, fits. From x, try x ± step·(hi − lo)·e_j for every free parameter
//! (feasible trials only, simulated in parallel, chosen in a fixed order), move to the best
//! improvement, else halve the step; stop below MIN_STEP or after MAX_SIMULATIONS episodes.

use rayon::prelude::*;

use toolconf_model::registry::AnyTool;

use super::polytope::Polytope;
use super::{DesignError, Setting};

const INITIAL_STEP: f64 = 0.125;
const MIN_STEP: f64 = 1.0 / 1024.0;
const MAX_SIMULATIONS: usize = 400;

#[derive(Debug, Clone, PartialEq)]
pub struct FreeEnergyOptimum {
    pub x: Vec<f64>,
    pub free_energy: f64,
    pub simulations: usize,
}

fn free_energy(setting: &Setting, polytope: &Polytope, x: &[f64]) -> Option<f64> {
    let tool = AnyTool::new(setting.model, &polytope.full(x)).ok()?;
    setting
        .tasks
        .simulate(&tool)
        .ok()
        .map(|m| m.free_energy)
        .filter(|v| v.is_finite())
}

/// Compass search for the smallest ∫F dt from `start` (feasible).
pub fn minimise(
    polytope: &Polytope,
    setting: &Setting,
    start: &[f64],
) -> Result<FreeEnergyOptimum, DesignError> {
    let mut x = start.to_vec();
    let mut best = free_energy(setting, polytope, &x).ok_or_else(|| {
        DesignError::Failed(
            "the confidence optimum's episode fails, so ∫F dt cannot be searched from it".into(),
        )
    })?;
    let mut simulations = 1;
    let mut step = INITIAL_STEP;
    while step >= MIN_STEP && simulations < MAX_SIMULATIONS {
        let trials: Vec<Vec<f64>> = (0..polytope.dim())
            .flat_map(|j| [1.0, -1.0].map(|sign| (j, sign)))
            .map(|(j, sign)| {
                let mut t = x.clone();
                t[j] += sign * step * (polytope.hi[j] - polytope.lo[j]);
                t
            })
            .filter(|t| polytope.contains(t))
            .collect();
        simulations += trials.len();
        let values: Vec<Option<f64>> = trials
            .par_iter()
            .map(|t| free_energy(setting, polytope, t))
            .collect();
        let improvement = values
            .iter()
            .enumerate()
            .filter_map(|(i, v)| v.map(|v| (i, v)))
            .filter(|(_, v)| *v < best)
            .fold(None, |acc: Option<(usize, f64)>, (i, v)| match acc {
                Some((_, b)) if b <= v => acc,
                _ => Some((i, v)),
            });
        match improvement {
            Some((i, v)) => {
                x = trials[i].clone();
                best = v;
            }
            None => step *= 0.5,
        }
    }
    Ok(FreeEnergyOptimum {
        x,
        free_energy: best,
        simulations,
    })
}
