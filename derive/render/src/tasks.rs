//! The Rust each task needs, decided here so that the templates only loop: the task's variant of
//! `TaskKind` (its name in CamelCase), how a model's sensitivity function's outputs fill the
//! three kinematic terms, which precisions its control confidence takes, each default goal or
//! precision (zero for a term the task does not use), and the terms as `Term` variants.
//!
//! The tasks are those of `derive/tasks.toml`, the same for every model; [`task_list`] checks
//! that every model's IR agrees before the registry renders `TaskKind` from them.

use serde_json::{json, Value};

use crate::RenderError;

/// The free-energy terms (eq. free_energy), in the order the runtime's `Term` lists them.
const TERMS: [&str; 4] = ["theta", "theta_dot", "theta_ddot", "u"];
/// The terms with a sensitivity ∂(term)/∂U (the control `u` has none).
const KINEMATIC: [&str; 3] = ["theta", "theta_dot", "theta_ddot"];

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

fn text<'a>(v: &'a Value, key: &str, task: &str) -> Result<&'a str, RenderError> {
    v.get(key)
        .and_then(Value::as_str)
        .ok_or_else(|| RenderError::Task(format!("task '{task}' has no string '{key}'")))
}

fn strings(v: &Value, key: &str, task: &str) -> Result<Vec<String>, RenderError> {
    v.get(key)
        .and_then(Value::as_array)
        .and_then(|a| a.iter().map(|x| x.as_str().map(String::from)).collect())
        .ok_or_else(|| RenderError::Task(format!("task '{task}' has no string list '{key}'")))
}

/// The task's IR entry with the Rust decisions added (`variant`, `sensitivity_binding`,
/// `sensitivity_fields`, `confidence_args`, `default_fields`, `term_variants`, `error_variant`).
pub fn with_rust(task: &Value) -> Result<Value, RenderError> {
    let name = text(task, "name", "?")?;
    let terms = strings(task, "terms", name)?;
    let used = strings(task, "sensitivity_terms", name)?;
    let error = text(task, "error", name)?;
    let sensitivity = text(task, "sensitivity_function", name)?;
    for t in terms.iter().chain(std::iter::once(&error.to_string())) {
        if !TERMS.contains(&t.as_str()) {
            return Err(RenderError::Task(format!(
                "task '{name}': unknown term '{t}'"
            )));
        }
    }
    let outputs: Vec<String> = used.iter().map(|t| format!("d_{t}_du")).collect();
    // A one-output function returns the matrix itself, not a 1-tuple.
    let pattern = match outputs.as_slice() {
        [one] => one.clone(),
        many => format!("({})", many.join(", ")),
    };
    let sensitivity_fields: Vec<Value> = KINEMATIC
        .iter()
        .map(|t| {
            let field = format!("d_{t}_du");
            let value = if used.iter().any(|u| u == t) {
                format!("Some({field})")
            } else {
                "None".to_string()
            };
            json!({ "field": field, "value": value })
        })
        .collect();
    let mut default_fields = Vec::new();
    for t in KINEMATIC {
        let value = if used.iter().any(|u| u == t) {
            format!("{name}::GOAL_{}", t.to_uppercase())
        } else {
            "[0.0; DOF]".to_string()
        };
        default_fields.push(json!({ "field": format!("goal_{t}"), "value": value }));
    }
    for t in TERMS {
        let value = if terms.iter().any(|u| u == t) {
            format!("{name}::PRECISION_{}", t.to_uppercase())
        } else {
            "0.0".to_string()
        };
        default_fields.push(json!({ "field": format!("precision_{t}"), "value": value }));
    }
    let mut out = task.clone();
    out["variant"] = Value::from(camel_case(name));
    out["sensitivity_binding"] = Value::from(format!("let {pattern} = {sensitivity}(params);"));
    out["sensitivity_fields"] = Value::from(sensitivity_fields);
    out["confidence_args"] = Value::from(
        terms
            .iter()
            .map(|t| format!("p_{t}"))
            .collect::<Vec<_>>()
            .join(", "),
    );
    out["default_fields"] = Value::from(default_fields);
    out["term_variants"] = Value::from(
        terms
            .iter()
            .map(|t| format!("Term::{}", camel_case(t)))
            .collect::<Vec<_>>(),
    );
    out["error_variant"] = Value::from(format!("Term::{}", camel_case(error)));
    out["title_literal"] = Value::from(format!("{:?}", text(task, "title", name)?));
    out["doc_literal"] = Value::from(format!("{:?}", text(task, "doc", name)?));
    Ok(out)
}

