//! The generated models whose tool is a URDF tool at a flange: what `toolconf tool --urdf`'s
//! row may name as its `model` (the reader itself is the crate toolconf-tool-urdf).

use toolconf_messages::Clip;

/// The generated models whose tool is a URDF tool at a flange (their parameters are the row's
/// `tool_mass`, ...: `panda`, `ur5`).
pub fn flange_models() -> Vec<&'static str> {
    super::ModelKind::all()
        .iter()
        .filter(|m| m.parameter_names().contains(&"tool_mass"))
        .map(|m| m.name())
        .collect()
}

/// The row's `model`: one of [`flange_models`] (case and blanks ignored), or why not.
pub fn flange_model(name: &str) -> Result<&'static str, String> {
    let models = flange_models();
    match super::lookup(name) {
        Ok(kind) if models.contains(&kind.name()) => Ok(kind.name()),
        _ => Err(format!(
            "'{}' is not a model with a tool at a URDF flange ({})",
            Clip(name),
            models.join(", ")
        )),
    }
}
