//! The Rust each task needs, decided here so that the templates only loop: the task's variant of
//! `TaskKind` (its name in CamelCase), how a model's sensitivity function's outputs fill the
//! kinematic terms, which precisions its control confidence takes, each default goal or
//! precision (zero for a term the task does not use), the terms as `Term` variants, and the
//! formulation of its sensitivities in words.
//!
//! The tasks are those of `derive/tasks.toml`, the same for every model; [`task_list`] checks
//! that every model's IR agrees before the registry renders `TaskKind` from them.

use serde::Serialize;

use crate::escape::comment;
use crate::ir::{ChosenBy, Formulation, Goal, Ir, Precision, Source, Task, Term};
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

/// A Rust string literal of `text` ([`crate::escape::rust_string`]).
pub fn string_literal(text: &str) -> String {
    crate::escape::rust_string(text)
}

/// The runtime's `Term` variant of a term named `name` (`Term::ThetaDot`).
fn variant(name: &str) -> String {
    format!("Term::{}", camel_case(name))
}

/// The name of the model's constant of a task's default goal for a term.
fn goal_constant(name: &str) -> String {
    format!("GOAL_{}", name.to_uppercase())
}

/// The name of the model's constant of a task's default precision for a term.
fn precision_constant(name: &str) -> String {
    format!("PRECISION_{}", name.to_uppercase())
}

/// The sensitivity function's output, and the local, that holds ∂(term)/∂U.
fn sensitivity(name: &str) -> String {
    format!("d_{name}_du")
}

/// What the templates render of one term of the free energy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TermView<'a> {
    pub name: &'a str,
    /// `Term`'s variant, without the `Term::` path (`ThetaDot`).
    pub variant: String,
    pub index: usize,
    pub symbol_literal: String,
    /// Its doc, one line of a comment; as a Rust string literal.
    pub doc: String,
    pub doc_literal: String,
    pub label_literal: String,
    pub unit_literal: String,
    /// `Read::State { block: 0 }`, `Read::Tip { order: 1 }`.
    pub read: String,
    /// `Some("joint_angle")` or `None`.
    pub goal_range: String,
    pub has_sensitivity: bool,
}

/// The term list's view; an error for a repeated name, a term nothing can read, or a list
/// without exactly one control term.
pub fn term_views(terms: &[Term]) -> Result<Vec<TermView<'_>>, RenderError> {
    let bad = |what: String| RenderError::Task(format!("terms: {what}"));
    for (i, t) in terms.iter().enumerate() {
        if terms[..i]
            .iter()
            .any(|o| o.name == t.name || o.read == t.read)
        {
            return Err(bad(format!(
                "'{}' repeats an earlier term's name or reading",
                t.name
            )));
        }
    }
    if terms.iter().filter(|t| !t.has_sensitivity()).count() != 1 {
        return Err(bad("exactly one term must be read from the control".into()));
    }
    Ok(terms.iter().enumerate().map(term_view).collect())
}

fn term_view((index, t): (usize, &Term)) -> TermView<'_> {
    let read = match t.read.source {
        Source::State => format!("Read::State {{ block: {} }}", t.read.block),
        Source::StateRate => format!("Read::StateRate {{ block: {} }}", t.read.block),
        Source::Control => "Read::Control".to_string(),
        Source::Tip => format!("Read::Tip {{ order: {} }}", t.read.block),
    };
    TermView {
        name: &t.name,
        variant: camel_case(&t.name),
        index,
        symbol_literal: string_literal(&t.symbol),
        doc: comment(&t.doc),
        doc_literal: string_literal(&t.doc),
        label_literal: string_literal(&t.label),
        unit_literal: string_literal(&t.unit),
        read,
        goal_range: t
            .goal_range
            .as_deref()
            .map_or("None".into(), |r| format!("Some({})", string_literal(r))),
        has_sensitivity: t.has_sensitivity(),
    }
}

