//! The table of named cases [`super::hostile`] runs: each class of bad input to the C ABI
//! once, the regressions among them (a destroyed, doubly destroyed, foreign or forged handle;
//! a learning rate of 1e300 or 1e-300; an initial torque of 1e300; dynamics that would be NaN
//! or infinite). Each row: its name, the call, the status the ABI's rules give, and a fragment
//! its message must hold. The rows run in order: the handles' rows are a story (a controller
//! made where a destroyed one was, ticked, destroyed, refused).

use crate::status::{
    BAD_HANDLE, INVALID_OPTION, INVALID_TASK, INVALID_TOOL, NOT_FINITE, NULL_POINTER, OK,
    UNKNOWN_TASK,
};

/// A handle a row passes.
#[derive(Debug, Clone, Copy)]
pub enum Target {
    Null,
    /// A controller of this library, destroyed.
    Destroyed,
    /// A controller made after `Destroyed` was destroyed.
    Reborn,
    /// A live controller of another library or model.
    Foreign,
    /// An integer made up.
    Integer(usize),
    /// The address of other memory, plus one.
    Misaligned,
}

/// A change to a typical array: none, NULL instead, or one entry (from the end when
/// `from_end`) or all entries set to a value.
#[derive(Debug, Clone, Copy)]
pub enum Edit {
    None,
    Null,
    One {
        from_end: bool,
        value: f64,
    },
    All(f64),
    /// The first entry set to `outside`, the tool's first parameter's value just outside its
    /// domain.
    OutOfDomain,
}

impl Edit {
    /// `typical` changed (empty for NULL).
    pub fn applied(self, typical: &[f64], outside: f64) -> Vec<f64> {
        let mut v = typical.to_vec();
        match self {
            Edit::None => {}
            Edit::Null => v.clear(),
            Edit::One { from_end, value } => {
                let i = if from_end { v.len() - 1 } else { 0 };
                v[i] = value;
            }
            Edit::All(value) => v.iter_mut().for_each(|x| *x = value),
            Edit::OutOfDomain => v[0] = outside,
        }
        v
    }
}

/// What a row calls.
#[derive(Debug, Clone, Copy)]
pub enum Call {
    /// `toolconf_controller_create` with γ, U0 on every joint, and a rate (None: one at which
    /// the tool's ticks settle).
    Create {
        gamma: f64,
        u0: f64,
        rate: Option<f64>,
    },
    Tick(Target),
    PiU(Target),
    Destroy(Target),
    /// `toolconf_dynamics` at the equilibrium state and a valid tool, changed.
    Dynamics {
        x: Edit,
        tool: Edit,
    },
    /// `toolconf_control_confidence` of a valid tool on its task (None: the model's).
    Confidence {
        task: Option<u32>,
        goals: Edit,
        precisions: Edit,
        tool: Edit,
    },
}

/// The status a row wants.
#[derive(Debug, Clone, Copy)]
pub enum Want {
    Is(i32),
    /// This status if the direct dynamics at the row's state and tool are not finite, else OK:
    /// whether a model's arithmetic overflows at an input is the model's.
    IfNotFinite(i32),
}

const fn create(gamma: f64, u0: f64, rate: Option<f64>) -> Call {
    Call::Create { gamma, u0, rate }
}

const fn confidence(task: Option<u32>, goals: Edit, precisions: Edit, tool: Edit) -> Call {
    Call::Confidence {
        task,
        goals,
        precisions,
        tool,
    }
}

const BAD: &str = "is not a live controller";
const LAST_NAN: Edit = Edit::One {
    from_end: true,
    value: f64::NAN,
};
const LAST_HUGE: Edit = Edit::One {
    from_end: true,
    value: 1e300,
};

