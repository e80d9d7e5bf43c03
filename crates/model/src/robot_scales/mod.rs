//! The robot's own scales: what a task takes from the robot where its file says nothing.
//!
//! The paper's precisions (P = I on U, 100 on the position) and its ΔT = −0.8 N m are the scales
//! of its planar arm, whose torques are a few N m. On a real arm they are not: a goal-only tip
//! task file under P^U = I gives every Panda tool ln|Π^U| ≈ 0.0005 and progress 0.0003 (the
//! controller's prior on U outweighs the tip's error by orders of magnitude). So a URDF arm's
//! defaults come from its own scales, as the shipped task files state theirs:
//!
//! - **precision.u** on a tip task file: P^U = diag(1/σ_i²) with σ_i = [`TORQUE_SHARE_PERCENT`] (10 %) of
//!   joint i's rated torque (the URDF's `<limit effort>`, [`rated_torque`]);
//! - **precision.tip**, **tip_dot**, **tip_ddot**: 1/σ² of the tolerances [`TIP_SIGMA`] (1 mm),
//!   [`TIP_DOT_SIGMA`] (5 mm/s) and [`TIP_DDOT_SIGMA`] (0.02 m/s²);
//! - **ΔT** of `toolconf reproduce` when the task file's `[episode] perturbation` is not given:
//!   −[`TORQUE_SHARE_PERCENT`] % of each joint's rated torque ([`default_perturbation`]).
//!
//! A model that is not a URDF arm (the planar arms, the mass-spring-damper) keeps the paper's
//! precisions and ΔT = [`PAPER_PERTURBATION`] on every joint.

pub mod rated_torque;

use std::sync::Mutex;

pub use rated_torque::RatedTorques;

use crate::registry::ModelKind;
use crate::Term;

/// The share of each joint's rated torque, in percent, that is one σ of the control U, and the
/// size of the default ΔT: the 10 % the shipped tip task files state.
pub const TORQUE_SHARE_PERCENT: f64 = 10.0;

/// [`TORQUE_SHARE_PERCENT`] of `torque`, computed as the shipped files' σ are written
/// (87 N m → 8.7, not 87·0.1 = 8.700000000000001).
pub fn torque_share(torque: f64) -> f64 {
    torque * TORQUE_SHARE_PERCENT / 100.0
}
/// Default tolerance on the tip's position, m (the shipped touch tasks' σ).
pub const TIP_SIGMA: f64 = 1e-3;
/// Default tolerance on the tip's velocity, m/s (the shipped touch tasks' σ on ẏ).
pub const TIP_DOT_SIGMA: f64 = 5e-3;
/// Default tolerance on the tip's acceleration, m/s² (the shipped push-off tasks' σ).
pub const TIP_DDOT_SIGMA: f64 = 0.02;
/// The paper's ΔT, N m on every joint: the default where a model has no rated torques.
pub const PAPER_PERTURBATION: f64 = -0.8;

type Cached = (String, Result<Option<RatedTorques>, String>);
static CACHE: Mutex<Vec<Cached>> = Mutex::new(Vec::new());

/// `model`'s rated torques (read once per process); `Ok(None)` for a model that is not a URDF
/// arm, `Err` (why) when its description or URDF cannot be read.
pub fn rated_torques(model: ModelKind) -> Result<Option<RatedTorques>, String> {
    let mut cache = CACHE.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((_, found)) = cache.iter().find(|(name, _)| name == model.name()) {
        return found.clone();
    }
    let found = rated_torque::read(model.info().description, model.dof())
        .map_err(|e| format!("model {model}: {e}"));
    cache.push((model.name().to_string(), found.clone()));
    found
}

/// The rated torques of the model named `name`, if it is registered and a URDF arm.
pub fn rated_torques_of(name: &str) -> Result<Option<RatedTorques>, String> {
    match crate::registry::lookup(name) {
        Ok(model) => rated_torques(model),
        Err(_) => Ok(None),
    }
}

/// A ΔT per joint and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Perturbation {
    /// N m (N for a prismatic joint), one per joint.
    pub values: Vec<f64>,
    /// "−10 % of each joint's rated torque (…)", "the task file's [episode] perturbation", …
    pub source: String,
}

/// The ΔT `toolconf reproduce` applies when the task states none: −10 % of each joint's rated
/// torque on a URDF arm, the paper's −0.8 N m on every joint otherwise.
pub fn default_perturbation(model: ModelKind) -> Result<Perturbation, String> {
    Ok(match rated_torques(model)? {
        Some(rated) => Perturbation {
            values: rated.values.iter().map(|t| -torque_share(*t)).collect(),
            source: format!(
                "the default, −{TORQUE_SHARE_PERCENT} % of each joint's rated torque ({})",
                rated.source
            ),
        },
        None => Perturbation {
            values: vec![PAPER_PERTURBATION; model.dof()],
            source: format!(
                "the default, the paper's {PAPER_PERTURBATION} N m on every joint (model {model} \
                 states no rated torques)"
            ),
        },
    })
}

/// The default precision of `term` on a tip task file that does not give it, for a URDF arm
/// with rated torques `rated`: the diagonal, one entry per component (the tip's, or U's).
pub fn default_precision(term: Term, rated: &RatedTorques, tip_dim: usize) -> Option<Vec<f64>> {
    let sigma = match term {
        Term::U => {
            return Some(
                rated
                    .values
                    .iter()
                    .map(|t| 1.0 / torque_share(*t).powi(2))
                    .collect(),
            )
        }
        Term::Tip => TIP_SIGMA,
        Term::TipDot => TIP_DOT_SIGMA,
        Term::TipDdot => TIP_DDOT_SIGMA,
        _ => return None,
    };
    Some(vec![1.0 / (sigma * sigma); tip_dim])
}

/// The default precision of `term` on a URDF arm's tip task file, in words (for reports).
pub fn default_words(term: Term) -> Option<String> {
    let sigma = match term {
        Term::U => format!("{TORQUE_SHARE_PERCENT} % of each joint's rated torque"),
        Term::Tip => format!("{} mm", TIP_SIGMA * 1e3),
        Term::TipDot => format!("{} mm/s", TIP_DOT_SIGMA * 1e3),
        Term::TipDdot => format!("{} m/s²", TIP_DDOT_SIGMA),
        _ => return None,
    };
    Some(format!("1/σ² with σ = {sigma}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_follow_the_rated_torques() {
        let rated = RatedTorques {
            values: vec![87.0, 12.0],
            source: String::new(),
        };
        let u = default_precision(Term::U, &rated, 3).unwrap();
        // The shipped task files' entries, 1/σ² with σ = 8.7 and 1.2 N m.
        assert_eq!(u, [0.013211784912141634, 0.6944444444444444]);
        assert_eq!(
            default_precision(Term::Tip, &rated, 3).unwrap(),
            vec![1e6; 3]
        );
        assert_eq!(default_precision(Term::Theta, &rated, 3), None);
        let panda = default_perturbation(ModelKind::Panda).unwrap();
        assert_eq!(panda.values[0], -8.7);
        assert!(panda.source.contains("panda.urdf"), "{}", panda.source);
        let arm2 = default_perturbation(ModelKind::Arm2).unwrap();
        assert_eq!(arm2.values, [-0.8, -0.8]);
    }
}
