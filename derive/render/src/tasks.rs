//! The Rust each task needs, decided here so that the templates only loop: the task's variant of
//! `TaskKind` (its name in CamelCase), how a model's sensitivity function's outputs fill the
//! three kinematic terms, which precisions its control confidence takes, each default goal or
//! precision (zero for a term the task does not use), and the terms as `Term` variants.
//!
//! The tasks are those of `derive/tasks.toml`, the same for every model; [`task_list`] checks
//! that every model's IR agrees before the registry renders `TaskKind` from them.

use serde::Serialize;

use crate::ir::{Ir, Task, Term};
use crate::RenderError;

/// `arm2_exact` → `Arm2Exact`, `position` → `Position`.
pub fn camel_case(name: &str) -> String {
    name.split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

/// A Rust string literal of `text` (quotes and backslashes escaped).
pub fn string_literal(text: &str) -> String {
    format!("{text:?}")
}

impl Term {
    /// The runtime's `Term` variant (`Term::ThetaDot`).
    fn variant(self) -> String {
        format!("Term::{}", camel_case(self.name()))
    }

    /// The field of `TaskSensitivities` that holds ∂(term)/∂U, and the sensitivity function's
    /// output of that name.
    fn sensitivity(self) -> String {
        format!("d_{}_du", self.name())
    }

    /// The name of the model's constant of a task's default goal for this term.
    fn goal_constant(self) -> String {
        format!("GOAL_{}", self.name().to_uppercase())
    }

    /// The name of the model's constant of a task's default precision for this term.
    fn precision_constant(self) -> String {
        format!("PRECISION_{}", self.name().to_uppercase())
    }
}

/// `field: value,` of a struct literal.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FieldValue {
    pub field: String,
    pub value: String,
}

/// `pub const GOAL_THETA: [f64; count] = [values];` of a task's module.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GoalView<'a> {
    pub term: &'static str,
    pub constant: String,
    pub count: usize,
    pub values: &'a [String],
}

/// `pub const PRECISION_THETA: f64 = rust;` of a task's module.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrecisionView<'a> {
    pub term: &'static str,
    pub constant: String,
    pub rust: &'a str,
}

/// What the templates render of one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskView<'a> {
    pub name: &'a str,
    pub index: u8,
    pub title: &'a str,
    pub doc: &'a str,
    /// The task's terms' names, and how many.
    pub terms: Vec<&'static str>,
    pub term_count: usize,
    pub goals: Vec<GoalView<'a>>,
    pub precisions: Vec<PrecisionView<'a>>,
    pub confidence_function: &'a str,
    pub gradient_function: &'a str,
    /// `TaskKind`'s variant.
    pub variant: String,
    /// `let <outputs> = <task>_sensitivity(params);`
    pub sensitivity_binding: String,
    /// `TaskSensitivities`' fields: `Some(d_theta_du)` or `None` per kinematic term.
    pub sensitivity_fields: Vec<FieldValue>,
    /// The precisions the task's confidence functions take: `p_theta, p_u`.
    pub confidence_args: String,
    /// `TaskDefaults`' fields: the task module's constant, or zero for a term it does not use.
    pub default_fields: Vec<FieldValue>,
    pub term_variants: Vec<String>,
    pub error_variant: String,
    pub title_literal: String,
    pub doc_literal: String,
}

