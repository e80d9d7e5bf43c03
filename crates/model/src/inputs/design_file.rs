//! The design file (TOML): what may vary, between which bounds, under which linear
//! constraints, and what to optimise.
//!
//! ```toml
//! objective = "confidence"            # maximise ln|Π^U| (default), or "free_energy": minimise ∫F dt
//! constraints = ["l1 + l2 >= 0.7", "m1 + m2 <= 0.5"]
//! [bounds]                            # every parameter not fixed needs bounds in its domain (> 0)
//! m1 = [0.1, 0.6]
//! [fixed]                             # optional: parameters held at a value (e.g. a payload mass)
//! mp = 0.2
//! [search]                            # optional, defaults shown
//! seed = 0                            # random starts and the random tools compared with
//! starts = 8                          # random feasible starts besides the centre
//! samples = 100000                    # random feasible tools the design is compared with
//! simulate = 5                        # how many of the most confident of them are simulated
//! perturbation = -0.8                 # ΔT [N m] for the sensitivity |Δ task error|
//! validation = 100                    # random feasible tools simulated to check that confidence
//!                                     # predicts the task error here (0: no check)
//! ```
//!
//! Every mistake is a [`DesignFileError`] naming the file and the key.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use crate::registry::ModelKind;
use toolconf_generated::validity::ParameterDomain;
use toolconf_messages::{Clip, ClipMessage, ClipPath, ShortList};

pub mod constraint;
use constraint::{parse_constraint, LinearConstraint};

/// Tools simulated alongside to check claim (a) by default (`rank --validation`, design's
/// `[search] validation`; the check is `toolconf::evaluation::check`).
pub const VALIDATION_TOOLS: usize = 100;

/// A bad design file (or design dict): the file, where in it (a key or a line), and what is
/// wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct DesignFileError {
    pub file: String,
    /// `key bounds.m1`, `line 4`, or empty when the whole file is meant.
    pub place: String,
    pub message: String,
}

impl DesignFileError {
    fn new(file: &str, place: &str, message: String) -> Self {
        Self {
            file: file.into(),
            place: place.into(),
            message,
        }
    }
}

impl std::fmt::Display for DesignFileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        super::write_located(f, &self.file, &self.place, &self.message)
    }
}

/// What the design optimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DesignObjective {
    /// Maximise ln|Π^U| (closed form with its derived gradient).
    Confidence,
    /// Minimise ∫F dt by simulation, started from the confidence optimum.
    FreeEnergy,
    /// Minimise the predicted task error of the closed loop linearised at the equilibrium
    /// ([`crate::prediction`]; its gradient in `toolconf::design::predicted`).
    PredictedTaskError,
    /// Minimise the predicted ∫F dt of the same linearised loop.
    PredictedFreeEnergy,
}

impl DesignObjective {
    pub fn name(self) -> &'static str {
        match self {
            DesignObjective::Confidence => "confidence",
            DesignObjective::FreeEnergy => "free_energy",
            DesignObjective::PredictedTaskError => "predicted_task_error",
            DesignObjective::PredictedFreeEnergy => "predicted_free_energy",
        }
    }
}

/// Search settings (`[search]` table).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchSettings {
    pub seed: u64,
    pub starts: usize,
    pub samples: usize,
    pub simulate: usize,
    pub perturbation: f64,
    /// The first this many random feasible tools are simulated to check claim (a) on the
    /// design's feasible set (`toolconf::evaluation::check`).
    pub validation: usize,
}

impl Default for SearchSettings {
    fn default() -> Self {
        Self {
            seed: 0,
            starts: 8,
            samples: 100_000,
            simulate: 5,
            perturbation: -0.8,
            validation: VALIDATION_TOOLS,
        }
    }
}

