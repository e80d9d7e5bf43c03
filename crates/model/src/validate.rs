//! The valid range of every number a user gives toolconf, in one place: tool parameters, task
//! precisions and goals, episode and integrator options, MPC options. The command line, the
//! files it reads and the Python package all check against these constants before any work
//! starts, so a value refused in one is refused, with the same words, in the others.
//!
//! # Why these ranges
//!
//! The generated closed forms are rational functions of the tool parameters. With every
//! parameter in [10⁻ᵏ, 10ᵏ], a term of total degree d (a product like m·l², counted with its
//! exponents' absolute values: m·l² has degree 3, 1/(m·l²)² degree 6) lies within 10^(±k·d).
//! `python/tests/test_parameter_range.py` bounds every temporary of every generated function of
//! every model that way, from the IR (`generated/*.json`), by interval arithmetic on
//! log10|value|: with k = 6 and precisions |P| ≤ 10⁶, no value anywhere exceeds 10²¹⁰ (the
//! gradients of ln|Π^U| of arm3, before their division by det Π^U; A, B, the sensitivities, Π^U
//! and the dynamics stay below 10⁷⁰) or falls below 10⁻⁵⁴ unless it is 0, and Π^U's entries stay
//! below 10⁶⁷, so that ln|Π^U|'s determinant cannot overflow either. At k = 9 the bound reaches
//! 10³⁰³: no margin. Hence [1e-6, 1e6] for every tool parameter (a microgram to a thousand
//! tonnes, a micrometre to a thousand kilometres) and 1e6 for |P|. The states the generated
//! code sees, and the torques, are bounded by the episode's divergence bound (10⁶: a state
//! beyond it is a diverged simulation). `tests/parameter_range.rs` evaluates every generated
//! function at the corners of that box and checks that every output is finite.
//!
//! Starts and goals are bounded by what a joint does, not by what the arithmetic survives:
//! angles within two turns ([`JOINT_ANGLE`]), rates within 100 rad/s ([`JOINT_RATE`]),
//! accelerations within 10⁴ rad/s² ([`JOINT_ACCELERATION`]). A start far outside them is
//! valid arithmetic but no task: the controller spends the episode unwinding it, and the
//! integrator the episode's whole work budget following it
//! ([`crate::model::episode_budget`]).
//!
//! Finite is not the same as accurate: a tool whose parameters span many decades (1e-4 and 1e4
//! in one tool) can make Π^U so ill-conditioned that its determinant has no correct digit.
//! [`crate::model::logdet_of`] refuses those ([`crate::Error::IllConditioned`]) rather than
//! report a ln|Π^U| of noise; over [1e-2, 1e2] it never does.

use core::fmt;

pub use toolconf_core::validate::{
    goal_range, Range, JOINT_ACCELERATION, JOINT_ANGLE, JOINT_RATE, LEARNING_RATE, PRECISION_ENTRY,
    STATE_BOUND, TOOL_PARAMETER, TORQUE,
};

/// Any state an episode reaches, the divergence bound: past it a simulation has diverged.
/// Not an input of its own (starts are within [`JOINT_ANGLE`] and [`JOINT_RATE`]), but the
/// box over which the generated code is shown to stay finite.
pub const STATE: Range = Range::closed(-STATE_BOUND, STATE_BOUND, "");
/// The episode's end time.
pub const T_END: Range = Range::above(0.0, 1e6, "s");
/// The output step; also at most t_end, and the grid at most
/// [`crate::model::MAX_GRID_POINTS`] points.
pub const DT: Range = Range::closed(1e-6, 1e6, "s");
/// The integrator's relative tolerance: below 1e-12 the error estimate is rounding noise
/// (ode45 raises anything below 100·ε itself); above 0.1 it no longer controls the error, and
/// the run ends in "state became non-finite" rather than a result.
pub const RTOL: Range = Range::closed(1e-12, 0.1, "");
/// The integrator's absolute tolerance (same reasons; angles are of order 1 rad).
pub const ATOL: Range = Range::closed(1e-15, 1.0, "");
/// The MPC's control period.
pub const MPC_PERIOD: Range = Range::closed(1e-4, 1e3, "s");
/// The MPC's prediction horizon (also at most `MAX_HORIZON_STEPS` periods).
pub const MPC_HORIZON: Range = Range::above(0.0, 1e6, "s");
/// The MPC's torque bound per joint (`inf`: none).
pub const TORQUE_LIMIT: Range = Range::above(0.0, f64::INFINITY, "N m");
/// The MPC's disturbance-observer gain.
pub const OBSERVER_GAIN: Range = Range::above(0.0, 1.0, "");
/// A coefficient of a design constraint: with parameters in [`TOOL_PARAMETER`], a term stays
/// within 10¹², which the QP solver handles (rows are also scaled to a largest coefficient of 1).
pub const CONSTRAINT_COEFFICIENT: Range = Range::closed(-1e6, 1e6, "");
/// The constant side of a design constraint.
pub const CONSTRAINT_BOUND: Range = Range::closed(-1e12, 1e12, "");

