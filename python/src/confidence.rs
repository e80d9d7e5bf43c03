//! `toolconf.confidence`: the closed-form control confidence of one tool or of many.

use nalgebra::SMatrix;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat};
use rayon::prelude::*;
use toolconf::model::{ArmModel, SensitivitiesN, ToolN};
use toolconf::task_file::TaskSpec;
use toolconf::validate::finite_output;
use toolconf::Term;

use crate::errors::{detached, Failure};
use crate::models::{model_kind, ops};
use crate::task::task_spec;

/// Below this many tools a batch runs on one thread: spreading it costs more than it saves.
const MIN_TOOLS_PER_THREAD: usize = 256;
/// The results of one chunk of tools, before they are copied into the output arrays.
const CHUNK_BYTES: usize = 8 << 20;

/// The results for k tools, each array flat in C order (tool, row, column).
pub struct Confidences {
    pub k: usize,
    pub n: usize,
    pub nx: usize,
    /// A = ∂f/∂X at the equilibrium (k × NX × NX).
    pub a: Vec<f64>,
    /// B = ∂f/∂U at the equilibrium (k × NX × N).
    pub b: Vec<f64>,
    /// The task's sensitivities by name (each k × N × N); a term the task does not use is absent.
    pub sensitivities: Vec<(&'static str, Vec<f64>)>,
    /// Π^U (k × N × N).
    pub pi_u: Vec<f64>,
    /// ln|Π^U| (k).
    pub logdet: Vec<f64>,
}

/// One tool's matrices (on the stack: a batch allocates only its output arrays).
struct One<const N: usize, const NX: usize> {
    a: SMatrix<f64, NX, NX>,
    b: SMatrix<f64, NX, N>,
    sensitivities: SensitivitiesN<N>,
    pi_u: SMatrix<f64, N, N>,
    logdet: f64,
}

impl<const N: usize, const NX: usize> One<N, NX> {
    /// The last line of defence before the arrays reach Python: every number finite
    /// ([`toolconf::validate::finite_output`]).
    fn check_finite<M, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> Result<(), toolconf::Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let s = &self.sensitivities;
        let sensitivities = [s.d_theta_du, s.d_theta_dot_du, s.d_theta_ddot_du];
        let finite = |m: &[f64]| m.iter().all(|v| v.is_finite());
        if finite(self.a.as_slice())
            && finite(self.b.as_slice())
            && finite(self.pi_u.as_slice())
            && self.logdet.is_finite()
            && sensitivities.iter().flatten().all(|m| finite(m.as_slice()))
        {
            // The common case, without naming the tool: a batch checks millions.
            return Ok(());
        }
        let tool = format!("{}({tool})", M::NAME);
        finite_output(&tool, "A", self.a.iter().copied())?;
        finite_output(&tool, "B", self.b.iter().copied())?;
        for m in sensitivities.iter().flatten() {
            finite_output(&tool, "a sensitivity", m.iter().copied())?;
        }
        finite_output(&tool, "Π^U", self.pi_u.iter().copied())?;
        finite_output(&tool, "ln|Π^U|", [self.logdet])
    }
}

/// Appends `m` to `out` in C order (row by row; nalgebra stores columns).
fn push_c_order<const R: usize, const C: usize>(out: &mut Vec<f64>, m: &SMatrix<f64, R, C>) {
    out.extend((0..R).flat_map(|i| (0..C).map(move |j| m[(i, j)])));
}