/// A checked design problem over one model's parameters (in the model's order).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSpec {
    pub file: String,
    pub objective: DesignObjective,
    pub names: Vec<&'static str>,
    /// Per parameter: `Some(value)` if fixed.
    pub fixed: Vec<Option<f64>>,
    /// Per parameter: (lo, hi); a fixed parameter's are (value, value).
    pub bounds: Vec<(f64, f64)>,
    pub constraints: Vec<LinearConstraint>,
    pub search: SearchSettings,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDesign {
    objective: Option<String>,
    #[serde(default)]
    constraints: Vec<String>,
    #[serde(default)]
    bounds: BTreeMap<String, Vec<f64>>,
    #[serde(default)]
    fixed: BTreeMap<String, f64>,
    #[serde(default)]
    search: RawSearch,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawSearch {
    seed: Option<u64>,
    starts: Option<usize>,
    samples: Option<usize>,
    simulate: Option<usize>,
    perturbation: Option<f64>,
    validation: Option<usize>,
}

impl DesignSpec {
    /// Reads and checks a design file for a tool of `model`.
    pub fn from_file(path: &Path, model: ModelKind) -> Result<Self, DesignFileError> {
        let file = ClipPath(&path.to_string_lossy()).to_string();
        let text = super::bounded_read::read_text_file(path, "design file")
            .map_err(|message| DesignFileError::new(&file, "", message))?;
        Self::parse(&text, &file, model)
    }

    /// Parses and checks design-file text for a tool of `model`; `file` names it in errors.
    /// Bounds and fixed values must lie in each parameter's domain, and the model's own
    /// constraints (a URDF tool's triangle inequality, `generated::validity`) join the file's.
    pub fn parse(text: &str, file: &str, model: ModelKind) -> Result<Self, DesignFileError> {
        let raw: RawDesign = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| 1 + text[..s.start].matches('\n').count());
            let place = line.map(|l| format!("line {l}")).unwrap_or_default();
            let message = e.message().trim().replace('\n', " ");
            DesignFileError::new(file, &place, ClipMessage(&message).to_string())
        })?;
        Self::from_raw(raw, file, model)
    }

    fn from_raw(raw: RawDesign, file: &str, model: ModelKind) -> Result<Self, DesignFileError> {
        let names = model.parameter_names();
        let err =
            |key: &str, message: String| DesignFileError::new(file, &format!("key {key}"), message);
        let objective =
            design_objective(raw.objective.as_deref()).map_err(|m| err("objective", m))?;
        let (fixed, bounds) = fixed_and_bounds(&raw, model, &err)?;
        let mut constraints = raw
            .constraints
            .iter()
            .enumerate()
            .map(|(i, c)| {
                parse_constraint(c, names)
                    .map_err(|m| err(&format!("constraints[{i}]"), format!("'{}': {m}", Clip(c))))
            })
            .collect::<Result<Vec<_>, _>>()?;
        constraints.extend(model_constraints(model, &fixed).map_err(|m| err("fixed", m))?);
        Ok(Self {
            file: file.into(),
            objective,
            names: names.to_vec(),
            fixed,
            bounds,
            constraints,
            search: search_settings(&raw.search)
                .map_err(|(k, m)| err(&format!("search.{k}"), m))?,
        })
    }
}

/// The file's `objective`: confidence (the default), free_energy, or a predicted cost.
fn design_objective(name: Option<&str>) -> Result<DesignObjective, String> {
    match name {
        None | Some("confidence") => Ok(DesignObjective::Confidence),
        Some("free_energy") | Some("free-energy") => Ok(DesignObjective::FreeEnergy),
        Some("predicted_task_error") => Ok(DesignObjective::PredictedTaskError),
        Some("predicted_free_energy") => Ok(DesignObjective::PredictedFreeEnergy),
        Some(other) => Err(format!(
            "'{}' is not an objective (confidence, free_energy, predicted_task_error or \
             predicted_free_energy)",
            Clip(other)
        )),
    }
}

/// Per parameter: its fixed value, if any, and its range.
type FixedAndBounds = (Vec<Option<f64>>, Vec<(f64, f64)>);

/// Each parameter's fixed value (the file's, else the model's default where the file gives no
/// bounds either) and its range ((v, v) for a fixed one), each checked against its domain;
/// `err` makes the error naming a key.
fn fixed_and_bounds(
    raw: &RawDesign,
    model: ModelKind,
    err: &dyn Fn(&str, String) -> DesignFileError,
) -> Result<FixedAndBounds, DesignFileError> {
    let names = model.parameter_names();
    let domains = model.parameter_domains();
    let known = |key: String, name: &str| -> Result<usize, DesignFileError> {
        names.iter().position(|n| *n == name).ok_or_else(|| {
            err(
                &Clip(&key).to_string(),
                format!(
                    "unknown parameter '{}' (parameters: {})",
                    Clip(name),
                    names.join(", ")
                ),
            )
        })
    };
    let mut fixed = vec![None; names.len()];
    for (name, &value) in &raw.fixed {
        let k = known(format!("fixed.{name}"), name)?;
        if let Err(why) = crate::validate::tool_parameter(&domains[k], value) {
            return Err(err(&format!("fixed.{name}"), why));
        }
        fixed[k] = Some(value);
    }
    let mut bounds = vec![None; names.len()];
    for (name, range) in &raw.bounds {
        let key = format!("bounds.{name}");
        let k = known(key.clone(), name)?;
        if fixed[k].is_some() {
            return Err(err(
                &key,
                format!("'{name}' is also fixed; give one of the two"),
            ));
        }
        bounds[k] = Some(check_bounds(range, &domains[k]).map_err(|m| err(&key, m))?);
    }
    // A parameter a tools file may leave out (a URDF tool's products of inertia and tip) is
    // fixed at its default where the design file is silent on it.
    for (k, default) in model.parameter_defaults().iter().enumerate() {
        if fixed[k].is_none() && bounds[k].is_none() {
            fixed[k] = *default;
        }
    }
    let mut out = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        match (fixed[k], bounds[k]) {
            (Some(v), _) => out.push((v, v)),
            (None, Some(b)) => out.push(b),
            (None, None) => {
                return Err(err(
                    "bounds",
                    format!("parameter '{name}' has no bounds: give bounds.{name} = [lo, hi] or fixed.{name} = value"),
                ))
            }
        }
    }
    Ok((fixed, out))
}

