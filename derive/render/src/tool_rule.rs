//! The registry's view of a model's tool rule (templates/registry/src/validity.rs.tera, and the
//! URDF report's table of valid tools): each domain's bounds as Rust literals and its rule in
//! words, the constraints' coefficients and text, the sampling box. The rule is the IR's
//! `model.tool_rule`, or for a model whose description states none, the planar arms'.

use serde::Serialize;

use crate::escape::comment;
use crate::ir::{Domain, Inertia, Model, Parameter, ToolRule};
use crate::tasks::string_literal;
use crate::RenderError;

/// One parameter's domain, rendered.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DomainView {
    pub name: String,
    /// The bounds as Rust literals (an infinite one for no bound).
    pub lo: String,
    pub hi: String,
    pub lo_open: bool,
    pub hi_open: bool,
    /// The rule in words ("a finite number > 0"), and as a Rust string literal.
    pub words: String,
    pub rule: String,
    /// The sampling box as the report prints it, `[0.1, 0.6]`.
    pub sample: String,
}

/// A constraint c · p ≤ 0, rendered.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstraintView {
    pub coefficients: Vec<String>,
    pub text: String,
    /// `text` as a Rust string literal.
    pub rule: String,
}

/// A sampling interval's ends as Rust literals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SampleView {
    pub lo: String,
    pub hi: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToolRuleView {
    pub domains: Vec<DomainView>,
    pub constraints: Vec<ConstraintView>,
    pub sample: Vec<SampleView>,
    /// Per parameter, its default as a Rust `Option<f64>` literal (`None`, `Some(0.0)`).
    pub defaults: Vec<String>,
    /// The inertia rule as a Rust `Option<InertiaRule>` expression.
    pub inertia: String,
    /// The inertia rule in words, if there is one (the URDF report).
    pub inertia_text: Option<String>,
}

/// The planar arms' rule, for a model whose IR states none: every parameter (a mass, a length,
/// a stiffness) finite and > 0, random tools drawn from the paper's [0.1, 0.6]
/// ("Implementation details"), no constraint across parameters.
fn default_tool_rule(count: usize) -> ToolRule {
    let positive = Domain {
        lo: Some(0.0),
        hi: None,
        lo_open: true,
        hi_open: true,
    };
    ToolRule {
        domains: vec![positive; count],
        constraints: Vec::new(),
        sample: vec![[0.1, 0.6]; count],
        defaults: vec![None; count],
        inertia: None,
        source: String::new(),
    }
}

/// The model's tool rule, rendered; an error unless it has one domain and one sampling box per
/// parameter and one coefficient per parameter in each constraint.
pub fn tool_rule_view(model: &Model) -> Result<ToolRuleView, RenderError> {
    let parameters = &model.parameters;
    let default;
    let rule = match &model.tool_rule {
        Some(rule) => rule,
        None => {
            default = default_tool_rule(parameters.len());
            &default
        }
    };
    let bad = |what: &str| RenderError::Template(format!("model.tool_rule: {what}"));
    if rule.domains.len() != parameters.len() || rule.sample.len() != parameters.len() {
        return Err(bad("one domain and one sampling box per parameter"));
    }
    if rule
        .constraints
        .iter()
        .any(|c| c.coefficients.len() != parameters.len())
    {
        return Err(bad("a constraint needs one coefficient per parameter"));
    }
    if rule.defaults.len() != parameters.len()
        || rule.defaults.iter().flatten().any(|d| !d.is_finite())
    {
        return Err(bad("one finite default (or null) per parameter"));
    }
    let inertia_text = match &rule.inertia {
        Some(i) => Some(inertia_text(i, parameters).ok_or_else(|| {
            bad("inertia: an index is not a parameter's, or the slack not in [0, 1e-3]")
        })?),
        None => None,
    };
    let domains = rule
        .domains
        .iter()
        .zip(&rule.sample)
        .zip(parameters)
        .map(|((d, [lo, hi]), p)| domain_view(d, &p.name, &p.unit, format!("[{lo}, {hi}]")))
        .collect();
    let constraints = rule
        .constraints
        .iter()
        .map(|c| ConstraintView {
            coefficients: c.coefficients.iter().copied().map(rust_f64).collect(),
            text: comment(&c.text),
            rule: string_literal(&c.text),
        })
        .collect();
    let sample = rule
        .sample
        .iter()
        .map(|&[lo, hi]| SampleView {
            lo: rust_f64(lo),
            hi: rust_f64(hi),
        })
        .collect();
    let defaults = rule
        .defaults
        .iter()
        .map(|d| d.map_or("None".to_string(), |v| format!("Some({})", rust_f64(v))))
        .collect();
    let inertia = match (&rule.inertia, &inertia_text) {
        (Some(i), Some(text)) => format!(
            "Some(InertiaRule {{ moments: [{}], products: [{}], slack: {}, rule: {} }})",
            join(&i.moments),
            join(&i.products),
            rust_f64(i.slack),
            string_literal(text)
        ),
        _ => "None".to_string(),
    };
    Ok(ToolRuleView {
        domains,
        constraints,
        sample,
        defaults,
        inertia,
        inertia_text: inertia_text.as_deref().map(comment),
    })
}

