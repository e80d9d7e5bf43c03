//! NumPy arrays as Rust vectors, whatever their memory: `numpy.require` gives an aligned,
//! C-contiguous array of the dtype (a copy only when needed), so the values are read as one
//! slice. Arrays that crossed a process boundary (a Dask worker's, unpickled from out-of-band
//! buffers) can be unaligned, and a view of them would be undefined behaviour.
//!
//! Every vector sized by the input is allocated here, fallibly: an allocation that fails is
//! `MemoryError` naming what it was for, where `Vec::with_capacity` would abort the interpreter.

use numpy::{Element, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyTuple};

use crate::errors::Failure;

/// `value`'s shape and its values in C order, as `dtype` (`"float64"`, `"int64"`).
pub fn values<T: Element + Copy>(
    value: &Bound<'_, PyAny>,
    dtype: &str,
) -> PyResult<(Vec<usize>, Vec<T>)> {
    let numpy = value.py().import("numpy")?;
    let array = numpy.call_method1("require", (value, dtype, ["A", "C"]))?;
    let array = array.cast_into::<PyArrayDyn<T>>()?;
    let shape = array.shape().to_vec();
    let readonly = array.readonly();
    let slice = readonly
        .as_slice()
        .expect("numpy.require gives an aligned, C-contiguous array");
    let mut copy = with_capacity(slice.len(), &format!("a {dtype} array of shape {shape:?}"))
        .map_err(|f| f.into_pyerr(value.py()))?;
    copy.extend_from_slice(slice);
    Ok((shape, copy))
}

/// A float argument's shape and values, [`values`] as float64, of an array of real numbers:
/// float, integer, or objects that are each a real number (Python ints past int64 included).
/// A boolean, complex, text, date or structured array is a `TypeError` naming the argument (a
/// complex array would lose its imaginary part, booleans are not quantities); a value NumPy
/// cannot make an array of is a `ValueError` naming it (`params: setting an array element …`).
pub fn float_argument(name: &str, value: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let py = value.py();
    let failed = |e: PyErr| Failure::python(name, e).into_pyerr(py);
    let numpy = py.import("numpy")?;
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        // NumPy would make [0.3, True] the floats [0.3, 1.0]: the items are checked first.
        let objects = PyDict::new(py);
        objects.set_item("dtype", "object")?;
        let items = numpy
            .call_method("array", (value,), Some(&objects))
            .map_err(failed)?;
        real_objects(name, &items)?;
    }
    let array = numpy.call_method1("asarray", (value,)).map_err(failed)?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    match kind.as_str() {
        "f" | "i" | "u" => {}
        "O" => real_objects(name, &array)?,
        _ => {
            let what = match kind.as_str() {
                "b" => "an array of booleans",
                "c" => "an array of complex numbers (its imaginary part would be lost)",
                "U" | "S" => "an array of text",
                "M" | "m" => "an array of dates or times",
                _ => "an array of records",
            };
            return Err(Failure::Type(format!(
                "{name}: {what} (dtype {}); expected real numbers (floats or integers)",
                dtype.str()?
            ))
            .into_pyerr(py));
        }
    }
    values::<f64>(&array, "float64").map_err(failed)
}

/// Checks that every item of an object array is a real number and not a bool (`True` is an
/// int to Python, but not a mass); the first that is not is a `TypeError` naming it.
fn real_objects(name: &str, array: &Bound<'_, PyAny>) -> PyResult<()> {
    let py = array.py();
    let real = py.import("numbers")?.getattr("Real")?;
    let numpy_bool = py.import("numpy")?.getattr("bool_")?;
    for item in array.getattr("flat")?.try_iter()? {
        let item = item?;
        let boolean = item.is_instance_of::<PyBool>() || item.is_instance(&numpy_bool)?;
        if boolean || !item.is_instance(&real)? {
            let type_name = item.get_type().name()?;
            return Err(Failure::Type(format!(
                "{name}: {} ({type_name}) is not a real number",
                crate::tools::short_repr(&item)
            ))
            .into_pyerr(py));
        }
    }
    Ok(())
}

/// An empty vector with room for `n` values, or `MemoryError` naming `what` it was for.
pub fn with_capacity<T>(n: usize, what: &str) -> Result<Vec<T>, Failure> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| out_of_memory::<T>(n, what))?;
    Ok(v)
}

/// The `MemoryError` of `n` values of `T` for `what`.
pub fn out_of_memory<T>(n: usize, what: &str) -> Failure {
    let bytes = n.saturating_mul(std::mem::size_of::<T>()) as f64;
    let size = if bytes >= 1e9 {
        format!("{:.1} GB", bytes / 1e9)
    } else {
        format!("{:.1} MB", bytes / 1e6)
    };
    Failure::Memory(format!(
        "{what}: cannot allocate {size} ({n} values): not enough memory"
    ))
}

/// `n` zeros ([`with_capacity`]).
pub fn zeros(n: usize, what: &str) -> Result<Vec<f64>, Failure> {
    let mut v = with_capacity(n, what)?;
    v.resize(n, 0.0);
    Ok(v)
}

/// The items as a vector ([`with_capacity`]).
pub fn collect<T>(items: impl ExactSizeIterator<Item = T>, what: &str) -> Result<Vec<T>, Failure> {
    let mut v = with_capacity(items.len(), what)?;
    v.extend(items);
    Ok(v)
}

/// A tool-parameter argument (`params`: one tool, 1-D, or one per row, 2-D) of model `kind`, read
/// as [`float_argument`] does; a tool that gives only the required parameters gets the model's
/// trailing defaults (a URDF tool of toolconf's earlier 7: no products of inertia, tip at the
/// flange; `ModelKind::with_defaults`), as a tools file without those columns does.
pub fn tool_params(
    kind: toolconf_model::registry::ModelKind,
    value: &Bound<'_, PyAny>,
) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let (mut shape, values) = float_argument("params", value)?;
    let (required, all) = (kind.required_parameters(), kind.parameter_names().len());
    if shape.last() != Some(&required) || required == all || required == 0 {
        return Ok((shape, values));
    }
    let mut out = Vec::with_capacity(values.len() / required * all);
    for row in values.chunks_exact(required) {
        out.extend(kind.with_defaults(row).unwrap_or_else(|| row.to_vec()));
    }
    if let Some(last) = shape.last_mut() {
        *last = all;
    }
    Ok((shape, out))
}
