//! The one error type of the crate, plus the input checks every routine shares.

/// Why a statistic could not be computed. Each message names the offending input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StatsError {
    /// Two inputs that must be paired element by element have different lengths.
    #[error("{what} have different lengths ({left} and {right}); they must be paired one to one")]
    Length {
        what: &'static str,
        left: usize,
        right: usize,
    },
    /// Fewer observations (or resamples) than the statistic needs.
    #[error("too few {what}: got {got}, need at least {need}")]
    TooFew {
        what: &'static str,
        got: usize,
        need: usize,
    },
    /// An input value that is NaN or infinite.
    #[error("{what}[{index}] = {value} is not a finite number")]
    NonFinite {
        what: &'static str,
        index: usize,
        value: f64,
    },
    /// A tuning argument (confidence level, ...) outside its valid range.
    #[error("invalid {name} = {value}: {expected}")]
    InvalidArgument {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// The data are valid numbers, but the statistic is undefined for them.
    #[error("statistic is undefined: {reason}")]
    Degenerate { reason: String },
}

impl StatsError {
    pub(crate) fn degenerate(reason: impl Into<String>) -> Self {
        StatsError::Degenerate {
            reason: reason.into(),
        }
    }
}

/// Rejects NaN and ±∞ up front, so no routine can turn them into a NaN result.
pub(crate) fn check_finite(what: &'static str, x: &[f64]) -> Result<(), StatsError> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(StatsError::NonFinite {
            what,
            index,
            value: x[index],
        }),
        None => Ok(()),
    }
}

pub(crate) fn check_len(what: &'static str, got: usize, need: usize) -> Result<(), StatsError> {
    if got < need {
        return Err(StatsError::TooFew { what, got, need });
    }
    Ok(())
}

/// How the two halves of a paired sample are called in error messages.
pub(crate) struct PairNames {
    first: &'static str,
    second: &'static str,
    both: &'static str,
}

pub(crate) const XY: PairNames = PairNames {
    first: "x",
    second: "y",
    both: "x and y",
};
pub(crate) const AB: PairNames = PairNames {
    first: "a",
    second: "b",
    both: "a and b",
};

/// Checks for a paired sample: equal length, at least `need` pairs, all finite.
pub(crate) fn check_pairs(
    names: &PairNames,
    x: &[f64],
    y: &[f64],
    need: usize,
) -> Result<(), StatsError> {
    if x.len() != y.len() {
        return Err(StatsError::Length {
            what: names.both,
            left: x.len(),
            right: y.len(),
        });
    }
    check_len("pairs", x.len(), need)?;
    check_finite(names.first, x)?;
    check_finite(names.second, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_problem() {
        let e = check_pairs(&XY, &[1.0, 2.0], &[1.0], 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "x and y have different lengths (2 and 1); they must be paired one to one"
        );
        let e = check_pairs(&XY, &[1.0, 2.0], &[1.0, 2.0], 3).unwrap_err();
        assert_eq!(e.to_string(), "too few pairs: got 2, need at least 3");
        let e = check_pairs(&AB, &[1.0, 2.0, 3.0], &[1.0, f64::NAN, 3.0], 3).unwrap_err();
        assert_eq!(e.to_string(), "b[1] = NaN is not a finite number");
        let e = check_finite("x", &[f64::NEG_INFINITY]).unwrap_err();
        assert_eq!(e.to_string(), "x[0] = -inf is not a finite number");
    }
}
