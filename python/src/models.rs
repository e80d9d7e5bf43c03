//! The generated models, and calling the generic runtime with one model's sizes.

use std::marker::PhantomData;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf::generated;
use toolconf::model::mixed::ModelKind;
use toolconf::model::{ArmModel, Metrics};
use toolconf::task_file::TaskSpec;

use crate::confidence::Confidences;
use crate::errors::Failure;
use crate::simulate::Episode;

/// What the Python functions need of one model, with the model's sizes fixed: each generated
/// model gets one [`Ops`] (through [`ops`]), so the functions dispatch once, by name.
pub trait ModelOps: Sync {
    /// A, B, sensitivities, Π^U and ln|Π^U| of `k` tools (`params`: k × NP, row-major).
    fn confidences(&self, spec: &TaskSpec, params: &[f64]) -> Result<Confidences, Failure>;
    /// One episode of the tool `params` (NP values).
    fn episode(&self, spec: &TaskSpec, params: &[f64]) -> Result<Episode, Failure>;
    /// The metrics of every tool of `params` (k × NP) under every task of `specs`, tool-major
    /// (bad tools named from `first_tool`, or unnumbered for a single 1-D tool).
    fn batch(
        &self,
        specs: &[TaskSpec],
        params: &[f64],
        first_tool: Option<usize>,
    ) -> Result<Vec<Result<Metrics, String>>, Failure>;
}

/// [`ModelOps`] of model `M`.
pub struct Ops<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    PhantomData<M>,
);

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> ModelOps
    for Ops<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn confidences(&self, spec: &TaskSpec, params: &[f64]) -> Result<Confidences, Failure> {
        crate::confidence::confidences::<M, N, NX, NP, NZ>(spec, params)
    }

    fn episode(&self, spec: &TaskSpec, params: &[f64]) -> Result<Episode, Failure> {
        crate::simulate::episode_of::<M, N, NX, NP, NZ>(spec, params)
    }

    fn batch(
        &self,
        specs: &[TaskSpec],
        params: &[f64],
        first_tool: Option<usize>,
    ) -> Result<Vec<Result<Metrics, String>>, Failure> {
        crate::batch::batch::<M, N, NX, NP, NZ>(specs, params, first_tool)
    }
}

/// One [`Ops`] per model of the generated registry (`toolconf::for_each_model!`).
macro_rules! model_ops {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        /// The operations of `kind`.
        pub fn ops(kind: ModelKind) -> &'static dyn ModelOps {
            match kind {
                $(ModelKind::$marker => &Ops::<
                    toolconf::model::$marker,
                    { generated::$module::DOF },
                    { generated::$module::STATE_DIM },
                    { generated::$module::PARAMETER_COUNT },
                    { generated::$module::STATE_DIM + generated::$module::DOF },
                >(PhantomData),)*
            }
        }

        fn title(kind: ModelKind) -> &'static str {
            match kind { $(ModelKind::$marker => $title,)* }
        }
    };
}

toolconf::for_each_model!(model_ops);

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
        entry.set_item("title", title(kind))?;
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
