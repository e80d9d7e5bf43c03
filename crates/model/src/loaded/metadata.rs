//! A library's metadata (`toolconf_model_info()`, C structs) read into the runtime's own
//! [`ModelInfo`], every count, name and number checked first: a library whose metadata does not
//! hold together is refused with the first thing wrong, never half-registered.

use std::ffi::c_char;

use toolconf_cabi::info::{Domain, ModelInfo as CInfo};
use toolconf_cabi::{Exports, ABI_VERSION};

use super::c_text;
use crate::registry::ModelInfo;
use crate::{TaskKind, Term};
use toolconf_generated::validity::{InertiaRule, ParameterDomain};
use toolconf_generated::{Constraint, MAX_PARAMETER_COUNT};

/// The metadata, owned until the model is registered ([`Metadata::leak`]).
pub(crate) struct Metadata {
    pub name: String,
    title: String,
    description: String,
    pub dof: usize,
    parameter_names: Vec<String>,
    parameter_units: Vec<String>,
    state_names: Vec<String>,
    control_names: Vec<String>,
    domains: Vec<(f64, f64, bool, bool, String)>,
    constraints: Vec<(Vec<f64>, String)>,
    sample: Vec<(f64, f64)>,
    defaults: Vec<Option<f64>>,
    inertia: Option<([usize; 3], [usize; 3], f64, String)>,
    has_tip: bool,
    tip_dim: usize,
    equilibrium_state: Vec<f64>,
    equilibrium_control: Vec<f64>,
    tasks: Vec<TaskKind>,
}

impl Metadata {
    /// How many tool parameters.
    pub fn parameter_count(&self) -> usize {
        self.parameter_names.len()
    }

    /// The metadata for the life of the process, as a built-in model's.
    pub fn leak(self) -> &'static ModelInfo {
        let text = |s: String| -> &'static str { Box::leak(s.into_boxed_str()) };
        let texts = |v: Vec<String>| -> &'static [&'static str] {
            v.into_iter().map(text).collect::<Vec<_>>().leak()
        };
        let domains = self
            .domains
            .into_iter()
            .map(|(lo, hi, lo_open, hi_open, rule)| ParameterDomain {
                lo,
                hi,
                lo_open,
                hi_open,
                rule: text(rule),
            })
            .collect::<Vec<_>>()
            .leak();
        let constraints = self
            .constraints
            .into_iter()
            .map(|(c, rule)| Constraint {
                coefficients: c.leak(),
                rule: text(rule),
            })
            .collect::<Vec<_>>()
            .leak();
        Box::leak(Box::new(ModelInfo {
            name: text(self.name),
            title: text(self.title),
            description: text(self.description),
            dof: self.dof,
            state_dim: 2 * self.dof,
            parameter_names: texts(self.parameter_names),
            parameter_units: texts(self.parameter_units),
            state_names: texts(self.state_names),
            control_names: texts(self.control_names),
            domains,
            constraints,
            sample: self.sample.leak(),
            defaults: self.defaults.leak(),
            inertia: self
                .inertia
                .map(|(moments, products, slack, rule)| InertiaRule {
                    moments,
                    products,
                    slack,
                    rule: text(rule),
                }),
            has_tip: self.has_tip,
            tip_dim: self.tip_dim,
            equilibrium_state: self.equilibrium_state.leak(),
            equilibrium_control: self.equilibrium_control.leak(),
            tasks: self.tasks.leak(),
        }))
    }
}

/// The most joints a library may have (the largest size the runtime runs is smaller).
const MAX_DOF: usize = 64;

