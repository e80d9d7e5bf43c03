//! What an IR must be beyond its shape (which [`crate::ir`]'s types check), before anything is
//! rendered from it: an IR is data, whoever wrote it (`make model IR=...` renders one a user
//! gives). Each field is one of four kinds, checked here:
//!
//! - text (titles, docs, units, LaTeX, paths, ...): every string of the document, one line with
//!   no [`refused`] character (a control character, a newline included, a line or paragraph
//!   separator, a bidirectional control, a byte-order mark); it reaches generated code only
//!   through [`crate::escape`];
//! - names (the model, its parameters and coordinates, terms, tasks, functions and their
//!   values): [`name_problem`]'s grammar, a model's name at most [`MAX_NAME`] and not one of the
//!   registry's own modules;
//! - file names (the IR's and its test vectors'): [`file_name_problem`]'s grammar, a file
//!   beside the IR and nowhere else;
//! - code (closed forms, instruction steps, element accesses, types): [`crate::code`]'s
//!   grammar.
//!
//! A refusal names the key (`model.parameters[2].unit`) and the value, one line.

use serde_json::Value;

use crate::code;
use crate::escape::{file_name_problem, name_problem, refused, shown, MAX_NAME};
use crate::ir::{Coefficients, Function, Ir, Let, Output, Sequence};

/// A field of the IR that is not what it must be: its key and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    pub key: String,
    pub problem: String,
}

type Checked = Result<(), Refusal>;

fn refuse(key: impl Into<String>, problem: String) -> Refusal {
    Refusal {
        key: key.into(),
        problem,
    }
}

/// The model names the generated registry's own modules take (description.py's
/// RESERVED_MODEL_NAMES).
pub const RESERVED_MODEL_NAMES: [&str; 7] = [
    "lib",
    "mod",
    "powi",
    "rigid_body",
    "tasks",
    "trig",
    "validity",
];

/// The longest name of anything else the IR names (a task's name is at most [`MAX_NAME`]; its
/// functions add a suffix).
const MAX_DERIVED_NAME: usize = 2 * MAX_NAME;

/// Every string of the document, wherever it is: no [`refused`] character.
pub fn check_text(value: &Value) -> Checked {
    let mut pending = vec![(String::new(), value)];
    while let Some((key, value)) = pending.pop() {
        match value {
            Value::String(text) => {
                if let Some(c) = text.chars().find(|&c| refused(c)) {
                    return Err(refuse(
                        key,
                        format!(
                            "'{}' holds the character U+{:04X}: a text field is one line with no \
                             control character",
                            shown(text),
                            c as u32
                        ),
                    ));
                }
            }
            Value::Array(items) => pending.extend(
                items
                    .iter()
                    .enumerate()
                    .rev()
                    .map(|(i, v)| (format!("{key}[{i}]"), v)),
            ),
            Value::Object(map) => pending.extend(map.iter().rev().map(|(k, v)| {
                let key = if key.is_empty() {
                    k.clone()
                } else {
                    format!("{key}.{k}")
                };
                (key, v)
            })),
            _ => {}
        }
    }
    Ok(())
}

fn name(key: impl Into<String>, value: &str, most: usize) -> Checked {
    match name_problem(value, most) {
        Some(problem) => Err(refuse(key, problem)),
        None => Ok(()),
    }
}

fn names<'a>(key: &str, values: impl IntoIterator<Item = &'a String>) -> Checked {
    values
        .into_iter()
        .enumerate()
        .try_for_each(|(i, v)| name(format!("{key}[{i}]"), v, MAX_DERIVED_NAME))
}

fn grammar(key: impl Into<String>, value: &str, rule: fn(&str) -> Result<(), String>) -> Checked {
    rule(value).map_err(|problem| {
        refuse(
            key,
            format!(
                "'{}' is not in the grammar of the IR's code: {problem}",
                shown(value)
            ),
        )
    })
}

