//! Integer arguments (`screen`, `first_tool`, `seed`) as the command line takes its integer flags: a
//! whole number within the flag's range, or one line naming the argument and the value, never
//! pyo3's `OverflowError` for a number past 64 bits.

use pyo3::prelude::*;
use pyo3::types::PyBool;

use crate::errors::Failure;
use crate::tools::short_repr;

/// `value` as an integer in [lo, hi]: a Python int or anything with `__index__` (a NumPy
/// integer), or a `TypeError` (a bool, a float, text); outside the range, a `ValueError`
/// naming `name`, the value and the bound it crosses.
pub fn integer(name: &str, value: &Bound<'_, PyAny>, lo: i128, hi: i128) -> Result<i128, Failure> {
    let shown = || short_repr(value);
    if value.is_instance_of::<PyBool>() {
        return Err(Failure::Type(format!(
            "{name} = {}: expected an integer, not a bool",
            shown()
        )));
    }
    let index = value
        .py()
        .import("operator")
        .and_then(|operator| operator.call_method1("index", (value,)))
        .map_err(|_| Failure::Type(format!("{name} = {}: expected an integer", shown())))?;
    // Past i128 only the sign matters: the value is outside any range an argument has.
    let v = match index.extract::<i128>() {
        Ok(v) => v,
        Err(_) if index.lt(0).unwrap_or(false) => i128::MIN,
        Err(_) => i128::MAX,
    };
    if v < lo {
        return Err(Failure::Input(format!(
            "{name} = {}: must be at least {lo}",
            shown()
        )));
    }
    if v > hi {
        return Err(Failure::Input(format!(
            "{name} = {}: must be at most {hi}",
            shown()
        )));
    }
    Ok(v)
}

/// A seed: an integer in [0, 2⁶⁴ − 1], as the command line's `--seed`.
pub fn seed(value: &Bound<'_, PyAny>) -> Result<u64, Failure> {
    let v = integer("seed", value, 0, u64::MAX.into())?;
    Ok(u64::try_from(v).expect("within [0, 2^64 - 1]"))
}
