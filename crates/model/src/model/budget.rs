//! An episode's work budget: how many step attempts its integration may spend before it is
//! stopped with one message saying where and why, instead of grinding through the integrator's
//! own limit ([`toolconf_integrators::Options::max_steps`], 10⁶ attempts: 11 s of a Panda episode).
//!
//! An error-controlled method of order 5 takes steps h ∝ tol^(1/5) on a smooth solution, and a
//! task's output step dt is the time scale its user asked to see. So the budget is
//!
//!   B = max(B_min, b · n · (10⁻³ / tol)^(1/5)),   n = ⌈t_end / dt⌉,   tol = min(rtol, 10³·atol),
//!
//! with b attempts per output step at the paper's tolerances (rtol = 10⁻³, atol = 10⁻⁶, where
//! the two bind alike). The constants leave a wide margin over every episode the shipped
//! examples, tests and the paper's experiments run (the most, ode45 on the acceleration task of
//! a light tool, takes a few hundred attempts per output step); an episode that needs more is
//! following dynamics far faster than anything it reports.

use crate::validate::{JOINT_ANGLE, JOINT_RATE};
use toolconf_messages::Short;

/// b: step attempts per output step at the paper's tolerances.
pub const ATTEMPTS_PER_OUTPUT_STEP: f64 = 1000.0;
/// B_min: what even a one-step episode may spend (the transient of its first steps).
pub const MIN_ATTEMPTS: f64 = 20_000.0;

/// B for an episode of `steps` output (or control) steps at `rtol`, `atol`, at most `cap`
/// (the integrator's own limit).
pub fn episode_budget(steps: f64, rtol: f64, atol: f64, cap: usize) -> usize {
    let tol = rtol.min(1e3 * atol);
    let per_step = ATTEMPTS_PER_OUTPUT_STEP * (1e-3 / tol).max(1.0).powf(0.2);
    let budget = (per_step * steps.ceil()).max(MIN_ATTEMPTS);
    if budget >= cap as f64 {
        cap
    } else {
        budget as usize
    }
}

/// Why the budget ran out, from the state Z = [θ; θ̇; U] and the step size where it did: the
/// state had left the joints' physical range, or the steps had shrunk to a sliver of dt.
pub fn diagnosis<const N: usize>(state: &[f64], h: f64, dt: f64) -> String {
    // The joint furthest outside `range` among `values`, numbered from 1.
    let outside = |values: &[f64], range: crate::validate::Range| {
        values
            .iter()
            .enumerate()
            .filter(|(_, x)| !range.contains(**x))
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map(|(i, &x)| (i + 1, x))
    };
    if state.len() >= 2 * N {
        if let Some((i, x)) = outside(&state[N..2 * N], JOINT_RATE) {
            return format!(
                "the state left the joints' range, θ̇{i} = {x:.3e} rad/s (valid starts are in \
                 {JOINT_RATE})"
            );
        }
        if let Some((i, x)) = outside(&state[..N], JOINT_ANGLE) {
            return format!(
                "the state left the joints' range, θ{i} = {x:.3e} rad (valid starts are in \
                 {JOINT_ANGLE})"
            );
        }
    }
    format!(
        "the step size had fallen to {h:.1e} s, {} of the output step dt = {} s: the dynamics \
         are faster than the episode can follow",
        Fraction(h / dt),
        Short(dt)
    )
}

/// `1/4e5` for a small ratio.
struct Fraction(f64);

impl std::fmt::Display for Fraction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 > 0.0 && self.0 < 1.0 {
            write!(f, "1/{:.0e}", 1.0 / self.0)
        } else {
            write!(f, "{:.1e}", self.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_grows_with_the_output_steps_and_the_tolerance() {
        let cap = 1_000_000;
        // The paper's episode: 100 output steps at rtol 1e-3, atol 1e-6.
        assert_eq!(episode_budget(100.0, 1e-3, 1e-6, cap), 100_000);
        // A one-step episode still gets B_min.
        assert_eq!(episode_budget(1.0, 1e-3, 1e-6, cap), 20_000);
        // rtol 1e-8: steps 10^(5/5) = 10 times shorter.
        assert_eq!(episode_budget(100.0, 1e-8, 1e-11, cap), 1_000_000);
        assert_eq!(episode_budget(10.0, 1e-8, 1e-11, cap), 100_000);
        // A tight atol binds as a tight rtol does; loose tolerances never lower b.
        assert_eq!(episode_budget(10.0, 1e-3, 1e-11, cap), 100_000);
        assert_eq!(episode_budget(100.0, 0.1, 1.0, cap), 100_000);
        // Never past the integrator's own limit.
        assert_eq!(episode_budget(1e6, 1e-3, 1e-6, cap), cap);
    }

    #[test]
    fn the_diagnosis_names_the_joint_that_left_its_range_or_the_step_size() {
        let rate = diagnosis::<2>(&[0.1, 20.0, 3.0, -5e4, 1.0, 1.0], 1e-9, 0.05);
        assert_eq!(
            rate,
            "the state left the joints' range, θ̇2 = -5.000e4 rad/s (valid starts are in [-100, 100] rad/s)"
        );
        let angle = diagnosis::<2>(&[0.1, 20.0, 3.0, 5.0, 1.0, 1.0], 1e-9, 0.05);
        assert!(
            angle.contains("θ2 = 2.000e1 rad (valid starts are in [-4π, 4π] rad)"),
            "{angle}"
        );
        let step = diagnosis::<2>(&[0.1, 0.2, 3.0, 5.0, 1e5, 1.0], 2e-8, 0.05);
        assert!(
            step.starts_with(
                "the step size had fallen to 2.0e-8 s, 1/2e6 of the output step dt = 0.05 s"
            ),
            "{step}"
        );
    }
}