/// `Term::ThetaDdot, ...`: the IR's `cost_order`, which must name every term once.
pub fn cost_order(ir: &Ir) -> Result<Vec<String>, RenderError> {
    let mut named: Vec<&str> = ir.cost_order.iter().map(String::as_str).collect();
    let mut all: Vec<&str> = ir.terms.iter().map(|t| t.name.as_str()).collect();
    named.sort_unstable();
    all.sort_unstable();
    if named != all {
        return Err(RenderError::Task(format!(
            "cost_order {:?} must name every term once ({})",
            ir.cost_order,
            all.join(", ")
        )));
    }
    Ok(ir.cost_order.iter().map(|t| variant(t)).collect())
}

/// What the templates render of one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskView<'a> {
    pub name: &'a str,
    pub index: u8,
    /// Its title and doc, each one line of a comment.
    pub title: String,
    pub doc: String,
    /// The task's terms' names, and how many.
    pub terms: Vec<&'a str>,
    pub term_count: usize,
    pub goals: Vec<GoalView<'a>>,
    pub precisions: Vec<PrecisionView<'a>>,
    pub confidence_function: &'a str,
    pub gradient_function: &'a str,
    /// `TaskKind`'s variant.
    pub variant: String,
    /// `let <outputs> = <task>_sensitivity(params);`
    pub sensitivity_binding: String,
    /// `TaskSensitivities::d_du`, one per term: `Some(d_theta_du)` or `None`.
    pub sensitivity_values: Vec<String>,
    /// The precisions the task's confidence functions take: `&precision[Term::Theta as usize], ...`.
    pub confidence_args: String,
    /// `TaskDefaults::goal` and `::precision`, one per term: the task module's constant, or
    /// zero for a term it does not use.
    pub default_goals: Vec<String>,
    pub default_precisions: Vec<String>,
    pub term_variants: Vec<String>,
    pub error_variant: String,
    pub title_literal: String,
    pub doc_literal: String,
    /// The formulation of its sensitivities in this model, in words (the reports' line).
    pub formulation: String,
    /// What its sensitivity function's doc comment adds: a paragraph naming a formulation other
    /// than the paper's, none for the paper's (whose formulas the outputs' docs state).
    pub sensitivity_notes: Vec<String>,
}

/// `pub const GOAL_THETA: [f64; count] = [values];` of a task's module.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GoalView<'a> {
    pub term: &'a str,
    pub constant: String,
    pub count: usize,
    pub values: &'a [String],
}

impl<'a> GoalView<'a> {
    fn of(goal: &'a Goal) -> Self {
        GoalView {
            term: &goal.term,
            constant: goal_constant(&goal.term),
            count: goal.rust.len(),
            values: &goal.rust,
        }
    }
}

/// `pub const PRECISION_THETA: f64 = rust;` of a task's module.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrecisionView<'a> {
    pub term: &'a str,
    pub constant: String,
    pub rust: &'a str,
}

impl<'a> PrecisionView<'a> {
    fn of(precision: &'a Precision) -> Self {
        PrecisionView {
            term: &precision.term,
            constant: precision_constant(&precision.term),
            rust: &precision.rust,
        }
    }
}