/// Π^U = Σ Sᵀ P S + P^U (eq. control_conf) and ln|Π^U| of every tool in `params` (k × NP, row
/// major) for `spec` bound to model `M`, with A, B and the sensitivities; rayon's threads share
/// the tools, and the first bad tool in order is the error. The output is allocated once, before
/// the work, and fallibly (`MemoryError`, not an abort, when it does not fit); the tools are
/// computed in chunks of a few MiB of matrices, so nothing else grows with k.
pub fn confidences<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    spec: &TaskSpec,
    params: &[f64],
) -> Result<Confidences, Failure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let task = spec.task::<M, N, NX, NP, NZ>().map_err(Failure::input)?;
    let task = task.validated().map_err(Failure::input)?;
    let kind = task.task().kind;
    let k = params.len() / NP;
    // Bad input before any allocation: a bad tool is a ValueError however many tools there are.
    for (i, p) in params.chunks_exact(NP).enumerate() {
        if let Err(e) = ToolN::<M, N, NX, NP, NZ>::new(p.try_into().expect("NP values")) {
            return Err(tool_error(M::PARAMETER_NAMES, params, k, i, e.into()));
        }
    }
    let used = [Term::Theta, Term::ThetaDot, Term::ThetaDdot].map(|t| kind.uses(t));
    let mut out = Confidences::allocate(k, N, NX, used, M::NAME)?;
    let chunk = (CHUNK_BYTES / std::mem::size_of::<Result<One<N, NX>, toolconf::Error>>()).max(1);
    for (c, tools) in params.chunks(chunk * NP).enumerate() {
        let mut results: Vec<Result<One<N, NX>, toolconf::Error>> =
            crate::arrays::with_capacity(tools.len() / NP, "confidence")?;
        tools
            .par_chunks_exact(NP)
            .with_min_len(MIN_TOOLS_PER_THREAD)
            .map(|p| {
                let tool = ToolN::<M, N, NX, NP, NZ>::new(p.try_into().expect("NP values"))?;
                let c = task.control_confidence(&tool)?;
                let one = One {
                    a: tool.state_matrix(),
                    b: tool.input_matrix(),
                    sensitivities: tool.sensitivities(kind),
                    pi_u: c.pi_u,
                    logdet: c.logdet,
                };
                one.check_finite(&tool)?;
                Ok(one)
            })
            .collect_into_vec(&mut results);
        for (j, r) in results.into_iter().enumerate() {
            let i = c * chunk + j;
            let one = r.map_err(|e| tool_error(M::PARAMETER_NAMES, params, k, i, e))?;
            out.push(&one);
        }
    }
    Ok(out)
}

/// Tool `i`'s error: named by its row and parameters in a batch, bad input or a failed run.
fn tool_error<const NP: usize>(
    names: [&str; NP],
    params: &[f64],
    k: usize,
    i: usize,
    e: toolconf::Error,
) -> Failure {
    let row = &params[i * NP..(i + 1) * NP];
    let message = if k == 1 {
        e.to_string()
    } else {
        format!("tool {i} ({}): {e}", named(names, row))
    };
    match Failure::from_error(e) {
        Failure::Run(_) => Failure::Run(message),
        _ => Failure::Input(message),
    }
}

impl Confidences {
    /// Room for k tools' results (the sensitivities of the `used` terms only), or `MemoryError`.
    fn allocate(
        k: usize,
        n: usize,
        nx: usize,
        used: [bool; 3],
        model: &str,
    ) -> Result<Self, Failure> {
        // The message says what all the arrays need, not the one that failed.
        let sensitivities_used = used.iter().filter(|u| **u).count();
        let per_tool = nx * nx + nx * n + (sensitivities_used + 1) * n * n + 1;
        let total = k.saturating_mul(per_tool);
        let failed = |_| {
            let what = format!("confidence of {k} {model} tools");
            crate::arrays::out_of_memory::<f64>(total, &what)
        };
        let room = |per_tool: usize| {
            let values = k.saturating_mul(per_tool);
            crate::arrays::with_capacity(values, "").map_err(failed)
        };
        let names = ["d_theta_du", "d_theta_dot_du", "d_theta_ddot_du"];
        let mut sensitivities = Vec::new();
        for (name, used) in names.into_iter().zip(used) {
            if used {
                sensitivities.push((name, room(n * n)?));
            }
        }
        Ok(Confidences {
            k,
            n,
            nx,
            a: room(nx * nx)?,
            b: room(nx * n)?,
            sensitivities,
            pi_u: room(n * n)?,
            logdet: room(1)?,
        })
    }

    /// Appends one tool's results (within the room [`Confidences::allocate`] made).
    fn push<const N: usize, const NX: usize>(&mut self, one: &One<N, NX>) {
        push_c_order(&mut self.a, &one.a);
        push_c_order(&mut self.b, &one.b);
        push_c_order(&mut self.pi_u, &one.pi_u);
        self.logdet.push(one.logdet);
        let s = &one.sensitivities;
        // A term the task does not use has no sensitivity (the command line leaves it out too).
        let present = [s.d_theta_du, s.d_theta_dot_du, s.d_theta_ddot_du]
            .into_iter()
            .flatten();
        for ((_, all), m) in self.sensitivities.iter_mut().zip(present) {
            push_c_order(all, &m);
        }
    }
}

/// `m1=0.3 m2=0.4 …`, as the crate prints a tool.
pub fn named<const NP: usize>(names: [&str; NP], values: &[f64]) -> String {
    let parts: Vec<String> = names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n}={}", toolconf::display::Short(*v)))
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
///     task's ∂(task variable)/∂U: ``d_theta_du``, ``d_theta_dot_du``, ``d_theta_ddot_du``),
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
    let (shape, values) = crate::arrays::float_argument("params", params)?;
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
    let c = detached(py, || ops(kind).confidences(&spec, &values))?;
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
    for (name, s) in c.sensitivities {
        sensitivities.set_item(name, array(s, c.n, c.n)?)?;
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