/// The task's view; an error for a sensitivity of a term that has none or a goal or precision
/// of a term the task does not use.
pub fn task_view(task: &Task) -> Result<TaskView<'_>, RenderError> {
    let name = task.name.as_str();
    let bad = |what: String| RenderError::Task(format!("task '{name}': {what}"));
    let used = &task.sensitivity_terms;
    if let Some(t) = used.iter().find(|t| !Term::KINEMATIC.contains(t)) {
        return Err(bad(format!("'{}' has no sensitivity ∂/∂U", t.name())));
    }
    if let Some(t) = used.iter().find(|t| !task.terms.contains(t)) {
        return Err(bad(format!(
            "a sensitivity of '{}', which is not among its terms",
            t.name()
        )));
    }
    if let Some(g) = task.goals.iter().find(|g| !used.contains(&g.term)) {
        return Err(bad(format!(
            "a goal for '{}', which has no sensitivity",
            g.term.name()
        )));
    }
    if let Some(p) = task
        .precisions
        .iter()
        .find(|p| !task.terms.contains(&p.term))
    {
        return Err(bad(format!(
            "a precision for '{}', which is not among its terms",
            p.term.name()
        )));
    }
    let outputs: Vec<String> = used.iter().map(|t| t.sensitivity()).collect();
    let sensitivity_fields = Term::KINEMATIC
        .iter()
        .map(|t| FieldValue {
            field: t.sensitivity(),
            value: if used.contains(t) {
                format!("Some({})", t.sensitivity())
            } else {
                "None".to_string()
            },
        })
        .collect();
    let goals = Term::KINEMATIC.iter().map(|t| FieldValue {
        field: format!("goal_{}", t.name()),
        value: if used.contains(t) {
            format!("{name}::{}", t.goal_constant())
        } else {
            "[0.0; DOF]".to_string()
        },
    });
    let precisions = Term::ALL.iter().map(|t| FieldValue {
        field: format!("precision_{}", t.name()),
        value: if task.terms.contains(t) {
            format!("{name}::{}", t.precision_constant())
        } else {
            "0.0".to_string()
        },
    });
    Ok(TaskView {
        name,
        index: task.index,
        title: &task.title,
        doc: &task.doc,
        terms: task.terms.iter().map(|t| t.name()).collect(),
        term_count: task.terms.len(),
        goals: task
            .goals
            .iter()
            .map(|g| GoalView {
                term: g.term.name(),
                constant: g.term.goal_constant(),
                count: g.rust.len(),
                values: &g.rust,
            })
            .collect(),
        precisions: task
            .precisions
            .iter()
            .map(|p| PrecisionView {
                term: p.term.name(),
                constant: p.term.precision_constant(),
                rust: &p.rust,
            })
            .collect(),
        confidence_function: &task.confidence_function,
        gradient_function: &task.gradient_function,
        variant: camel_case(name),
        sensitivity_binding: format!(
            "let {} = {}(params);",
            binding_pattern(&outputs),
            task.sensitivity_function
        ),
        sensitivity_fields,
        confidence_args: task
            .terms
            .iter()
            .map(|t| format!("p_{}", t.name()))
            .collect::<Vec<_>>()
            .join(", "),
        default_fields: goals.chain(precisions).collect(),
        term_variants: task.terms.iter().map(|t| t.variant()).collect(),
        error_variant: task.error.variant(),
        title_literal: string_literal(&task.title),
        doc_literal: string_literal(&task.doc),
    })
}

/// The pattern that binds a function's outputs: a one-output function returns the matrix
/// itself, not a 1-tuple.
pub fn binding_pattern(outputs: &[String]) -> String {
    match outputs {
        [one] => one.clone(),
        many => format!("({})", many.join(", ")),
    }
}

/// The IR's tasks, each [`task_view`].
pub fn task_views(ir: &Ir) -> Result<Vec<TaskView<'_>>, RenderError> {
    ir.tasks.iter().map(task_view).collect()
}

/// The tasks every model shares (from `derive/tasks.toml`), for the registry: an error names the
/// first model whose task list differs from the first model's.
pub fn task_list(irs: &[Ir]) -> Result<Vec<TaskView<'_>>, RenderError> {
    let Some(first) = irs.first() else {
        return Ok(Vec::new());
    };
    let names = |ir: &Ir| -> Vec<String> { ir.tasks.iter().map(|t| t.name.clone()).collect() };
    let expected = names(first);
    for ir in &irs[1..] {
        if names(ir) != expected {
            return Err(RenderError::Task(format!(
                "model {:?} has tasks {:?}, the first model has {:?}: every model is derived with the same derive/tasks.toml",
                ir.model.name,
                names(ir),
                expected
            )));
        }
    }
    task_views(first)
}

