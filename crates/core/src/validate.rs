//! The valid ranges the core checks itself: tool parameters ([`crate::ToolN::new`]), goals and
//! precisions ([`crate::TaskN::validate`]). Why these ranges (the generated arithmetic's
//! exponents, bounded from the IR) is in the runtime's `toolconf_model::validate`, which adds the
//! ranges of the episode, integrator, MPC and design options and re-exports these.

use core::f64::consts::PI;
use core::fmt;

use crate::display::Short;

/// An interval of valid values, `[lo, hi]` or `(lo, hi]`, with the unit named in messages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
    /// `(lo, hi]`: lo itself is not valid (a step or a rate of 0).
    pub lo_open: bool,
    pub unit: &'static str,
}

impl Range {
    pub const fn closed(lo: f64, hi: f64, unit: &'static str) -> Self {
        Self {
            lo,
            hi,
            lo_open: false,
            unit,
        }
    }

    pub const fn above(lo: f64, hi: f64, unit: &'static str) -> Self {
        Self {
            lo,
            hi,
            lo_open: true,
            unit,
        }
    }

    /// Whether `x` is in the range (never NaN).
    pub fn contains(&self, x: f64) -> bool {
        let above_lo = if self.lo_open {
            x > self.lo
        } else {
            x >= self.lo
        };
        above_lo && x <= self.hi
    }

    /// `x` if it is in the range, else the reason in words: `0 must be a number in [1e-6, 1e6] s`.
    #[cfg(feature = "std")]
    pub fn check(&self, x: f64) -> Result<f64, std::string::String> {
        if self.contains(x) {
            Ok(x)
        } else {
            Err(std::format!("{} must be a number in {self}", Short(x)))
        }
    }
}

/// A range's end: `1e6` rather than `1000000`, `4π` rather than `12.566370614359172`.
struct End(f64);

impl fmt::Display for End {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let multiple = (1..=16).find(|&k| f64::from(k) * PI == self.0.abs());
        if let Some(k) = multiple {
            write!(f, "{}{k}π", if self.0 < 0.0 { "-" } else { "" })
        } else if self.0.is_finite() && self.0.abs() >= 1e4 {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", Short(self.0))
        }
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let open = if self.lo_open { "(" } else { "[" };
        write!(f, "{open}{}, {}]", End(self.lo), End(self.hi))?;
        if !self.unit.is_empty() {
            write!(f, " {}", self.unit)?;
        }
        Ok(())
    }
}

/// Every tool parameter, in its SI unit (kg, m, N/m, N s/m): see the runtime's `toolconf_model::validate` for why.
pub const TOOL_PARAMETER: Range = Range::closed(1e-6, 1e6, "");
/// Each entry of a precision matrix (a precision is also symmetric positive semi-definite).
pub const PRECISION_ENTRY: Range = Range::closed(-1e6, 1e6, "");
/// The episode's divergence bound: a state past it is a diverged simulation
/// (the runtime's `DIVERGENCE_BOUND`).
pub const STATE_BOUND: f64 = 1e6;
/// Torques, the initial torque U0 and the perturbation ΔT: the divergence bound, over which
/// the generated arithmetic is shown to stay finite (the runtime's `toolconf_model::validate`).
pub const TORQUE: Range = Range::closed(-STATE_BOUND, STATE_BOUND, "N m");
/// The controller's learning rate γ.
pub const LEARNING_RATE: Range = Range::above(0.0, 1e6, "");
/// The on-robot controller's control rate: up to 1 MHz, 25 times the fastest loop a robot's
/// fieldbus runs (EtherCAT drives close their loops at up to 40 kHz; the Panda's and the
/// UR5's controllers tick at 1 kHz and 500 Hz). A faster rate only makes each tick's step
/// γ/rate smaller, until it is lost to rounding.
pub const CONTROL_RATE: Range = Range::above(0.0, 1e6, "Hz");
/// Joint angles, the initial θ₀ and the goal θ_g, in rad (m for a prismatic joint or the
/// mass-spring-damper): |θ| ≤ 4π, two full turns either way of the zero pose. Every revolute
/// joint of the shipped arms travels less (the UR5's ±2π is the widest), and the controller's
/// error θ − θ_g is not wrapped, so an angle further out asks the arm to unwind whole turns
/// rather than reach a pose: with θ₀ = 10⁶ an episode spent 10⁶ step attempts doing so.
pub const JOINT_ANGLE: Range = Range::closed(-4.0 * PI, 4.0 * PI, "rad");
/// Joint rates, the initial θ̇₀ and the goal θ̇_g: |θ̇| ≤ 100 rad/s (about 950 rpm), some
/// thirty times the fastest rated joint of the shipped arms (the UR5's and Panda's wrists turn
/// at ≈ 3 rad/s).
pub const JOINT_RATE: Range = Range::closed(-100.0, 100.0, "rad/s");
/// Joint accelerations, the goal θ̈_g: |θ̈| ≤ 10⁴ rad/s², enough to reach [`JOINT_RATE`]'s
/// bound from rest in 10 ms (the shipped arms are rated at 10-40 rad/s²).
pub const JOINT_ACCELERATION: Range = Range::closed(-1e4, 1e4, "rad/s²");

/// The tool tip's position in the base frame, a goal y_g of a tip task: |y| ≤ 10 m in each
/// component, five times the reach of the largest shipped arm (the UR5's 0.85 m, the Panda's
/// 0.855 m, plus a tool): a point an arm cannot touch is a valid goal it moves towards, but one
/// further out only scales the error, which the generated arithmetic's range bounds.
pub const TIP_POSITION: Range = Range::closed(-10.0, 10.0, "m");
/// The tool tip's velocity, a goal ẏ_g: |ẏ| ≤ 10 m/s in each component, several times an
/// industrial arm's rated tool speed (the Panda's 2 m/s, the UR5's ≈ 1 m/s).
pub const TIP_VELOCITY: Range = Range::closed(-10.0, 10.0, "m/s");
/// The tool tip's acceleration, a goal ÿ_g: |ÿ| ≤ 100 m/s² in each component, ten times the
/// gravity an arm lifts against and above the Panda's rated 13 m/s² Cartesian acceleration.
pub const TIP_ACCELERATION: Range = Range::closed(-100.0, 100.0, "m/s²");

/// The ranges a goal may be checked against, by the name `derive/tasks.toml` gives a term's
/// `goal_range` (and `toolconf.ranges()` its key).
pub const GOAL_RANGES: [(&str, Range); 6] = [
    ("joint_angle", JOINT_ANGLE),
    ("joint_rate", JOINT_RATE),
    ("joint_acceleration", JOINT_ACCELERATION),
    ("tip_position", TIP_POSITION),
    ("tip_velocity", TIP_VELOCITY),
    ("tip_acceleration", TIP_ACCELERATION),
];

/// The range a goal of `term` must lie in; `None` for a term without a goal (the control's).
pub fn goal_range(term: crate::generated::Term) -> Option<Range> {
    let name = term.goal_range()?;
    GOAL_RANGES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, r)| *r)
}

#[cfg(test)]
mod goal_range_tests {
    use crate::generated::Term;

    #[test]
    fn every_term_with_a_goal_names_a_known_range() {
        for term in Term::ALL {
            assert_eq!(super::goal_range(term).is_some(), term.has_goal(), "{term}");
        }
    }
}