/// The model's constraints across its parameters as design constraints (c · p ≤ 0), but those
/// on fixed parameters only: they are checked here, once.
fn model_constraints(
    model: ModelKind,
    fixed: &[Option<f64>],
) -> Result<Vec<LinearConstraint>, String> {
    let mut out = Vec::new();
    for (coefficients, rule) in model.parameter_constraints() {
        let on_free = coefficients
            .iter()
            .zip(fixed)
            .any(|(&c, f)| c != 0.0 && f.is_none());
        if on_free {
            out.push(LinearConstraint {
                coefficients: coefficients.to_vec(),
                bound: 0.0,
                text: rule.to_string(),
            });
            continue;
        }
        let value: f64 = coefficients
            .iter()
            .zip(fixed)
            .map(|(c, f)| c * f.unwrap_or(0.0))
            .sum();
        if value > 0.0 {
            return Err(format!("the fixed values break {rule}"));
        }
    }
    Ok(out)
}

fn check_bounds(range: &[f64], domain: &ParameterDomain) -> Result<(f64, f64), String> {
    let &[lo, hi] = range else {
        return Err(format!("{} is not [lo, hi]", ShortList(range)));
    };
    let shown = ShortList(range);
    if domain.is_positive() {
        let valid = crate::validate::TOOL_PARAMETER;
        if lo <= 0.0 {
            return Err(format!(
                "{shown} admits values <= 0; masses and lengths must be > 0 (give lo > 0)"
            ));
        }
        if !(valid.contains(lo) && valid.contains(hi)) {
            return Err(format!(
                "{shown} goes outside {valid}, where every tool parameter must lie"
            ));
        }
    } else if !(domain.contains(lo) && domain.contains(hi)) {
        return Err(format!(
            "{shown} leaves the parameter's domain: it must be {}",
            domain.rule
        ));
    }
    if lo > hi {
        return Err(format!("{shown} is empty (lo > hi)"));
    }
    Ok((lo, hi))
}

fn search_settings(raw: &RawSearch) -> Result<SearchSettings, (&'static str, String)> {
    let d = SearchSettings::default();
    let s = SearchSettings {
        seed: raw.seed.unwrap_or(d.seed),
        starts: raw.starts.unwrap_or(d.starts),
        samples: raw.samples.unwrap_or(d.samples),
        simulate: raw.simulate.unwrap_or(d.simulate),
        perturbation: raw.perturbation.unwrap_or(d.perturbation),
        validation: raw.validation.unwrap_or(d.validation),
    };
    if s.validation > 100_000 {
        return Err(("validation", format!("{} is more than 10^5", s.validation)));
    }
    if s.samples > 10_000_000 {
        return Err(("samples", format!("{} is more than 10^7", s.samples)));
    }
    if s.starts > 1000 {
        return Err(("starts", format!("{} is more than 1000", s.starts)));
    }
    if s.simulate > 1000 {
        return Err(("simulate", format!("{} is more than 1000", s.simulate)));
    }
    crate::validate::TORQUE
        .check(s.perturbation)
        .map_err(|m| ("perturbation", m))?;
    Ok(s)
}

/// Designs given as data rather than as a file (the Python package's design dicts).
impl DesignSpec {
    /// A design given as a TOML table with a design file's keys, checked exactly as a design
    /// file is; `source` names it in errors (`design dict, key bounds.m1: …`). A value of the
    /// wrong type or an unknown key is named by its dotted key, as a file's would be by its line.
    pub fn from_table(
        table: toml::Table,
        source: &str,
        model: ModelKind,
    ) -> Result<Self, DesignFileError> {
        let raw: RawDesign = table.try_into().map_err(|e| {
            // As TaskSpec::from_table: toml names the place as a last line "in `bounds.m1`".
            let text = e.to_string();
            let (message, place) = match text.trim_end().rsplit_once("\nin `") {
                Some((message, key)) => (message, format!("key {}", key.trim_end_matches('`'))),
                None => (text.trim_end(), String::new()),
            };
            DesignFileError::new(source, &place, message.trim().replace('\n', " "))
        })?;
        Self::from_raw(raw, source, model)
    }
}
