//! `toolconf.dynamics`: a robot's own rigid-body dynamics Ẋ = [q̇; q̈], for one state or a batch;
//! `toolconf.tip`: its tool's tip and the tip's Jacobian.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf_model::registry::{BatchError, ModelKind, Rows};

use crate::errors::{detached, Failure};
use crate::models::model_kind;

/// An argument of shape (width,) or (k, width): its rows and k (None for 1-D).
fn rows<'a>(
    name: &str,
    shape: &[usize],
    data: &'a [f64],
    width: usize,
    kind: ModelKind,
    what: &str,
) -> Result<(Rows<'a>, Option<usize>), Failure> {
    match shape {
        [w] if *w == width => Ok((
            Rows {
                data,
                width,
                shared: true,
            },
            None,
        )),
        [k, w] if *w == width => Ok((
            Rows {
                data,
                width,
                shared: false,
            },
            Some(*k),
        )),
        _ => Err(Failure::Input(format!(
            "{name} of shape {shape:?}: model {kind} takes {width} {what}, as a 1-D array or a \
             2-D array with one row per state"
        ))),
    }
}

/// The robot's own rigid-body dynamics, Ẋ = [q̇; q̈] with M(q) q̈ + C(q, q̇) q̇ + g(q) = U.
///
/// U is the joint torques themselves: for the URDF arms (``panda``, ``ur5``) this is the arm with
/// the tool fixed at its flange, without the joint impedance their controllers' plant adds (what
/// Pinocchio's ``aba`` computes); for the other models, whose plant is their rigid-body dynamics,
/// it is that plant.
///
/// Args:
///     model: a generated model's name (``toolconf.models()``).
///     params: the tool's parameters in the model's order, a 1-D array (one tool for every
///         state) or a 2-D array with one tool per state; each tool must obey the model's rule
///         (``toolconf.models()[model]["domains"]``).
///     state: X = [q; q̇], a 1-D array of the model's state size, or a 2-D array of one state
///         per row.
///     control: U (N m per joint), 1-D (the same for every state) or 2-D (one row per state).
///
/// Returns:
///     numpy.ndarray: Ẋ, of shape (state size,) when every argument is 1-D, else (k, state size)
///     for k rows.
///
/// Raises:
///     ValueError: an unknown model, shapes that do not fit it or each other, a tool outside
///         the model's rule (naming the parameter or constraint, and the row), a non-finite state
///         or control, or a state where the dynamics are not finite.
///     TypeError: an argument of booleans, complex numbers or text.
///     MemoryError: a batch that does not fit in memory.
///
/// A batch runs on rayon's threads without holding the GIL.
#[pyfunction]
pub fn dynamics<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    state: &Bound<'py, PyAny>,
    control: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    let (n, np) = (kind.dof(), kind.parameter_names().len());
    let nx = 2 * n;
    let read = crate::arrays::float_argument;
    let (p_shape, p_data) = crate::arrays::tool_params(kind, params)?;
    let (x_shape, x_data) = read("state", state)?;
    let (u_shape, u_data) = read("control", control)?;
    let shapes = (p_shape, x_shape, u_shape);
    let out =
        detached(py, || {
            let (p, kp) = rows("params", &shapes.0, &p_data, np, kind, "tool parameters")?;
            let (x, kx) = rows(
                "state",
                &shapes.1,
                &x_data,
                nx,
                kind,
                "state entries [q; q_dot]",
            )?;
            let (u, ku) = rows("control", &shapes.2, &u_data, n, kind, "torques")?;
            let counts: Vec<usize> = [kp, kx, ku].into_iter().flatten().collect();
            if counts.windows(2).any(|w| w[0] != w[1]) {
                return Err(Failure::Input(format!(
                "params, state and control have {} rows: the 2-D ones must have the same number",
                counts.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")
            )));
            }
            let k = counts.first().copied();
            let rows = k.unwrap_or(1);
            let what = format!("dynamics of {rows} states");
            let mut out = crate::arrays::zeros(rows.saturating_mul(nx), &what)?;
            kind.model()
                .rigid_body_dynamics(rows, &p, &x, &u, &mut out)
                .map_err(|e| batch_failure(e, &what))?;
            Ok((out, k))
        })?;
    let (data, k) = out;
    let array = PyArray1::from_vec(py, data);
    match k {
        None => Ok(array.into_any()),
        Some(k) => Ok(array.reshape([k, nx])?.into_any()),
    }
}