/// The names, file names and code of the IR (module docs); its text is [`check_text`]'s.
pub fn check_ir(ir: &Ir) -> Checked {
    let m = &ir.model;
    name("model.name", &m.name, MAX_NAME)?;
    if RESERVED_MODEL_NAMES.contains(&m.name.as_str()) {
        return Err(refuse(
            "model.name",
            format!("'{}' is a module of the generated registry", m.name),
        ));
    }
    names("model.parameters", m.parameters.iter().map(|p| &p.name))?;
    names("model.state", m.state.iter().map(|v| &v.name))?;
    names("model.control", m.control.iter().map(|v| &v.name))?;
    for (i, c) in m.constants.iter().enumerate() {
        name(
            format!("model.constants[{i}].name"),
            &c.name,
            MAX_DERIVED_NAME,
        )?;
        let upper = c.name.to_uppercase();
        if c.rust != upper {
            return Err(refuse(
                format!("model.constants[{i}].rust"),
                format!(
                    "'{}' is not the constant's name in upper case, '{upper}'",
                    shown(&c.rust)
                ),
            ));
        }
    }
    for (i, v) in m.equilibrium.x.iter().chain(&m.equilibrium.u).enumerate() {
        let (part, j) = match i.checked_sub(m.equilibrium.x.len()) {
            None => ("x", i),
            Some(j) => ("u", j),
        };
        grammar(
            format!("model.equilibrium.{part}[{j}]"),
            v,
            code::expression,
        )?;
    }
    file(&ir.generator.ir, "generator.ir", ".json")?;
    file(&ir.generator.vectors, "generator.vectors", ".vectors.json")?;
    file(&ir.test_vectors.file, "test_vectors.file", ".vectors.json")?;
    names("terms", ir.terms.iter().map(|t| &t.name))?;
    names("cost_order", &ir.cost_order)?;
    for (i, t) in ir.tasks.iter().enumerate() {
        check_task(&format!("tasks[{i}]"), t)?;
    }
    for (i, f) in ir.functions.iter().enumerate() {
        check_function(&format!("functions[{i}]"), f)?;
    }
    for (i, t) in ir.templates.iter().flatten().enumerate() {
        if t != crate::ir::URDF_REPORT_TEMPLATE {
            return Err(refuse(
                format!("templates[{i}]"),
                format!("'{}' is not a template variant", shown(t)),
            ));
        }
    }
    Ok(())
}

fn file(value: &str, key: &str, suffix: &str) -> Checked {
    match file_name_problem(value, suffix) {
        Some(problem) => Err(refuse(key, problem)),
        None => Ok(()),
    }
}

fn check_task(key: &str, t: &crate::ir::Task) -> Checked {
    name(format!("{key}.name"), &t.name, MAX_NAME)?;
    names(&format!("{key}.terms"), &t.terms)?;
    names(&format!("{key}.sensitivity_terms"), &t.sensitivity_terms)?;
    name(format!("{key}.error"), &t.error, MAX_DERIVED_NAME)?;
    for (field, value) in [
        ("sensitivity_function", &t.sensitivity_function),
        ("confidence_function", &t.confidence_function),
        ("gradient_function", &t.gradient_function),
        ("formulation.name", &t.formulation.name),
    ] {
        name(format!("{key}.{field}"), value, MAX_DERIVED_NAME)?;
    }
    for (i, g) in t.goals.iter().enumerate() {
        name(format!("{key}.goals[{i}].term"), &g.term, MAX_DERIVED_NAME)?;
        for (j, v) in g.rust.iter().enumerate() {
            grammar(format!("{key}.goals[{i}].rust[{j}]"), v, code::expression)?;
        }
    }
    for (i, p) in t.precisions.iter().enumerate() {
        name(
            format!("{key}.precisions[{i}].term"),
            &p.term,
            MAX_DERIVED_NAME,
        )?;
        grammar(
            format!("{key}.precisions[{i}].rust"),
            &p.rust,
            code::expression,
        )?;
    }
    Ok(())
}

fn lets(key: &str, lets: &[Let]) -> Checked {
    for (i, l) in lets.iter().enumerate() {
        name(format!("{key}[{i}].name"), &l.name, MAX_DERIVED_NAME)?;
        grammar(format!("{key}[{i}].rust"), &l.rust, code::expression)?;
    }
    Ok(())
}

fn bindings(key: &str, bindings: &[crate::ir::Binding]) -> Checked {
    for (i, b) in bindings.iter().enumerate() {
        name(format!("{key}[{i}].name"), &b.name, MAX_DERIVED_NAME)?;
        name(format!("{key}[{i}].arg"), &b.arg, MAX_DERIVED_NAME)?;
        grammar(format!("{key}[{i}].access"), &b.access, code::access)?;
    }
    Ok(())
}

fn check_function(key: &str, f: &Function) -> Checked {
    name(format!("{key}.name"), &f.name, MAX_DERIVED_NAME)?;
    let args = f
        .args
        .iter()
        .map(|a| (a.name.as_str(), a.rust_type.as_str()));
    arguments(&format!("{key}.args"), args)?;
    for (i, o) in f.outputs.iter().enumerate() {
        output(&format!("{key}.outputs[{i}]"), o)?;
    }
    lets(&format!("{key}.constants"), &f.constants)?;
    bindings(&format!("{key}.bindings"), &f.bindings)?;
    for (i, t) in f.trig.iter().enumerate() {
        name(format!("{key}.trig[{i}].angle"), &t.angle, MAX_DERIVED_NAME)?;
        for (side, value) in [("sin", &t.sin), ("cos", &t.cos)] {
            if value != "_" {
                name(format!("{key}.trig[{i}].{side}"), value, MAX_DERIVED_NAME)?;
            }
        }
    }
    lets(&format!("{key}.compounds"), &f.compounds)?;
    lets(&format!("{key}.temporaries"), &f.temporaries)?;
    if let Some(c) = &f.coefficients {
        coefficients(&format!("{key}.coefficients"), c)?;
    }
    if let Some(s) = &f.sequence {
        sequence(&format!("{key}.sequence"), s)?;
    }
    Ok(())
}

