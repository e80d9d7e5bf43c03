//! The models of the registry (`toolconf_model::registry`), by name.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf_model::registry::ModelKind;

use crate::errors::Failure;

/// A model by name, or the error naming the models there are.
pub fn model_kind(name: &str) -> Result<ModelKind, Failure> {
    name.parse().map_err(Failure::Input)
}

/// The models, generated then loaded (``load_model``): ``{name: {"title": str, "dof": int, "parameters": [str, ...],
/// "equilibrium": {"q", "q_dot", "u"}, "domains": {...}}}`` in registry order. ``parameters`` is
/// the order ``confidence`` and ``simulate`` take a tool's parameters in (masses in kg, lengths
/// in m, ...); ``dof`` is the number of joints (torques); ``equilibrium`` the state and torque
/// the model is linearised at; ``domains`` which tools are valid (each parameter's domain in
/// words, the constraints across them, the box random tools are drawn from, the defaults of the
/// parameters a tool may leave out); ``has_tip`` whether ``tip`` takes the model.
#[pyfunction]
pub fn models(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    for kind in ModelKind::all() {
        let entry = PyDict::new(py);
        entry.set_item("title", kind.title())?;
        entry.set_item("dof", kind.dof())?;
        entry.set_item("parameters", kind.parameter_names().to_vec())?;
        entry.set_item("equilibrium", crate::dynamics::equilibrium(py, kind)?)?;
        entry.set_item("domains", crate::dynamics::domains(py, kind)?)?;
        entry.set_item("has_tip", kind.has_tip())?;
        out.set_item(kind.name(), entry)?;
    }
    Ok(out)
}

/// The free-energy terms (eq. free_energy), in order: ``[{"name", "symbol", "doc", "label", "unit",
/// "goal_range", "sensitivity"}, ...]``. ``name`` keys a task's ``goal`` and ``precision`` (and
/// a trajectory's arrays in ``simulate``); ``goal_range`` names the ``ranges()`` entry its goal
/// lies in (``None``: the control's term, which has no goal); ``sensitivity`` the key of its
/// ∂(term)/∂U in ``confidence``'s ``sensitivities`` (``None`` for the control's term).
#[pyfunction]
pub fn terms(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    toolconf_model::Term::ALL
        .into_iter()
        .map(|term| {
            let entry = PyDict::new(py);
            entry.set_item("name", term.name())?;
            entry.set_item("symbol", term.symbol())?;
            entry.set_item("doc", term.doc())?;
            entry.set_item("label", term.label())?;
            entry.set_item("unit", term.unit())?;
            entry.set_item("goal_range", term.goal_range())?;
            let sensitivity = term.has_sensitivity().then(|| term.sensitivity_name());
            entry.set_item("sensitivity", sensitivity)?;
            Ok(entry)
        })
        .collect()
}

/// Every documented valid range (``docs/reference/errors.md``): ``{name: {"low", "high",
/// "low_open", "unit"}}``, e.g. ``ranges()["tool_parameter"]`` is ``[1e-6, 1e6]``, the range of
/// every tool parameter, where the generated arithmetic is known to stay finite. A value outside
/// its range raises ``ValueError`` before any work starts.
#[pyfunction]
pub fn ranges(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    for (name, range) in toolconf_model::validate::RANGES {
        let entry = PyDict::new(py);
        entry.set_item("low", range.lo)?;
        entry.set_item("high", range.hi)?;
        entry.set_item("low_open", range.lo_open)?;
        entry.set_item("unit", range.unit)?;
        out.set_item(name, entry)?;
    }
    Ok(out)
}

/// Loads a model library built by ``make model`` (its ``OUT`` folder, or the
/// ``libtoolconf_model_<model>.so`` in it) next to the built-in models, and returns the name
/// every function then takes it by: the library's own, or ``name``. No rebuild of toolconf and
/// no reinstall of this package. Loading the same file under the same name again returns the
/// same name. The library is native code that runs with the interpreter's privileges: load only
/// libraries you built (docs/reference/c-abi.md).
///
/// Raises:
///     ValueError: one line naming the file and what is wrong: not a library, a C ABI or task
///         list other than this toolconf's, a missing symbol, a name taken by another model, a
///         size (joints, tool parameters) this toolconf does not run, or too many loaded.
#[pyfunction]
#[pyo3(signature = (path, name = None))]
pub fn load_model(
    py: Python<'_>,
    path: std::path::PathBuf,
    name: Option<String>,
) -> PyResult<String> {
    py.detach(|| toolconf_model::loaded::load(&path, name.as_deref()))
        .map(|kind| kind.name().to_string())
        .map_err(|e| Failure::Input(e.to_string()).into_pyerr(py))
}

/// ``TOOLCONF_MODEL_PATH``'s entries as ``[(path, name or None), ...]``, read by the command
/// line's rule (``toolconf_model::loaded::environment_entries``): what ``import toolconf`` loads.
#[pyfunction]
#[pyo3(name = "_model_path_entries")]
pub fn model_path_entries(py: Python<'_>) -> PyResult<Vec<(String, Option<String>)>> {
    toolconf_model::loaded::environment_entries()
        .map_err(|e| Failure::Input(e.to_string()).into_pyerr(py))
}