/// The tool's tip (tool-centre point) y(q) in the robot's base frame and its Jacobian
/// J = ∂y/∂q, for one joint configuration or a batch; with joint velocities ``q_dot``, also the
/// tip's acceleration at zero joint acceleration J̇(q, q̇) q̇, so that ÿ = J q̈ + J̇ q̇.
///
/// For the URDF arms (``panda``, ``ur5``) the tip is the tool's ``tool_tip_x/y/z`` offset in the
/// flange frame, carried through the arm's forward kinematics; J is the linear part of
/// Pinocchio's ``computeFrameJacobian`` at that frame in ``LOCAL_WORLD_ALIGNED``, and J̇ q̇ the
/// linear part of its ``getFrameClassicalAcceleration`` at zero joint acceleration.
///
/// Args:
///     model: a generated model's name with a tip (``toolconf.models()[m]["has_tip"]``).
///     params: the tool's parameters (1-D, one tool for every q, or 2-D, one per q), each tool
///         obeying the model's rule; a URDF tool may leave out its trailing products of inertia
///         and tip (zero).
///     q: the joint positions, 1-D (one configuration) or 2-D (one per row).
///     q_dot: optional joint velocities, of q's shape.
///
/// Returns:
///     dict: ``position`` of shape (3,) (m) and ``jacobian`` of shape (3, n) for 1-D arguments,
///     else (k, 3) and (k, 3, n); with ``q_dot``, ``bias`` (J̇ q̇, m/s²) of ``position``'s shape.
///
/// Raises:
///     ValueError: an unknown model or one without a tip, shapes that do not fit, a tool outside
///         the model's rule (naming the parameter and the row), a non-finite q or q_dot.
///     TypeError: an argument of booleans, complex numbers or text.
///     MemoryError: a batch that does not fit in memory.
#[pyfunction]
#[pyo3(signature = (model, params, q, q_dot=None))]
pub fn tip<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    q_dot: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    if !kind.has_tip() {
        return Err(Failure::Input(format!(
            "model {kind} has no tip (its description gives none)"
        ))
        .into_pyerr(py));
    }
    let params = crate::arrays::tool_params(kind, params)?;
    let q = crate::arrays::float_argument("q", q)?;
    let rates = q_dot
        .map(|v| crate::arrays::float_argument("q_dot", v))
        .transpose()?;
    if let Some((shape, _)) = &rates {
        if *shape != q.0 {
            return Err(Failure::Input(format!(
                "q_dot of shape {shape:?}: it must have q's shape {:?}",
                q.0
            ))
            .into_pyerr(py));
        }
    }
    let tips = detached(py, || tips(kind, &params, &q, rates.as_ref()))?;
    tips_dict(py, tips, kind.dof())
}

/// An array argument as read from Python: its shape and its values in row-major order.
type Argument = (Vec<usize>, Vec<f64>);

/// What [`tip`] computes, flat, before it is shaped into arrays: `rows` is the batch's size,
/// or None for 1-D arguments.
struct Tips {
    position: Vec<f64>,
    jacobian: Vec<f64>,
    bias: Option<Vec<f64>>,
    rows: Option<usize>,
}

/// The tips of the tools `params` at the configurations `q` (and, with `q_dot`, J̇ q̇): the
/// work [`tip`] does without the GIL, its arguments' rows checked against each other.
fn tips(
    kind: ModelKind,
    params: &Argument,
    q: &Argument,
    q_dot: Option<&Argument>,
) -> Result<Tips, Failure> {
    let (n, np) = (kind.dof(), kind.parameter_names().len());
    let (p, kp) = rows("params", &params.0, &params.1, np, kind, "tool parameters")?;
    let (qs, kq) = rows("q", &q.0, &q.1, n, kind, "joint positions")?;
    if let (Some(a), Some(b)) = (kp, kq) {
        if a != b {
            return Err(Failure::Input(format!(
                "params and q have {a} and {b} rows: the 2-D ones must have the same number"
            )));
        }
    }
    let k = kq.or(kp);
    let count = k.unwrap_or(1);
    let what = format!("tips of {count} configurations");
    let mut position = crate::arrays::zeros(count.saturating_mul(3), &what)?;
    let mut jacobian = crate::arrays::zeros(count.saturating_mul(3 * n), &what)?;
    // A 1-D q (or q_dot) is one configuration shared by every tool.
    let model = kind.model();
    model
        .tip(count, &p, &qs, &mut position, &mut jacobian)
        .map_err(|e| batch_failure(e, &what))?;
    let bias = match q_dot {
        None => None,
        Some((shape, data)) => {
            let (v, _) = rows("q_dot", shape, data, n, kind, "joint velocities")?;
            let mut bias = crate::arrays::zeros(count.saturating_mul(3), &what)?;
            model
                .tip_bias(count, &p, &qs, &v, &mut bias)
                .map_err(|e| batch_failure(e, &what))?;
            Some(bias)
        }
    };
    Ok(Tips {
        position,
        jacobian,
        bias,
        rows: k,
    })
}