/// Reads and checks `toolconf_model_info()`; `name` replaces the library's own name.
pub(crate) fn read(exports: &Exports, name: Option<&str>) -> Result<Metadata, String> {
    let p = (exports.model_info)();
    if p.is_null() {
        // SAFETY: the library's message for this thread, NUL-terminated.
        let why = unsafe { c_text((exports.last_error)()) }.unwrap_or_default();
        return Err(format!("toolconf_model_info() gave no metadata: {why}"));
    }
    // SAFETY: a non-NULL pointer to the library's metadata, valid while it is loaded.
    let c = unsafe { &*p };
    check_counts(c)?;
    let (n, np) = (c.dof, c.parameter_count);
    // SAFETY (every read below): the metadata's arrays hold the counts it gives.
    let own_name = unsafe { text(c.name, "name") }?;
    // A name given is taken as given: refused if it is not one, never changed into one.
    let name = name.map_or(own_name, str::to_string);
    check_name(&name)?;
    unsafe { check_task_and_term_names(c) }?;
    let offered = unsafe { numbers_i32(c.task_offered, c.task_count, "task_offered") }?;
    let defaults_given = unsafe { numbers_i32(c.has_default, np, "has_default") }?;
    let default_values = unsafe { raw(c.defaults, np, "defaults") }?;
    let metadata = Metadata {
        title: unsafe { text(c.title, "title") }?,
        description: unsafe { text(c.description, "description") }?,
        dof: n,
        parameter_names: unsafe { texts(c.parameter_names, np, "parameter_names") }?,
        parameter_units: unsafe { texts(c.parameter_units, np, "parameter_units") }?,
        state_names: unsafe { texts(c.state_names, 2 * n, "state_names") }?,
        control_names: unsafe { texts(c.control_names, n, "control_names") }?,
        domains: unsafe { domains(c.domains, np) }?,
        constraints: unsafe { constraints(c, np) }?,
        sample: unsafe { finite(c.sample_lo, np, "sample_lo") }?
            .into_iter()
            .zip(unsafe { finite(c.sample_hi, np, "sample_hi") }?)
            .collect(),
        defaults: defaults_given
            .iter()
            .zip(&default_values)
            .map(|(given, v)| (*given != 0 && v.is_finite()).then_some(*v))
            .collect(),
        inertia: unsafe { inertia(c) }?,
        has_tip: c.has_tip != 0,
        tip_dim: c.tip_dim,
        equilibrium_state: unsafe { finite(c.equilibrium_state, 2 * n, "equilibrium_state") }?,
        equilibrium_control: unsafe { finite(c.equilibrium_control, n, "equilibrium_control") }?,
        tasks: TaskKind::ALL
            .into_iter()
            .zip(offered)
            .filter_map(|(k, o)| (o != 0).then_some(k))
            .collect(),
        name,
    };
    Ok(metadata)
}

/// The metadata's version and counts, checked before any array is read: every read after
/// trusts them for its length.
fn check_counts(c: &CInfo) -> Result<(), String> {
    if c.abi_version != ABI_VERSION {
        return Err(format!(
            "its metadata is of C ABI version {}, not {ABI_VERSION}",
            c.abi_version
        ));
    }
    let (n, np) = (c.dof, c.parameter_count);
    if n == 0 || n > MAX_DOF || c.state_dim != 2 * n {
        return Err(format!(
            "its metadata gives {n} joints and a state of {}: expected 1 to {MAX_DOF} joints and \
             twice as many states",
            c.state_dim
        ));
    }
    if np == 0 || np > MAX_PARAMETER_COUNT {
        return Err(format!(
            "{np} tool parameters: this toolconf takes 1 to {MAX_PARAMETER_COUNT}"
        ));
    }
    if c.tip_dim > 3 || c.tip_dim > n {
        return Err(format!(
            "its tip has {} components: at most 3 and N",
            c.tip_dim
        ));
    }
    if c.task_count != TaskKind::ALL.len() || c.term_count != Term::ALL.len() {
        return Err(format!(
            "{} tasks and {} terms: this toolconf's task list has {} and {}",
            c.task_count,
            c.term_count,
            TaskKind::ALL.len(),
            Term::ALL.len()
        ));
    }
    Ok(())
}

/// The library's tasks and terms, one for one this toolconf's (in the same order): the task
/// offers and the sensitivities are indexed by them.
///
/// # Safety
/// `c`'s task and term name arrays hold the counts it gives ([`check_counts`] passed).
unsafe fn check_task_and_term_names(c: &CInfo) -> Result<(), String> {
    let task_names = texts(c.task_names, c.task_count, "task_names")?;
    let term_names = texts(c.term_names, c.term_count, "term_names")?;
    for (theirs, ours) in task_names.iter().zip(TaskKind::ALL) {
        if theirs != ours.name() {
            return Err(format!(
                "its task '{theirs}' is this toolconf's '{}'",
                ours.name()
            ));
        }
    }
    for (theirs, ours) in term_names.iter().zip(Term::ALL) {
        if theirs != ours.name() {
            return Err(format!(
                "its term '{theirs}' is this toolconf's '{}'",
                ours.name()
            ));
        }
    }
    Ok(())
}