/// The IR's tasks, each [`with_rust`].
pub fn tasks_with_rust(ir: &Value) -> Result<Vec<Value>, RenderError> {
    ir.get("tasks")
        .and_then(Value::as_array)
        .ok_or_else(|| RenderError::Task("the IR has no task list".into()))?
        .iter()
        .map(with_rust)
        .collect()
}

/// The tasks every model shares (from `derive/tasks.toml`), for the registry: an error names the
/// first model whose task list differs from the first model's.
pub fn task_list(irs: &[Value]) -> Result<Vec<Value>, RenderError> {
    let Some(first) = irs.first() else {
        return Ok(Vec::new());
    };
    let names = |ir: &Value| -> Vec<Value> {
        ir.get("tasks")
            .and_then(Value::as_array)
            .map(|a| a.iter().map(|t| t["name"].clone()).collect())
            .unwrap_or_default()
    };
    let expected = names(first);
    for ir in &irs[1..] {
        if names(ir) != expected {
            let model = ir.pointer("/model/name").cloned().unwrap_or(Value::Null);
            return Err(RenderError::Task(format!(
                "model {model} has tasks {:?}, the first model has {:?}: every model is derived with the same derive/tasks.toml",
                names(ir),
                expected
            )));
        }
    }
    tasks_with_rust(first)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn task(name: &str, terms: &[&str], error: &str) -> Value {
        let used: Vec<&str> = KINEMATIC
            .iter()
            .copied()
            .filter(|t| terms.contains(t))
            .collect();
        json!({
            "name": name, "title": "T", "doc": "D", "terms": terms, "sensitivity_terms": used,
            "error": error, "sensitivity_function": format!("{name}_sensitivity"),
        })
    }

    #[test]
    fn one_output_binds_the_matrix_and_unused_terms_are_none_or_zero() {
        let t = with_rust(&task("hold", &["theta_ddot", "u"], "theta_ddot")).unwrap();
        assert_eq!(
            t["sensitivity_binding"],
            "let d_theta_ddot_du = hold_sensitivity(params);"
        );
        assert_eq!(t["sensitivity_fields"][0]["value"], "None");
        assert_eq!(t["sensitivity_fields"][2]["value"], "Some(d_theta_ddot_du)");
        assert_eq!(t["default_fields"][0]["value"], "[0.0; DOF]");
        assert_eq!(t["default_fields"][2]["value"], "hold::GOAL_THETA_DDOT");
        assert_eq!(t["default_fields"][3]["value"], "0.0");
        assert_eq!(t["default_fields"][6]["value"], "hold::PRECISION_U");
        assert_eq!(t["confidence_args"], "p_theta_ddot, p_u");
        assert_eq!(t["variant"], "Hold");
        assert_eq!(t["error_variant"], "Term::ThetaDdot");
    }

    #[test]
    fn several_outputs_bind_a_tuple_in_term_order() {
        let t = with_rust(&task("reach", &["theta", "theta_dot", "u"], "theta")).unwrap();
        assert_eq!(
            t["sensitivity_binding"],
            "let (d_theta_du, d_theta_dot_du) = reach_sensitivity(params);"
        );
        assert_eq!(t["sensitivity_fields"][2]["value"], "None");
    }

    #[test]
    fn an_unknown_term_and_disagreeing_models_are_errors() {
        assert!(with_rust(&task("x", &["theta", "jerk"], "theta")).is_err());
        let a = json!({"model": {"name": "a"}, "tasks": [task("p", &["theta", "u"], "theta")]});
        let b = json!({"model": {"name": "b"}, "tasks": [task("q", &["theta", "u"], "theta")]});
        let e = task_list(&[a, b]).unwrap_err().to_string();
        assert!(e.contains("\"b\""), "{e}");
    }
}
