//! The models of the registry (`toolconf::registry`), by name.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf::registry::ModelKind;

use crate::errors::Failure;

/// A model by name, or the error naming the models there are.
pub fn model_kind(name: &str) -> Result<ModelKind, Failure> {
    name.parse().map_err(Failure::Input)
}

/// The generated models: ``{name: {"title": str, "dof": int, "parameters": [str, ...],
/// "equilibrium": {"q", "q_dot", "u"}, "domains": {...}}}`` in registry order. ``parameters`` is
/// the order ``confidence`` and ``simulate`` take a tool's parameters in (masses in kg, lengths
/// in m, ...); ``dof`` is the number of joints (torques); ``equilibrium`` the state and torque
/// the model is linearised at; ``domains`` which tools are valid (each parameter's domain in
/// words, the constraints across them, the box random tools are drawn from).
#[pyfunction]
pub fn models(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    for kind in ModelKind::ALL {
        let entry = PyDict::new(py);
        entry.set_item("title", kind.title())?;
        entry.set_item("dof", kind.dof())?;
        entry.set_item("parameters", kind.parameter_names().to_vec())?;
        entry.set_item("equilibrium", crate::dynamics::equilibrium(py, kind)?)?;
        entry.set_item("domains", crate::dynamics::domains(py, kind)?)?;
        out.set_item(kind.name(), entry)?;
    }
    Ok(out)
}

/// Every documented valid range (``README.md``, "Bad input"): ``{name: {"low", "high",
/// "low_open", "unit"}}``, e.g. ``ranges()["tool_parameter"]`` is ``[1e-6, 1e6]``, the range of
/// every tool parameter, where the generated arithmetic is known to stay finite. A value outside
/// its range raises ``ValueError`` before any work starts.
#[pyfunction]
pub fn ranges(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    for (name, range) in toolconf::validate::RANGES {
        let entry = PyDict::new(py);
        entry.set_item("low", range.lo)?;
        entry.set_item("high", range.hi)?;
        entry.set_item("low_open", range.lo_open)?;
        entry.set_item("unit", range.unit)?;
        out.set_item(name, entry)?;
    }
    Ok(out)
}