/// The inertia rule, if the library has one: the parameters it names must be the library's.
///
/// # Safety
/// `c`'s inertia rule text, if it has one, is NUL-terminated.
#[allow(clippy::type_complexity)]
unsafe fn inertia(c: &CInfo) -> Result<Option<([usize; 3], [usize; 3], f64, String)>, String> {
    if c.has_inertia == 0 {
        return Ok(None);
    }
    let np = c.parameter_count;
    let r = &c.inertia;
    let index = |i: u32| usize::try_from(i).ok().filter(|i| *i < np);
    let (m, pr) = (r.moments.map(index), r.products.map(index));
    if m.iter().chain(&pr).any(Option::is_none) || !r.slack.is_finite() {
        return Err("its inertia rule names a parameter it does not have".into());
    }
    Ok(Some((
        m.map(|i| i.unwrap_or(0)),
        pr.map(|i| i.unwrap_or(0)),
        r.slack,
        text(r.rule, "inertia.rule")?,
    )))
}

/// A model's name: what `--models`, a tools file's `model` column and Python take.
fn check_name(name: &str) -> Result<(), String> {
    let ok = (1..=64).contains(&name.len())
        && name.starts_with(|c: char| c.is_ascii_lowercase())
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    if ok {
        Ok(())
    } else {
        let lower = name.to_ascii_lowercase();
        let hint = match lower != name && check_name(&lower).is_ok() {
            true => format!(" ('{lower}' is)"),
            false => String::new(),
        };
        Err(format!(
            "the model name '{}' is not one: 1 to 64 of a-z, 0-9 and _, starting with a \
             letter{hint}",
            toolconf_messages::Clip(name)
        ))
    }
}

unsafe fn text(p: *const c_char, what: &str) -> Result<String, String> {
    c_text(p).ok_or_else(|| format!("its metadata's {what} is missing, too long or not UTF-8"))
}

unsafe fn texts(p: *const *const c_char, k: usize, what: &str) -> Result<Vec<String>, String> {
    if p.is_null() {
        return Err(format!("its metadata's {what} is missing"));
    }
    (0..k)
        .map(|i| text(p.add(i).read_unaligned(), what))
        .collect()
}

unsafe fn raw(p: *const f64, k: usize, what: &str) -> Result<Vec<f64>, String> {
    if p.is_null() {
        return Err(format!("its metadata's {what} is missing"));
    }
    Ok((0..k).map(|i| p.add(i).read_unaligned()).collect())
}

unsafe fn finite(p: *const f64, k: usize, what: &str) -> Result<Vec<f64>, String> {
    let v = raw(p, k, what)?;
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(format!(
            "its metadata's {what}[{i}] = {} is not finite",
            v[i]
        )),
        None => Ok(v),
    }
}

unsafe fn numbers_i32(p: *const i32, k: usize, what: &str) -> Result<Vec<i32>, String> {
    if p.is_null() {
        return Err(format!("its metadata's {what} is missing"));
    }
    Ok((0..k).map(|i| p.add(i).read_unaligned()).collect())
}

#[allow(clippy::type_complexity)]
unsafe fn domains(
    p: *const Domain,
    np: usize,
) -> Result<Vec<(f64, f64, bool, bool, String)>, String> {
    if p.is_null() {
        return Err("its metadata's domains are missing".into());
    }
    (0..np)
        .map(|i| {
            let d = p.add(i).read_unaligned();
            if d.lo.is_nan() || d.hi.is_nan() || d.lo > d.hi {
                return Err(format!(
                    "its metadata's domain of parameter {i} is [{}, {}]",
                    d.lo, d.hi
                ));
            }
            Ok((
                d.lo,
                d.hi,
                d.lo_open != 0,
                d.hi_open != 0,
                text(d.rule, "domain rule")?,
            ))
        })
        .collect()
}

unsafe fn constraints(c: &CInfo, np: usize) -> Result<Vec<(Vec<f64>, String)>, String> {
    if c.constraint_count > 1024 || (c.constraint_count > 0 && c.constraints.is_null()) {
        return Err(format!(
            "its metadata gives {} constraints it does not hold",
            c.constraint_count
        ));
    }
    (0..c.constraint_count)
        .map(|i| {
            let k = c.constraints.add(i).read_unaligned();
            Ok((
                finite(k.coefficients, np, "constraint coefficients")?,
                text(k.rule, "constraint rule")?,
            ))
        })
        .collect()
}
