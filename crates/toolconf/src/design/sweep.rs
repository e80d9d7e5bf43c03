//! The confidence–budget trade-off: `--sweep 'm1 + m2 <= 0.3..0.9:7'` re-solves the design with
//! the constraint's right side at K evenly spaced values from A to B, replacing the design file's
//! constraint with the same left side (or adding it). Infeasible budgets are kept as such.

use super::{confidence_optimum, DesignError, Setting};
use toolconf_model::inputs::design_file::constraint::{parse_constraint, split_comparison};
use toolconf_model::inputs::design_file::DesignSpec;

/// A parsed `--sweep`: the constraint text at each value.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// The left side and comparison, e.g. `m1 + m2 <=`.
    pub label: String,
    pub values: Vec<f64>,
    texts: Vec<String>,
}

/// One point of the front.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPoint {
    pub value: f64,
    /// The optimum's full parameters, ln|Π^U| and KKT residual, or why there is none.
    pub outcome: Result<(Vec<f64>, f64, f64), String>,
}

/// Parses `LEFT <= A..B:K` (or `>=`); K ≥ 2 values from A to B inclusive.
pub fn parse_sweep(text: &str, names: &[&str]) -> Result<Sweep, String> {
    let bad = |why: &str| format!("--sweep '{}': {why}", toolconf_messages::Clip(text));
    let (left, sense, right) = split_comparison(text).map_err(|e| bad(&e))?;
    let op = if matches!(
        sense,
        toolconf_model::inputs::design_file::constraint::Sense::AtMost
    ) {
        "<="
    } else {
        ">="
    };
    let (range, count) = right
        .split_once(':')
        .ok_or_else(|| bad("expected LEFT <= A..B:K"))?;
    let (a, b) = range
        .split_once("..")
        .ok_or_else(|| bad("expected A..B before ':'"))?;
    let number = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    let (Some(a), Some(b)) = (number(a), number(b)) else {
        return Err(bad("A and B must be finite numbers"));
    };
    let k: usize = count
        .trim()
        .parse()
        .map_err(|_| bad("K must be a whole number"))?;
    if !(2..=1000).contains(&k) {
        return Err(bad("K must be between 2 and 1000"));
    }
    // Rounded to 12 decimals so that 0.3..0.9:7 gives 0.6, not 0.6000000000000001.
    let values: Vec<f64> = (0..k)
        .map(|i| ((a + (b - a) * i as f64 / (k - 1) as f64) * 1e12).round() / 1e12)
        .collect();
    let texts: Vec<String> = values
        .iter()
        .map(|v| format!("{} {op} {v}", left.trim()))
        .collect();
    for t in &texts {
        parse_constraint(t, names).map_err(|e| bad(&e))?;
    }
    Ok(Sweep {
        label: format!("{} {op}", left.trim()),
        values,
        texts,
    })
}

/// Solves the design at every value of the sweep, in order.
pub fn run_sweep(
    spec: &DesignSpec,
    setting: &Setting,
    sweep: &Sweep,
) -> Result<Vec<SweepPoint>, DesignError> {
    let names: Vec<&str> = spec.names.clone();
    let mut points = Vec::with_capacity(sweep.values.len());
    for (value, text) in sweep.values.iter().zip(&sweep.texts) {
        let swept = parse_constraint(text, &names).map_err(DesignError::Input)?;
        let mut s = spec.clone();
        s.constraints
            .retain(|c| c.coefficients != swept.coefficients);
        s.constraints.push(swept);
        let outcome = match confidence_optimum(&s, setting) {
            Ok((polytope, o)) => Ok((polytope.full(&o.x), o.value, o.kkt_residual)),
            Err(DesignError::Infeasible(_)) => Err("infeasible".to_string()),
            Err(e) => return Err(e),
        };
        points.push(SweepPoint {
            value: *value,
            outcome,
        });
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_range_and_count() {
        let s = parse_sweep("m1 + m2 <= 0.3..0.9:7", &["m1", "m2", "l1", "l2"]).unwrap();
        assert_eq!(s.values.len(), 7);
        assert_eq!(s.values[0], 0.3);
        assert!((s.values[6] - 0.9).abs() < 1e-15);
        assert_eq!(s.label, "m1 + m2 <=");
        assert!(parse_sweep("m1 + m9 <= 0.3..0.9:7", &["m1", "m2"])
            .unwrap_err()
            .contains("unknown parameter 'm9'"));
        assert!(parse_sweep("m1 <= 0.3..0.9", &["m1"])
            .unwrap_err()
            .contains("A..B:K"));
        assert!(parse_sweep("m1 <= 0.3..0.9:1", &["m1"])
            .unwrap_err()
            .contains("between 2"));
    }
}