/// "position, velocity or acceleration (or 1, 2, 3)": how messages list the tasks, as a Rust
/// string literal.
pub fn task_choices(tasks: &[TaskView]) -> String {
    let names: Vec<&str> = tasks.iter().map(|t| t.name).collect();
    let numbers: Vec<String> = tasks.iter().map(|t| t.index.to_string()).collect();
    let names = match names.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    string_literal(&format!("{names} (or {})", numbers.join(", ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn task(name: &str, terms: &[&str], error: &str) -> Task {
        let used: Vec<&str> = ["theta", "theta_dot", "theta_ddot"]
            .into_iter()
            .filter(|t| terms.contains(t))
            .collect();
        let quoted = |ts: &[&str]| {
            ts.iter()
                .map(|t| format!("{t:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let text = format!(
            r#"{{"name": {name:?}, "index": 1, "title": "T", "doc": "D", "terms": [{}],
                "sensitivity_terms": [{}], "error": {error:?},
                "sensitivity_function": "{name}_sensitivity",
                "confidence_function": "{name}_control_confidence",
                "gradient_function": "{name}_logdet_gradient", "goals": [], "precisions": []}}"#,
            quoted(terms),
            quoted(&used)
        );
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
    }

    #[test]
    fn one_output_binds_the_matrix_and_unused_terms_are_none_or_zero() {
        let task = task("hold", &["theta_ddot", "u"], "theta_ddot");
        let t = task_view(&task).unwrap();
        assert_eq!(
            t.sensitivity_binding,
            "let d_theta_ddot_du = hold_sensitivity(params);"
        );
        assert_eq!(t.sensitivity_fields[0].value, "None");
        assert_eq!(t.sensitivity_fields[2].value, "Some(d_theta_ddot_du)");
        assert_eq!(t.default_fields[0].value, "[0.0; DOF]");
        assert_eq!(t.default_fields[2].value, "hold::GOAL_THETA_DDOT");
        assert_eq!(t.default_fields[3].value, "0.0");
        assert_eq!(t.default_fields[6].value, "hold::PRECISION_U");
        assert_eq!(t.confidence_args, "p_theta_ddot, p_u");
        assert_eq!(t.variant, "Hold");
        assert_eq!(t.error_variant, "Term::ThetaDdot");
    }

    #[test]
    fn several_outputs_bind_a_tuple_in_term_order() {
        let task = task("reach", &["theta", "theta_dot", "u"], "theta");
        let t = task_view(&task).unwrap();
        assert_eq!(
            t.sensitivity_binding,
            "let (d_theta_du, d_theta_dot_du) = reach_sensitivity(params);"
        );
        assert_eq!(t.sensitivity_fields[2].value, "None");
    }

    #[test]
    fn an_unknown_term_is_an_error_naming_it() {
        let text = r#"{"name": "x", "index": 1, "title": "T", "doc": "D", "terms": ["theta", "jerk"],
            "sensitivity_terms": [], "error": "theta", "sensitivity_function": "s",
            "confidence_function": "c", "gradient_function": "g", "goals": [], "precisions": []}"#;
        let e = serde_json::from_str::<Task>(text).unwrap_err().to_string();
        assert!(e.contains("unknown variant `jerk`"), "{e}");
    }

    #[test]
    fn models_with_other_tasks_are_an_error_naming_the_model() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/fixtures/pendulum.json");
        let a = crate::ir::read_ir(&path).expect("fixture");
        let mut b = a.clone();
        b.model.name = "other".into();
        b.tasks[0].name = "hold".into();
        let e = task_list(&[a, b]).unwrap_err().to_string();
        assert!(e.contains("model \"other\" has tasks"), "{e}");
    }

    #[test]
    fn a_sensitivity_of_the_control_is_an_error() {
        let mut t = task("x", &["theta", "u"], "theta");
        t.sensitivity_terms.push(Term::U);
        let e = task_view(&t).unwrap_err().to_string();
        assert!(e.contains("'u' has no sensitivity"), "{e}");
    }
}