/// Every documented range by its name (as `toolconf.ranges()` and docs/reference/errors.md give them).
pub const RANGES: [(&str, Range); 19] = [
    ("tool_parameter", TOOL_PARAMETER),
    ("precision_entry", PRECISION_ENTRY),
    ("joint_angle", JOINT_ANGLE),
    ("joint_rate", JOINT_RATE),
    ("joint_acceleration", JOINT_ACCELERATION),
    ("state", STATE),
    ("torque", TORQUE),
    ("learning_rate", LEARNING_RATE),
    ("t_end", T_END),
    ("dt", DT),
    ("rtol", RTOL),
    ("atol", ATOL),
    ("mpc_period", MPC_PERIOD),
    ("mpc_horizon", MPC_HORIZON),
    ("torque_limit", TORQUE_LIMIT),
    ("observer_gain", OBSERVER_GAIN),
    ("constraint_coefficient", CONSTRAINT_COEFFICIENT),
    ("constraint_bound", CONSTRAINT_BOUND),
    (
        "grid_points",
        Range::closed(1.0, crate::model::MAX_GRID_POINTS as f64, ""),
    ),
];

/// One tool parameter against its model's domain (`generated::validity`) and, for a "> 0"
/// domain (a mass, a length, a moment), [`TOOL_PARAMETER`]: the value, or why not in words
/// (`0 must be a number in [1e-6, 1e6]`), as [`toolconf_core::ToolN::new`] judges it.
pub fn tool_parameter(
    domain: &toolconf_generated::validity::ParameterDomain,
    value: f64,
) -> Result<f64, String> {
    if domain.is_positive() {
        TOOL_PARAMETER.check(value)
    } else if domain.contains(value) {
        Ok(value)
    } else {
        Err(format!(
            "{} must be {}",
            toolconf_messages::Short(value),
            domain.rule
        ))
    }
}

/// The last line of defence at the output: every value of `quantity` finite, else
/// [`crate::Error::NonFiniteResult`] naming the tool and the quantity, so that a front end never
/// prints NaN, inf or (in JSON) null for a number.
pub fn finite_output(
    tool: &dyn fmt::Display,
    quantity: &'static str,
    values: impl IntoIterator<Item = f64>,
) -> Result<(), crate::Error> {
    match values.into_iter().find(|v| !v.is_finite()) {
        None => Ok(()),
        Some(value) => Err(crate::Error::NonFiniteResult {
            quantity,
            tool: tool.to_string(),
            value,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_say_what_is_valid() {
        assert!(DT.contains(0.05) && !DT.contains(0.0) && !DT.contains(f64::NAN));
        assert!(!LEARNING_RATE.contains(0.0) && LEARNING_RATE.contains(1e6));
        assert!(TORQUE_LIMIT.contains(f64::INFINITY) && !TORQUE_LIMIT.contains(0.0));
        assert_eq!(
            DT.check(5e-324).unwrap_err(),
            "5e-324 must be a number in [1e-6, 1e6] s"
        );
        assert_eq!(LEARNING_RATE.to_string(), "(0, 1e6]");
        assert_eq!(
            RTOL.check(1e10).unwrap_err(),
            "1e10 must be a number in [1e-12, 0.1]"
        );
        let e = finite_output(&"arm2(m1=1)", "ln|Π^U|", [1.0, f64::NAN]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "ln|Π^U| of arm2(m1=1) is NaN, not a finite number: the run cannot report it"
        );
        assert!(finite_output(&"t", "A", [1.0, -2.0]).is_ok());
    }
}
