//! `toolconf.tool_from_urdf`: `toolconf tool --urdf`'s row as a dict (the crate toolconf-tool-urdf).

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};
use toolconf_messages::Clip;
use toolconf_model::registry::flange_model;
use toolconf_tool_urdf::{tool_from_urdf_file, Request};

use crate::errors::{detached, Failure};

/// A position (m or rad): a real number, not a bool.
fn position(name: &str, value: &Bound<'_, PyAny>) -> Result<f64, Failure> {
    if value.is_instance_of::<PyBool>() {
        return Err(Failure::Type(format!("{name}: a bool is not a position")));
    }
    let v: f64 = value
        .extract()
        .map_err(|_| Failure::Type(format!("{name}: a position must be a real number")))?;
    if !v.is_finite() {
        return Err(Failure::Input(format!("{name}: {v} is not finite")));
    }
    Ok(v)
}

/// A tool's row of a tools file from the tool's own URDF, as ``toolconf tool --urdf`` writes
/// it: the rigid bodies of ``root`` and every link below it merged, movable joints held at a
/// stated position, everything in the flange frame.
///
/// Args:
///     urdf: the URDF file's path.
///     root: the tool's root link (e.g. ``"panda_hand"``).
///     tip: the link whose origin is the tool-centre point, ``root`` or below it
///         (``"panda_hand_tcp"``).
///     flange: an ancestor link of ``root``, joined to it by fixed joints, whose frame is the
///         flange frame (``"panda_link8"``); ``None``: the root's frame.
///     opening: the position (m or rad) of every movable joint below ``root`` that is not a
///         ``<mimic>`` (mimics follow the joint they mimic).
///     joints: positions of named joints, ``{name: value}``, over ``opening``.
///     name: the row's ``name`` (default: ``root``).
///     model: the row's ``model``, a model with a tool at a URDF flange (``"panda"``,
///         ``"ur5"``), or ``None``.
///
/// Returns:
///     dict: ``name``, ``model`` (str or None), ``tool_mass`` (kg), ``tool_com_x/y/z`` (m),
///     ``tool_ixx``, ``tool_iyy``, ``tool_izz``, ``tool_ixy``, ``tool_ixz``, ``tool_iyz``
///     (kg m², about the centre of mass, URDF's ``<inertia>`` convention: ``tool_ixy`` is
///     I[0][1]) and ``tool_tip_x/y/z`` (m), in that order, every number finite.
///
/// Raises:
///     ValueError: a file that cannot be read or is not a URDF, an unknown link or joint, a
///         movable joint without a position or outside its limits, a merged body that no rigid
///         body is; the command line's one line, naming the file, line, link or joint and value.
///     TypeError: a position that is not a real number.
#[pyfunction]
#[pyo3(signature = (urdf, root, tip, *, flange=None, opening=None, joints=None, name=None, model=None))]
#[allow(clippy::too_many_arguments)]
pub fn tool_from_urdf<'py>(
    py: Python<'py>,
    urdf: PathBuf,
    root: String,
    tip: String,
    flange: Option<String>,
    opening: Option<&Bound<'py, PyAny>>,
    joints: Option<&Bound<'py, PyDict>>,
    name: Option<String>,
    model: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let read = || -> Result<Request, Failure> {
        let opening = opening
            .filter(|o| !o.is_none())
            .map(|o| position("opening", o))
            .transpose()?;
        let mut held = Vec::new();
        if let Some(joints) = joints {
            for (key, value) in joints.iter() {
                let key: String = key
                    .extract()
                    .map_err(|_| Failure::Type("joints: a joint's name must be a str".into()))?;
                let value = position(&format!("joints['{}']", Clip(&key)), &value)?;
                held.push((key, value));
            }
        }
        Ok(Request {
            root,
            tip,
            flange,
            opening,
            joints: held,
        })
    };
    let request = read().map_err(|f| f.into_pyerr(py))?;
    let model = model
        .map(|m| flange_model(&m).map_err(|e| Failure::Input(format!("model: {e}"))))
        .transpose()
        .map_err(|f| f.into_pyerr(py))?;
    let tool = detached(py, || {
        tool_from_urdf_file(&urdf, &request).map_err(Failure::input)
    })?;
    let out = PyDict::new(py);
    out.set_item("name", name.unwrap_or_else(|| request.root.clone()))?;
    out.set_item("model", model)?;
    for (column, value) in tool.values() {
        out.set_item(column, value)?;
    }
    Ok(out)
}