/// [`tip`]'s dict: `position` (3,) or (k, 3), `jacobian` (3, n) or (k, 3, n), and `bias` as
/// `position` when there is one.
fn tips_dict<'py>(py: Python<'py>, tips: Tips, n: usize) -> PyResult<Bound<'py, PyDict>> {
    let k = tips.rows;
    let dict = PyDict::new(py);
    let vector = |v: Vec<f64>| -> PyResult<Bound<'py, PyAny>> {
        let a = PyArray1::from_vec(py, v);
        Ok(match k {
            None => a.into_any(),
            Some(k) => a.reshape([k, 3])?.into_any(),
        })
    };
    dict.set_item("position", vector(tips.position)?)?;
    let jacobian = PyArray1::from_vec(py, tips.jacobian);
    match k {
        None => dict.set_item("jacobian", jacobian.reshape([3, n])?)?,
        Some(k) => dict.set_item("jacobian", jacobian.reshape([k, 3, n])?)?,
    }
    if let Some(bias) = tips.bias {
        dict.set_item("bias", vector(bias)?)?;
    }
    Ok(dict)
}

fn batch_failure(e: BatchError, what: &str) -> Failure {
    match e {
        BatchError::OutOfMemory { bytes } => crate::arrays::out_of_memory::<f64>(bytes / 8, what),
        BatchError::Input(message) => Failure::Input(message),
        BatchError::Tool(i, e) => Failure::Input(format!("tool {i}: {e}")),
    }
}

/// ``models()[m]["equilibrium"]``: ``q``, ``q_dot`` (X^e = [q; q_dot]) and ``u`` (U^e), lists.
pub fn equilibrium(py: Python<'_>, kind: ModelKind) -> PyResult<Bound<'_, PyDict>> {
    let (x, n) = (kind.equilibrium_state(), kind.dof());
    let out = PyDict::new(py);
    out.set_item("q", x[..n].to_vec())?;
    out.set_item("q_dot", x[n..].to_vec())?;
    out.set_item("u", kind.equilibrium_control().to_vec())?;
    Ok(out)
}

/// ``models()[m]["domains"]``: ``parameters`` (name → its domain in words), ``constraints``
/// (texts, the inertia tensor's rule among them), ``sample`` (name → [lo, hi], the box random
/// tools are drawn from) and ``defaults`` (name → the value of a parameter a tool may leave out).
pub fn domains(py: Python<'_>, kind: ModelKind) -> PyResult<Bound<'_, PyDict>> {
    let (parameters, sample) = (PyDict::new(py), PyDict::new(py));
    for ((name, domain), (lo, hi)) in kind
        .parameter_names()
        .iter()
        .zip(kind.parameter_domains())
        .zip(kind.sample_box())
    {
        parameters.set_item(name, domain.rule)?;
        sample.set_item(name, vec![*lo, *hi])?;
    }
    let out = PyDict::new(py);
    out.set_item("parameters", parameters)?;
    let constraints: Vec<&str> = kind.parameter_constraints().iter().map(|c| c.1).collect();
    out.set_item("constraints", constraints)?;
    out.set_item("sample", sample)?;
    let defaults = PyDict::new(py);
    for (name, d) in kind.parameter_names().iter().zip(kind.parameter_defaults()) {
        if let Some(d) = d {
            defaults.set_item(name, *d)?;
        }
    }
    out.set_item("defaults", defaults)?;
    if let Some(rule) = kind.info().inertia {
        constraints_with(&out, rule.rule)?;
    }
    Ok(out)
}

/// The inertia rule's text added to `domains["constraints"]`.
fn constraints_with(domains: &Bound<'_, PyDict>, rule: &str) -> PyResult<()> {
    let constraints = domains.get_item("constraints")?;
    if let Some(list) = constraints {
        list.call_method1("append", (rule,))?;
    }
    Ok(())
}
