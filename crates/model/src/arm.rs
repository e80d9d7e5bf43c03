//! A tool: the paper's 2-DOF arm with validated parameters (appendix "Tool Dynamics"), and the
//! command line's way of writing one.

use crate::model::Arm2Tool;
use crate::Error;

/// One tool of the paper's arm: link masses m1, m2 (kg) and lengths l1, l2 (m), each in
/// [`crate::validate::TOOL_PARAMETER`]. The generic [`Arm2Tool`] (`Arm::new([m1, m2, l1, l2])`); its dynamics, A, B and
/// sensitivities are its methods, Π^U is [`crate::control_confidence`].
pub type Arm = Arm2Tool;

/// Parses `M1,M2,L1,L2`, as the command line takes an arm.
pub fn parse(text: &str) -> Result<Arm, Error> {
    let syntax = |reason: String| Error::ArmSyntax {
        text: toolconf_messages::Clip(text).to_string(),
        reason,
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|v| {
            v.trim().parse::<f64>().map_err(|e| {
                let v = toolconf_messages::Clip(v.trim());
                syntax(format!("'{v}' is not a number ({e})"))
            })
        })
        .collect::<Result<_, _>>()?;
    match values[..] {
        [m1, m2, l1, l2] => Ok(Arm::new([m1, m2, l1, l2])?),
        _ => Err(syntax(format!("got {} values", values.len()))),
    }
}