fn join(indices: &[usize; 3]) -> String {
    indices.map(|i| i.to_string()).join(", ")
}

/// "the inertia tensor [[tool_ixx, tool_ixy, ...]] is positive definite ...": `None` if an
/// index is out of range or the slack unreasonable.
fn inertia_text(i: &Inertia, parameters: &[Parameter]) -> Option<String> {
    let name = |k: usize| parameters.get(k).map(|p| p.name.as_str());
    let [xx, yy, zz] = [
        name(i.moments[0])?,
        name(i.moments[1])?,
        name(i.moments[2])?,
    ];
    let [xy, xz, yz] = [
        name(i.products[0])?,
        name(i.products[1])?,
        name(i.products[2])?,
    ];
    if !(0.0..=1e-3).contains(&i.slack) {
        return None;
    }
    Some(format!(
        "the inertia tensor [[{xx}, {xy}, {xz}], [{xy}, {yy}, {yz}], [{xz}, {yz}, {zz}]] is \
         positive definite with eigenvalues obeying the triangle inequality (a rigid body's)"
    ))
}

/// One domain: its bounds as Rust literals (a missing bound is infinite) and the rule in words,
/// e.g. "a finite number > 0", "a finite number in [-1, 1] m".
fn domain_view(d: &Domain, name: &str, unit: &str, sample: String) -> DomainView {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    let (lo_open, hi_open) = (d.lo_open, d.hi_open);
    let words = match (d.lo, d.hi) {
        (None, None) => "a finite number".to_string(),
        (Some(l), None) => format!(
            "a finite number {} {l}{unit}",
            if lo_open { ">" } else { ">=" }
        ),
        (None, Some(h)) => format!(
            "a finite number {} {h}{unit}",
            if hi_open { "<" } else { "<=" }
        ),
        (Some(l), Some(h)) => format!(
            "a finite number in {}{l}, {h}{}{unit}",
            if lo_open { "(" } else { "[" },
            if hi_open { ")" } else { "]" }
        ),
    };
    DomainView {
        name: name.to_string(),
        lo: d.lo.map_or("f64::NEG_INFINITY".to_string(), rust_f64),
        hi: d.hi.map_or("f64::INFINITY".to_string(), rust_f64),
        lo_open,
        hi_open,
        rule: string_literal(&words),
        words: comment(&words),
        sample,
    }
}

/// An f64 as a Rust literal that reads back as the same double (`{:?}` is the shortest
/// round-trip form and always has a `.` or an exponent).
pub fn rust_f64(x: f64) -> String {
    format!("{x:?}")
}