/// Checks a task's terms against the term list: known names, sensitivities only of terms that
/// have one and the task uses, goals only of those, precisions only of the task's terms.
fn check_task(task: &Task, terms: &[Term]) -> Result<(), RenderError> {
    let bad = |what: String| RenderError::Task(format!("task '{}': {what}", task.name));
    let find = |name: &str| terms.iter().find(|t| t.name == name);
    let named = task
        .terms
        .iter()
        .chain(&task.sensitivity_terms)
        .chain(std::iter::once(&task.error))
        .chain(task.goals.iter().map(|g| &g.term))
        .chain(task.precisions.iter().map(|p| &p.term));
    for name in named {
        if find(name).is_none() {
            let known: Vec<&str> = terms.iter().map(|t| t.name.as_str()).collect();
            return Err(bad(format!(
                "unknown term '{name}' (terms: {})",
                known.join(", ")
            )));
        }
    }
    let used = &task.sensitivity_terms;
    if let Some(t) = used
        .iter()
        .find(|t| !find(t).is_some_and(Term::has_sensitivity))
    {
        return Err(bad(format!("'{t}' has no sensitivity ∂/∂U")));
    }
    if let Some(t) = used.iter().find(|t| !task.terms.contains(t)) {
        return Err(bad(format!(
            "a sensitivity of '{t}', which is not among its terms"
        )));
    }
    if !used.contains(&task.error) {
        return Err(bad(format!(
            "its error term '{}' has no sensitivity in it",
            task.error
        )));
    }
    if let Some(g) = task.goals.iter().find(|g| !used.contains(&g.term)) {
        return Err(bad(format!(
            "a goal for '{}', which has no sensitivity",
            g.term
        )));
    }
    if let Some(p) = task
        .precisions
        .iter()
        .find(|p| !task.terms.contains(&p.term))
    {
        return Err(bad(format!(
            "a precision for '{}', which is not among its terms",
            p.term
        )));
    }
    Ok(())
}

/// The task's view (after [`check_task`]); `terms` is the IR's term list.
pub fn task_view<'a>(task: &'a Task, terms: &'a [Term]) -> Result<TaskView<'a>, RenderError> {
    check_task(task, terms)?;
    let name = task.name.as_str();
    let used = &task.sensitivity_terms;
    let uses = |t: &Term| task.terms.contains(&t.name);
    let senses = |t: &Term| used.contains(&t.name);
    let outputs: Vec<String> = used.iter().map(|t| sensitivity(t)).collect();
    let control = terms.iter().find(|t| !t.has_sensitivity());
    let confidence_terms = used
        .iter()
        .map(String::as_str)
        .chain(control.map(|t| t.name.as_str()));
    Ok(TaskView {
        name,
        index: task.index,
        title: comment(&task.title),
        doc: comment(&task.doc),
        terms: task.terms.iter().map(String::as_str).collect(),
        term_count: task.terms.len(),
        goals: task.goals.iter().map(GoalView::of).collect(),
        precisions: task.precisions.iter().map(PrecisionView::of).collect(),
        confidence_function: &task.confidence_function,
        gradient_function: &task.gradient_function,
        variant: camel_case(name),
        sensitivity_binding: format!(
            "let {} = {}(params);",
            binding_pattern(&outputs),
            task.sensitivity_function
        ),
        sensitivity_values: per_term(
            terms,
            senses,
            |t| format!("Some({})", sensitivity(t)),
            "None",
        ),
        confidence_args: confidence_terms
            .map(|t| format!("&precision[{} as usize]", variant(t)))
            .collect::<Vec<_>>()
            .join(", "),
        default_goals: per_term(
            terms,
            senses,
            |t| format!("{name}::{}", goal_constant(t)),
            "[0.0; DOF]",
        ),
        default_precisions: per_term(
            terms,
            uses,
            |t| format!("{name}::{}", precision_constant(t)),
            "0.0",
        ),
        term_variants: task.terms.iter().map(|t| variant(t)).collect(),
        error_variant: variant(&task.error),
        title_literal: string_literal(&task.title),
        doc_literal: string_literal(&task.doc),
        formulation: comment(&formulation_text(&task.formulation)),
        sensitivity_notes: sensitivity_notes(&task.formulation)
            .iter()
            .map(|n| comment(n))
            .collect(),
    })
}

/// One entry per term of `terms`: `given` of the term's name where `has` the term, else `none`.
fn per_term(
    terms: &[Term],
    has: impl Fn(&Term) -> bool,
    given: impl Fn(&str) -> String,
    none: &str,
) -> Vec<String> {
    terms
        .iter()
        .map(|t| {
            if has(t) {
                given(&t.name)
            } else {
                none.to_string()
            }
        })
        .collect()
}

