//! NumPy arrays as Rust vectors, whatever their memory: `numpy.require` gives an aligned,
//! C-contiguous array of the dtype (a copy only when needed), so the values are read as one
//! slice. Arrays that crossed a process boundary (a Dask worker's, unpickled from out-of-band
//! buffers) can be unaligned, and a view of them would be undefined behaviour.

use numpy::{Element, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

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
    Ok((shape, slice.to_vec()))
}

/// A float argument's shape and values, [`values`] as float64; a value NumPy cannot read as
/// floats is a `ValueError` naming the argument (`params: could not convert …`).
pub fn float_argument(name: &str, value: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    values::<f64>(value, "float64")
        .map_err(|e| crate::errors::Failure::Input(format!("{name}: {e}")).into_pyerr(value.py()))
}