/// Arguments (name, Rust type), `key` the array's.
fn arguments<'a>(key: &str, args: impl Iterator<Item = (&'a str, &'a str)>) -> Checked {
    for (i, (arg, rust_type)) in args.enumerate() {
        name(format!("{key}[{i}].name"), arg, MAX_DERIVED_NAME)?;
        grammar(format!("{key}[{i}].rust_type"), rust_type, code::rust_type)?;
    }
    Ok(())
}

fn output(key: &str, o: &Output) -> Checked {
    name(format!("{key}.name"), &o.name, MAX_DERIVED_NAME)?;
    grammar(format!("{key}.rust_type"), &o.rust_type, code::rust_type)?;
    for (j, e) in o.entries.iter().enumerate() {
        if let Some(rust) = &e.rust {
            grammar(format!("{key}.entries[{j}].rust"), rust, code::expression)?;
        }
    }
    Ok(())
}

fn coefficients(key: &str, c: &Coefficients) -> Checked {
    if !code::camel_case(&c.r#struct) || c.r#struct.len() > MAX_DERIVED_NAME {
        return Err(refuse(
            format!("{key}.struct"),
            format!(
                "'{}' is not a struct's name (CamelCase ASCII)",
                shown(&c.r#struct)
            ),
        ));
    }
    lets(&format!("{key}.constants"), &c.constants)?;
    bindings(&format!("{key}.bindings"), &c.bindings)?;
    lets(&format!("{key}.temporaries"), &c.temporaries)?;
    for (i, v) in c.values.iter().enumerate() {
        grammar(format!("{key}.values[{i}]"), v, code::expression)?;
    }
    let args = c
        .args
        .iter()
        .map(|a| (a.name.as_str(), a.rust_type.as_str()));
    arguments(&format!("{key}.args"), args)
}

fn sequence(key: &str, s: &Sequence) -> Checked {
    for (i, slot) in s.slots.iter().enumerate() {
        name(
            format!("{key}.slots[{i}].name"),
            &slot.name,
            MAX_DERIVED_NAME,
        )?;
    }
    for (i, step) in s.steps.iter().enumerate() {
        grammar(
            format!("{key}.steps[{i}].target"),
            &step.target,
            code::target,
        )?;
        grammar(
            format!("{key}.steps[{i}].rust"),
            &step.rust,
            code::expression,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture() -> (Value, Ir) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/fixtures/pendulum.json");
        let text = std::fs::read_to_string(path).unwrap();
        let ir = crate::ir::parse_shape(&text).expect("fixture");
        (serde_json::from_str(&text).unwrap(), ir)
    }

    #[test]
    fn the_fixture_passes() {
        let (value, ir) = fixture();
        assert_eq!(check_text(&value), Ok(()));
        assert_eq!(check_ir(&ir), Ok(()));
    }

    #[test]
    fn a_control_character_anywhere_names_its_key() {
        let (mut value, _) = fixture();
        value["model"]["parameters"][0]["unit"] = "kg\nfn".into();
        let r = check_text(&value).unwrap_err();
        assert_eq!(r.key, "model.parameters[0].unit");
        assert!(r.problem.contains("U+000A"), "{}", r.problem);
        value["model"]["parameters"][0]["unit"] = "kg".into();
        value["report"]["a"] = "\u{2029}".into();
        assert_eq!(check_text(&value).unwrap_err().key, "report.a");
    }

    #[test]
    fn names_file_names_and_code_are_checked() {
        let (_, ir) = fixture();
        let refused = |edit: &dyn Fn(&mut Ir)| {
            let mut bad = ir.clone();
            edit(&mut bad);
            check_ir(&bad).unwrap_err().key
        };
        assert_eq!(
            refused(&|i| i.model.name = "../../evil".into()),
            "model.name"
        );
        assert_eq!(refused(&|i| i.model.name = "a".repeat(65)), "model.name");
        assert_eq!(refused(&|i| i.model.name = "tasks".into()), "model.name");
        assert_eq!(
            refused(&|i| i.test_vectors.file = "../../../../etc/hostname".into()),
            "test_vectors.file"
        );
        assert_eq!(
            refused(&|i| i.functions[0].temporaries.push(Let {
                name: "s".into(),
                rust: "{ std::process::abort() }".into()
            })),
            format!(
                "functions[0].temporaries[{}].rust",
                ir.functions[0].temporaries.len()
            )
        );
        assert_eq!(
            refused(&|i| i.functions[0].args[0].rust_type = "SVector<f64, 2>; fn f() {}".into()),
            "functions[0].args[0].rust_type"
        );
        assert_eq!(
            refused(&|i| i.model.equilibrium.u[0] = "loop {}".into()),
            "model.equilibrium.u[0]"
        );
    }
}
