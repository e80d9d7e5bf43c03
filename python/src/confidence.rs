//! `toolconf.confidence`: the closed-form control confidence of one tool or of many.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::{BatchError, Confidences, ModelKind};

use crate::errors::{detached, Failure};
use crate::models::model_kind;
use crate::task::task_spec;

/// Π^U = Σ Sᵀ P S + P^U (eq. control_conf) and ln|Π^U| of every tool in `params` (k × NP, row
/// major) for `spec` bound to model `kind`, with A, B and the sensitivities (the registry's
/// batch: rayon's threads share the tools, and the first bad tool in order is the error).
pub fn confidences(
    kind: ModelKind,
    spec: &TaskSpec,
    params: &[f64],
) -> Result<Confidences, Failure> {
    let task = kind.model().bind(spec).map_err(Failure::input)?;
    if let Some(e) = task.validation_error() {
        return Err(Failure::input(e));
    }
    let np = kind.parameter_names().len();
    let k = params.len() / np;
    task.confidences(params).map_err(|e| match e {
        BatchError::Tool(i, e) => {
            let row = &params[i * np..(i + 1) * np];
            let message = if k == 1 {
                e.to_string()
            } else {
                format!("tool {i} ({}): {e}", named(kind.parameter_names(), row))
            };
            match Failure::from_error(e) {
                Failure::Run(_) => Failure::Run(message),
                _ => Failure::Input(message),
            }
        }
        BatchError::Input(message) => Failure::Input(message),
        BatchError::OutOfMemory { bytes } => {
            let what = format!("confidence of {k} {} tools", kind.name());
            crate::arrays::out_of_memory::<f64>(bytes / std::mem::size_of::<f64>(), &what)
        }
    })
}

/// `m1=0.3 m2=0.4 …`, as the crate prints a tool.
pub fn named(names: &[&str], values: &[f64]) -> String {
    let parts: Vec<String> = names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n}={}", toolconf_messages::Short(*v)))
        .collect();
    parts.join(" ")
}

/// The closed-form control confidence Π^U = ∂²F/∂U² of one tool or of many, for a task.
///
/// Computed from the generated closed forms, without simulating (eq. control_conf: Π^U = Σ Sᵀ P S
/// over the task's terms, plus P^U; ln|Π^U| is the confidence term of the free energy).
///
/// Args:
///     model: a generated model's name (``toolconf.models()``), e.g. ``"arm2"``, the paper's arm.
///     params: one tool's parameters, a 1-D array in the model's parameter order (arm2:
///         m1, m2, l1, l2 in kg and m), or a 2-D array with one tool per row. Each must be a
///         number in ``toolconf.ranges()["tool_parameter"]``, [1e-6, 1e6].
///     task: ``"position"``, ``"velocity"``, ``"acceleration"`` (or ``1``, ``2``, ``3`` as
///         text), a task file's path, or a dict with a task file's keys, e.g.
///         ``{"kind": "position", "goal": {"theta": [0.78, 0.0]}, "precision": {"theta": 120.0}}``.
///
/// Returns:
///     dict: ``A`` (∂f/∂X at the equilibrium), ``B`` (∂f/∂U), ``sensitivities`` (a dict of the
///     task's ∂(term)/∂U, under the ``sensitivity`` keys of ``toolconf.terms()``),
///     ``pi_u`` (Π^U) and ``logdet`` (ln|Π^U|). For a 1-D ``params`` the matrices are 2-D arrays
///     and ``logdet`` a float; for a 2-D ``params`` every entry gains a leading axis of one row
///     per tool (``logdet`` a 1-D array). The numbers are the command line's
///     (``toolconf confidence --json``), digit for digit.
///
/// Raises:
///     ValueError: an unknown model, a parameter outside [1e-6, 1e6] (naming the
///         tool's row), a wrong number of parameters, or a bad task (naming the key), with the
///         command line's message.
///     TypeError: ``params`` of booleans, complex numbers or text.
///     MemoryError: an output that does not fit in memory (10⁶ Panda tools need 3 GB).
///     RuntimeError: a tool whose Π^U is too ill-conditioned for its ln|Π^U| to be computed
///         (its parameters span too many decades), the command line's status 1.
///
/// A batch runs on rayon's threads without holding the GIL.
#[pyfunction]
pub fn confidence<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    task: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    let spec = task_spec(task, None)?;
    let (shape, values) = crate::arrays::tool_params(kind, params)?;
    let np = kind.parameter_names().len();
    let batch = match shape.as_slice() {
        [n] if *n == np => false,
        [_, n] if *n == np => true,
        _ => {
            return Err(Failure::Input(format!(
                "params of shape {shape:?}: model {kind} takes {np} parameters ({}), as a 1-D \
                 array (one tool) or a 2-D array with one tool per row",
                kind.parameter_names().join(",")
            ))
            .into_pyerr(py))
        }
    };
    let c = detached(py, || confidences(kind, &spec, &values))?;
    to_dict(py, c, batch)
}

fn to_dict(py: Python<'_>, c: Confidences, batch: bool) -> PyResult<Bound<'_, PyDict>> {
    let array = |data: Vec<f64>, rows: usize, cols: usize| {
        let a = PyArray1::from_vec(py, data);
        if batch {
            a.reshape([c.k, rows, cols]).map(|a| a.into_any())
        } else {
            a.reshape([rows, cols]).map(|a| a.into_any())
        }
    };
    let out = PyDict::new(py);
    out.set_item("A", array(c.a, c.nx, c.nx)?)?;
    out.set_item("B", array(c.b, c.nx, c.n)?)?;
    let sensitivities = PyDict::new(py);
    for (name, rows, s) in c.sensitivities {
        sensitivities.set_item(name, array(s, rows, c.n)?)?;
    }
    out.set_item("sensitivities", sensitivities)?;
    out.set_item("pi_u", array(c.pi_u, c.n, c.n)?)?;
    if batch {
        out.set_item("logdet", PyArray1::from_vec(py, c.logdet))?;
    } else {
        out.set_item("logdet", PyFloat::new(py, c.logdet[0]))?;
    }
    Ok(out)
}