/// Why the model has the formulation, in words.
fn chosen_by(by: ChosenBy) -> &'static str {
    match by {
        ChosenBy::Default => "the default",
        ChosenBy::DefaultFor => "the default for this model's kind of dynamics, its `default_for`",
        ChosenBy::Description => "chosen by the model description's `[formulation]`",
    }
}

/// "the paper's formulas (the default)", "`static_gain` of ... (why), not the paper's formulas:
/// doc", without a final full stop.
pub fn formulation_text(f: &Formulation) -> String {
    if f.name == Formulation::PAPER {
        format!("the paper's formulas ({})", chosen_by(f.chosen_by))
    } else {
        format!(
            "`{}` of `derive/tasks.toml`'s `[task.formulations]` ({}), not the paper's formulas: {}",
            f.name,
            chosen_by(f.chosen_by),
            f.doc.trim_end_matches('.')
        )
    }
}

/// The sensitivity function's extra doc paragraph: only for a named formulation, so that a
/// model with the paper's formulas keeps its functions' docs as they were.
fn sensitivity_notes(f: &Formulation) -> Vec<String> {
    if f.name == Formulation::PAPER {
        Vec::new()
    } else {
        vec![format!("Formulation: {}.", formulation_text(f))]
    }
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
    term_views(&ir.terms)?;
    ir.tasks.iter().map(|t| task_view(t, &ir.terms)).collect()
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
        if ir.terms != first.terms || ir.cost_order != first.cost_order {
            return Err(RenderError::Task(format!(
                "model {:?} has other terms than the first model, {:?}: every model is derived with the same derive/tasks.toml",
                ir.model.name, first.model.name
            )));
        }
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

    /// The paper's four terms and the tip's two, as tasks.toml lists them.
    fn terms() -> Vec<Term> {
        let term = |name: &str, source: &str, block: usize, range: Option<&str>| {
            let range = range.map_or(String::new(), |r| format!(r#", "goal_range": "{r}""#));
            let text = format!(
                r#"{{"name": "{name}", "symbol": "s", "latex": "l", "doc": "d", "label": "a", "unit": "u",
                    "read": {{"source": "{source}", "block": {block}}}{range}}}"#
            );
            serde_json::from_str::<Term>(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
        };
        vec![
            term("theta", "state", 0, Some("joint_angle")),
            term("theta_dot", "state", 1, Some("joint_rate")),
            term("theta_ddot", "state_rate", 1, Some("joint_acceleration")),
            term("u", "control", 0, None),
            term("tip", "tip", 0, Some("tip_position")),
            term("tip_dot", "tip", 1, Some("tip_velocity")),
        ]
    }

    fn task(name: &str, terms: &[&str], error: &str) -> Task {
        let used: Vec<&str> = ["theta", "theta_dot", "theta_ddot", "tip", "tip_dot"]
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
                "gradient_function": "{name}_logdet_gradient", "goals": [], "precisions": [],
                "formulation": {{"name": "paper", "doc": "", "chosen_by": "default"}}}}"#,
            quoted(terms),
            quoted(&used)
        );
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
    }

    #[test]
    fn one_output_binds_the_matrix_and_unused_terms_are_none_or_zero() {
        let (task, terms) = (task("hold", &["theta_ddot", "u"], "theta_ddot"), terms());
        let t = task_view(&task, &terms).unwrap();
        assert_eq!(
            t.sensitivity_binding,
            "let d_theta_ddot_du = hold_sensitivity(params);"
        );
        assert_eq!(
            t.sensitivity_values,
            [
                "None",
                "None",
                "Some(d_theta_ddot_du)",
                "None",
                "None",
                "None"
            ]
        );
        assert_eq!(t.default_goals[0], "[0.0; DOF]");
        assert_eq!(t.default_goals[2], "hold::GOAL_THETA_DDOT");
        assert_eq!(t.default_goals[3], "[0.0; DOF]");
        assert_eq!(t.default_precisions[0], "0.0");
        assert_eq!(t.default_precisions[3], "hold::PRECISION_U");
        assert_eq!(
            t.confidence_args,
            "&precision[Term::ThetaDdot as usize], &precision[Term::U as usize]"
        );
        assert_eq!(t.variant, "Hold");
        assert_eq!(t.error_variant, "Term::ThetaDdot");
    }

    #[test]
    fn several_outputs_bind_a_tuple_in_term_order() {
        let (task, terms) = (
            task("reach", &["theta", "theta_dot", "u"], "theta"),
            terms(),
        );
        let t = task_view(&task, &terms).unwrap();
        assert_eq!(
            t.sensitivity_binding,
            "let (d_theta_du, d_theta_dot_du) = reach_sensitivity(params);"
        );
        assert_eq!(t.sensitivity_values[2], "None");
    }

    #[test]
    fn a_tip_task_reads_the_tip_and_fills_its_terms_slots() {
        let (task, terms) = (task("touch", &["tip", "tip_dot", "u"], "tip"), terms());
        let t = task_view(&task, &terms).unwrap();
        assert_eq!(
            t.sensitivity_binding,
            "let (d_tip_du, d_tip_dot_du) = touch_sensitivity(params);"
        );
        assert_eq!(
            t.sensitivity_values[4..],
            ["Some(d_tip_du)", "Some(d_tip_dot_du)"]
        );
        assert_eq!(t.default_goals[4], "touch::GOAL_TIP");
        assert_eq!(t.default_goals[0], "[0.0; DOF]");
        assert_eq!(t.error_variant, "Term::Tip");
        let views = term_views(&terms).unwrap();
        assert_eq!(views[4].read, "Read::Tip { order: 0 }");
        assert_eq!(views[5].read, "Read::Tip { order: 1 }");
        assert_eq!(views[5].variant, "TipDot");
    }

    #[test]
    fn a_named_formulation_is_in_the_sensitivity_doc_and_the_papers_is_not() {
        let mut task = task("reach", &["theta", "u"], "theta");
        let terms = terms();
        let paper = task_view(&task, &terms).unwrap();
        assert!(paper.sensitivity_notes.is_empty());
        assert_eq!(paper.formulation, "the paper's formulas (the default)");
        task.formulation = Formulation {
            name: "static_gain".into(),
            doc: "The static gain.".into(),
            chosen_by: ChosenBy::DefaultFor,
        };
        let named = task_view(&task, &terms).unwrap();
        assert_eq!(
            named.formulation,
            "`static_gain` of `derive/tasks.toml`'s `[task.formulations]` (the default for this \
             model's kind of dynamics, its `default_for`), not the paper's formulas: The static gain"
        );
        assert_eq!(
            named.sensitivity_notes,
            [format!("Formulation: {}.", named.formulation)]
        );
    }

    #[test]
    fn an_unknown_term_is_an_error_naming_it() {
        let t = task("x", &["theta", "jerk"], "theta");
        let e = task_view(&t, &terms()).unwrap_err().to_string();
        assert!(e.contains("unknown term 'jerk'"), "{e}");
    }

    #[test]
    fn a_term_list_needs_one_control_term_and_distinct_readings() {
        let mut list = terms();
        assert_eq!(
            term_views(&list).unwrap()[2].read,
            "Read::StateRate { block: 1 }"
        );
        list[1].read = list[0].read;
        let e = term_views(&list).unwrap_err().to_string();
        assert!(e.contains("'theta_dot' repeats"), "{e}");
        let e = term_views(&terms()[..3]).unwrap_err().to_string();
        assert!(e.contains("exactly one term"), "{e}");
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
        t.sensitivity_terms.push("u".into());
        let e = task_view(&t, &terms()).unwrap_err().to_string();
        assert!(e.contains("'u' has no sensitivity"), "{e}");
    }
}
