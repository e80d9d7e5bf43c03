//! A tool: the paper's 2-DOF arm with validated parameters (appendix "Tool Dynamics").

use std::fmt;
use std::str::FromStr;

use nalgebra::SVector;
use serde::Serialize;

use crate::generated::arm2;
use crate::{Error, InputMatrix, State, StateMatrix, Vector2};

/// One tool: link masses m1, m2 (kg) and lengths l1, l2 (m), each in
/// [`crate::validate::TOOL_PARAMETER`].
///
/// The fields are private so that every `Arm` in existence has passed [`Arm::new`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Arm {
    m1: f64,
    m2: f64,
    l1: f64,
    l2: f64,
}

impl Arm {
    /// Validates and builds an arm. A value outside [`crate::validate::TOOL_PARAMETER`] is an
    /// [`Error::InvalidParameter`] naming the parameter.
    pub fn new(m1: f64, m2: f64, l1: f64, l2: f64) -> Result<Self, Error> {
        for (name, value) in arm2::PARAMETER_NAMES.into_iter().zip([m1, m2, l1, l2]) {
            if !crate::validate::TOOL_PARAMETER.contains(value) {
                return Err(Error::InvalidParameter { name, value });
            }
        }
        Ok(Self { m1, m2, l1, l2 })
    }

    pub fn m1(&self) -> f64 {
        self.m1
    }
    pub fn m2(&self) -> f64 {
        self.m2
    }
    pub fn l1(&self) -> f64 {
        self.l1
    }
    pub fn l2(&self) -> f64 {
        self.l2
    }

    /// The parameter vector p = [m1 m2 l1 l2] the generated functions take.
    pub fn params(&self) -> SVector<f64, 4> {
        SVector::<f64, 4>::new(self.m1, self.m2, self.l1, self.l2)
    }

    /// The generative process Ẋ = f(X, U; p), eqs. (theta_1_ddot), (theta_2_ddot).
    pub fn dynamics(&self, x: &State, u: &Vector2) -> State {
        arm2::dynamics(x, u, &self.params())
    }

    /// A = ∂f/∂X at the equilibrium X^e = [−π/2 −π/2 0 0], U^e = 0 (eq. LTI).
    pub fn state_matrix(&self) -> StateMatrix {
        arm2::state_matrix(&self.params())
    }

    /// B = ∂f/∂U at the equilibrium (eq. LTI).
    pub fn input_matrix(&self) -> InputMatrix {
        arm2::input_matrix(&self.params())
    }

    /// The equilibrium state X^e the model is linearised at.
    pub fn equilibrium_state() -> State {
        State::from(arm2::EQUILIBRIUM_STATE)
    }
}

impl fmt::Display for Arm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use crate::display::Short;
        write!(
            f,
            "m1={} m2={} l1={} l2={}",
            Short(self.m1),
            Short(self.m2),
            Short(self.l1),
            Short(self.l2)
        )
    }
}

/// Parses `M1,M2,L1,L2`, as the command line takes an arm.
impl FromStr for Arm {
    type Err = Error;

    fn from_str(text: &str) -> Result<Self, Error> {
        let syntax = |reason: String| Error::ArmSyntax {
            text: crate::display::Clip(text).to_string(),
            reason,
        };
        let values: Vec<f64> = text
            .split(',')
            .map(|v| {
                v.trim().parse::<f64>().map_err(|e| {
                    let v = crate::display::Clip(v.trim());
                    syntax(format!("'{v}' is not a number ({e})"))
                })
            })
            .collect::<Result<_, _>>()?;
        match values[..] {
            [m1, m2, l1, l2] => Arm::new(m1, m2, l1, l2),
            _ => Err(syntax(format!("got {} values", values.len()))),
        }
    }
}

impl From<&Arm> for crate::model::Arm2Tool {
    fn from(arm: &Arm) -> Self {
        Self::from_checked(arm.params())
    }
}

impl From<&Arm> for crate::model::Arm2ExactTool {
    fn from(arm: &Arm) -> Self {
        Self::from_checked(arm.params())
    }
}