/// The rows.
pub const CASES: &[(&str, Call, Want, &str)] = &[
    (
        "dynamics: x NULL",
        Call::Dynamics {
            x: Edit::Null,
            tool: Edit::None,
        },
        Want::Is(NULL_POINTER),
        "x is a null pointer",
    ),
    (
        "dynamics: the last velocity NaN",
        Call::Dynamics {
            x: LAST_NAN,
            tool: Edit::None,
        },
        Want::Is(NOT_FINITE),
        "] = NaN is not finite",
    ),
    (
        "dynamics: a velocity of 1e300",
        Call::Dynamics {
            x: LAST_HUGE,
            tool: Edit::None,
        },
        Want::IfNotFinite(NOT_FINITE),
        "is not finite: the inputs are too large",
    ),
    (
        "dynamics: a tool of zeros",
        Call::Dynamics {
            x: Edit::None,
            tool: Edit::All(0.0),
        },
        Want::IfNotFinite(INVALID_TOOL),
        "is not finite: invalid",
    ),
    (
        "control_confidence: task u32::MAX",
        confidence(Some(u32::MAX), Edit::None, Edit::None, Edit::None),
        Want::Is(UNKNOWN_TASK),
        "task 4294967295 is not",
    ),
    (
        "control_confidence: all precisions zero",
        confidence(None, Edit::None, Edit::All(0.0), Edit::None),
        Want::Is(INVALID_TASK),
        "",
    ),
    (
        "control_confidence: a goal of 1e300",
        confidence(
            None,
            Edit::One {
                from_end: false,
                value: 1e300,
            },
            Edit::None,
            Edit::None,
        ),
        Want::Is(INVALID_TASK),
        "goal",
    ),
    (
        "control_confidence: a precision of inf",
        confidence(
            None,
            Edit::None,
            Edit::One {
                from_end: false,
                value: f64::INFINITY,
            },
            Edit::None,
        ),
        Want::Is(NOT_FINITE),
        "precisions[0] = inf",
    ),
    (
        "control_confidence: a parameter out of its domain",
        confidence(None, Edit::None, Edit::None, Edit::OutOfDomain),
        Want::Is(INVALID_TOOL),
        "invalid",
    ),
    (
        "create: learning rate 1e300",
        create(1e300, 0.1, None),
        Want::Is(INVALID_OPTION),
        "learning rate = 1e300: must be a number in (0, 1e6]",
    ),
    (
        "create: learning rate 1e-300",
        create(1e-300, 0.1, None),
        Want::Is(INVALID_OPTION),
        "learning rate (too small",
    ),
    (
        "create: learning rate NaN",
        create(f64::NAN, 0.1, None),
        Want::Is(NOT_FINITE),
        "learning_rate = NaN",
    ),
    (
        "create: initial torque 1e300",
        create(1.0, 1e300, None),
        Want::Is(INVALID_OPTION),
        "initial torque U0 = 1e300",
    ),
    (
        "create: control rate 0",
        create(1.0, 0.1, Some(0.0)),
        Want::Is(INVALID_OPTION),
        "control rate [Hz] = 0",
    ),
    (
        "create: control rate 1e300",
        create(1.0, 0.1, Some(1e300)),
        Want::Is(INVALID_OPTION),
        "control rate [Hz] = 1e300",
    ),
    (
        "tick: a destroyed handle",
        Call::Tick(Target::Destroyed),
        Want::Is(BAD_HANDLE),
        BAD,
    ),
    (
        "destroy: a destroyed handle (a double destroy)",
        Call::Destroy(Target::Destroyed),
        Want::Is(BAD_HANDLE),
        BAD,
    ),
    (
        "tick: the controller made after it",
        Call::Tick(Target::Reborn),
        Want::Is(OK),
        "",
    ),
    (
        "tick: another library's or model's controller",
        Call::Tick(Target::Foreign),
        Want::Is(BAD_HANDLE),
        "another",
    ),
    (
        "controller_pi_u: another library's or model's controller",
        Call::PiU(Target::Foreign),
        Want::Is(BAD_HANDLE),
        "another",
    ),
    (
        "destroy: another library's or model's controller",
        Call::Destroy(Target::Foreign),
        Want::Is(BAD_HANDLE),
        "another",
    ),
    (
        "controller_pi_u: the integer 0x1000",
        Call::PiU(Target::Integer(0x1000)),
        Want::Is(BAD_HANDLE),
        BAD,
    ),
    (
        "tick: all ones",
        Call::Tick(Target::Integer(usize::MAX)),
        Want::Is(BAD_HANDLE),
        BAD,
    ),
    (
        "tick: a misaligned address of other memory",
        Call::Tick(Target::Misaligned),
        Want::Is(BAD_HANDLE),
        BAD,
    ),
    (
        "tick: NULL",
        Call::Tick(Target::Null),
        Want::Is(NULL_POINTER),
        "controller is a null pointer",
    ),
    (
        "destroy: NULL",
        Call::Destroy(Target::Null),
        Want::Is(OK),
        "",
    ),
    (
        "destroy: the controller made after it",
        Call::Destroy(Target::Reborn),
        Want::Is(OK),
        "",
    ),
    (
        "tick: it, destroyed",
        Call::Tick(Target::Reborn),
        Want::Is(BAD_HANDLE),
        BAD,
    ),
];
