//! The Rust of each generated function, decided here so that templates/model.rs.tera only loops:
//! its signature and return type, the doc comment's cost lines, its body (a closed form's `let`s
//! and output entries, or CasADi's instruction sequence on its work slots: one shape for both),
//! and its per-tool coefficient struct.
//!
//! Two functions whose coefficients are the same (a URDF arm's plant and its Jacobian both take
//! the last body's inertia with the tool and the constant torque, the same CasADi function) share
//! one struct: the first function's, which the second names by a type alias.

use serde::Serialize;
use serde_json::Value;

use crate::escape::comment;
use crate::ir::{Coefficients, Cost, Function, Output, Step};
use crate::model_view::comment_all;
use crate::tasks::binding_pattern;
use crate::RenderError;

/// `let pattern = value;`
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LetView {
    pub pattern: String,
    pub value: String,
}

/// `target = value;`
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Assignment {
    pub target: String,
    pub value: String,
}

/// An output's declaration, `let binding = <rust_type>::zeros();`, then its entries' assignments.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputView<'a> {
    /// Its doc, one line of a comment.
    pub doc: String,
    pub binding: String,
    pub rust_type: &'a str,
    pub assignments: Vec<Assignment>,
}

/// A function's body: its `let`s, its outputs, then (for an instruction sequence) the work slots'
/// declarations, the steps and the mirrored entries of symmetric outputs, and the value returned.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyView<'a> {
    pub lets: Vec<LetView>,
    pub outputs: Vec<OutputView<'a>>,
    pub slots: Vec<String>,
    pub steps: &'a [Step],
    pub mirrors: Vec<Assignment>,
    pub result: String,
}

/// A coefficient struct's definition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StructView<'a> {
    pub name: &'a str,
    pub count: usize,
    /// Its cost, once per tool, in words.
    pub cost: String,
    pub lets: Vec<LetView>,
    pub values: &'a [String],
}

/// `pub type name = <struct>;`: a function's coefficients that are `first`'s.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AliasView<'a> {
    pub name: &'a str,
    pub first: &'a str,
}

/// What a function with per-tool coefficients adds: the struct (where this function is the
/// first to take it) or the alias this function names it by, and `<name>_with`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CoefficientsView<'a> {
    /// The struct the function takes.
    pub r#struct: &'a str,
    pub definition: Option<StructView<'a>>,
    /// The function's own name for the struct, where an earlier function's is the same.
    pub alias: Option<AliasView<'a>>,
    /// The public function's body: `<name>_with(x, u, &<Struct>::new(params))`.
    pub call: String,
    pub with_signature: Vec<String>,
    /// `<name>_with`'s cost per call, in words.
    pub with_cost: String,
    /// `<name>_with` is always inlined: its weighted cost is at most [`ALWAYS_INLINED_COST`].
    pub with_always_inlined: bool,
}

/// The largest weighted cost per call of a `<name>_with` that is always inlined. The closed
/// loop calls the plant's `dynamics_with` once per right-hand side; left to itself, the compiler
/// kept the 2-link arm's (cost 30) out of line there, and inlined it took one evaluation from
/// 37.4 to 33.2 ns and a task-1 episode from 63.4 to 59.3 µs (criterion `rhs/position`,
/// `episode/position`). A call costs about ten operations (arguments and results through memory),
/// a few percent of a body up to this size; the URDF arms' (over 1 000) stay out of line, where it
/// is under one percent and inlining would only grow every caller.
pub const ALWAYS_INLINED_COST: u64 = 200;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FunctionView<'a> {
    pub name: &'a str,
    /// Its doc, equation and arguments ([`comment_all`]), each one line of its doc comment.
    pub doc: String,
    /// Paragraphs the doc comment adds after `doc` (a task's formulation, for its sensitivity
    /// function), each one line.
    pub notes: Vec<String>,
    pub equation: String,
    pub args: Value,
    /// The doc comment's lines on the cost per call.
    pub cost_doc: Vec<String>,
    /// The public function's parameters, `x: &SVector<f64, 4>` (`_x` where the body does not
    /// read it), and its return type.
    pub signature: Vec<String>,
    pub return_type: String,
    pub body: BodyView<'a>,
    pub coefficients: Option<CoefficientsView<'a>>,
}

/// "131 operations, weighted 131 (43 ADD, 59 MUL, 1 NEG, 28 SUB), plus 6 `sin_cos`".
pub fn ops_text(c: &Cost) -> String {
    let mut text = format!(
        "{} operation{}, weighted {}",
        c.ops,
        if c.ops == 1 { "" } else { "s" },
        c.weighted
    );
    if c.ops > 0 {
        let kinds: Vec<String> = c.kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
        text += &format!(" ({})", kinds.join(", "));
    }
    if c.sin_cos > 0 {
        text += &format!(", plus {} `sin_cos`", c.sin_cos);
    }
    text
}

/// The views of a model's functions, in order; each coefficient struct is defined once, by the
/// first function that takes it. `notes` are the paragraphs a function's doc adds, by its name.
pub fn function_views<'a>(
    functions: &'a [Function],
    notes: &[(&str, Vec<String>)],
) -> Result<Vec<FunctionView<'a>>, RenderError> {
    let mut defined: Vec<(&str, &Coefficients)> = Vec::new();
    functions
        .iter()
        .map(|f| {
            let shared = f
                .coefficients
                .as_ref()
                .and_then(|c| defined.iter().copied().find(|(_, d)| same_factors(d, c)));
            let own = notes.iter().find(|(name, _)| *name == f.name);
            let mut view = function_view(f, shared)?;
            view.notes = own.map_or_else(Vec::new, |(_, lines)| {
                lines.iter().map(|l| comment(l)).collect()
            });
            if let (Some(c), None) = (&f.coefficients, shared) {
                defined.push((&f.name, c));
            }
            Ok(view)
        })
        .collect()
}

/// Whether two functions' coefficients are the same numbers from the same parameters (whatever
/// each calls its struct).
fn same_factors(a: &Coefficients, b: &Coefficients) -> bool {
    a.count == b.count
        && a.constants == b.constants
        && a.bindings == b.bindings
        && a.temporaries == b.temporaries
        && a.values == b.values
        && a.cost == b.cost
}

fn bad(f: &Function, what: &str) -> RenderError {
    RenderError::Template(format!("function {}: {what}", f.name))
}

/// One function's view; `shared` is an earlier function (its name and coefficients) whose
/// coefficients are the same as this one's.
fn function_view<'a>(
    f: &'a Function,
    shared: Option<(&'a str, &'a Coefficients)>,
) -> Result<FunctionView<'a>, RenderError> {
    let outputs: Vec<&str> = f.outputs.iter().map(|o| o.name.as_str()).collect();
    let return_type = match f.outputs.as_slice() {
        [one] => one.rust_type.clone(),
        many => {
            let types: Vec<&str> = many.iter().map(|o| o.rust_type.as_str()).collect();
            format!("({})", types.join(", "))
        }
    };
    let result = binding_pattern(&outputs.iter().map(|o| o.to_string()).collect::<Vec<_>>());
    let body = body_view(f, result)?;
    let Some(c) = &f.coefficients else {
        return Ok(FunctionView {
            name: &f.name,
            doc: comment(&f.doc),
            notes: Vec::new(),
            equation: comment(&f.equation),
            args: comment_all(&f.args),
            cost_doc: vec![format!("Cost per call: {}.", ops_text(&f.cost))],
            signature: f
                .args
                .iter()
                .map(|a| format!("{}{}: &{}", unused(a.used), a.name, a.rust_type))
                .collect(),
            return_type,
            body,
            coefficients: None,
        });
    };
    let unhoisted = f
        .unhoisted_cost
        .as_ref()
        .ok_or_else(|| bad(f, "coefficients but no unhoisted_cost"))?;
    let name = shared.map_or(c.r#struct.as_str(), |(_, s)| s.r#struct.as_str());
    let (call, with_signature) = with_arguments(f, c, name)?;
    let cost_doc = hoisted_cost_doc(f, c, name, unhoisted);
    Ok(FunctionView {
        name: &f.name,
        doc: comment(&f.doc),
        notes: Vec::new(),
        equation: comment(&f.equation),
        args: comment_all(&f.args),
        cost_doc,
        signature: f
            .args
            .iter()
            .map(|a| format!("{}: &{}", a.name, a.rust_type))
            .collect(),
        return_type,
        body,
        coefficients: Some(CoefficientsView {
            r#struct: name,
            definition: shared.is_none().then(|| struct_view(c)),
            alias: shared.map(|(first, _)| AliasView {
                name: &c.r#struct,
                first,
            }),
            call: format!("{}_with({})", f.name, call.join(", ")),
            with_signature,
            with_cost: ops_text(&f.cost),
            with_always_inlined: f.cost.weighted <= ALWAYS_INLINED_COST,
        }),
    })
}

/// The `_with` function's call from the plain one (its coefficients built from the parameters
/// as `name`, the struct they share) and its signature.
fn with_arguments(
    f: &Function,
    c: &Coefficients,
    name: &str,
) -> Result<(Vec<String>, Vec<String>), RenderError> {
    let own_type = format!("&{}", c.r#struct);
    let mut call = Vec::new();
    let mut with_signature = Vec::new();
    for a in &c.args {
        let rust_type = if a.name == "coefficients" {
            if a.rust_type != own_type {
                return Err(bad(
                    f,
                    "its coefficients argument is not its coefficient struct",
                ));
            }
            call.push(format!("&{name}::new(params)"));
            format!("&{name}")
        } else {
            call.push(a.name.clone());
            a.rust_type.clone()
        };
        with_signature.push(format!("{}{}: {rust_type}", unused(a.used), a.name));
    }
    Ok((call, with_signature))
}

/// The cost of a function with hoisted coefficients: building them, the `_with` call, and the
/// closed form with the parameters inline (`unhoisted`).
fn hoisted_cost_doc(f: &Function, c: &Coefficients, name: &str, unhoisted: &Cost) -> Vec<String> {
    let sin_cos = if f.cost.sin_cos > 0 {
        format!(", plus {} `sin_cos`", f.cost.sin_cos)
    } else {
        String::new()
    };
    vec![
        format!(
            "Cost per call: {} operations, weighted {}{sin_cos}: [`{name}::new`] ({}, weighted {}), then [`{n}_with`] ({}, weighted {}). Build the coefficients once per tool and call [`{n}_with`] where it is called often.",
            c.cost.ops + f.cost.ops,
            c.cost.weighted + f.cost.weighted,
            c.cost.ops,
            c.cost.weighted,
            f.cost.ops,
            f.cost.weighted,
            n = f.name,
        ),
        format!(
            "The same closed form with the parameters inline (not hoisted) would take {}.",
            ops_text(unhoisted)
        ),
    ]
}

fn unused(used: bool) -> &'static str {
    if used {
        ""
    } else {
        "_"
    }
}

fn struct_view(c: &Coefficients) -> StructView<'_> {
    let lets = c
        .constants
        .iter()
        .map(|x| (&x.name, &x.rust))
        .chain(c.bindings.iter().map(|b| (&b.name, &b.access)))
        .chain(c.temporaries.iter().map(|t| (&t.name, &t.rust)))
        .map(|(name, value)| LetView {
            pattern: name.clone(),
            value: value.clone(),
        })
        .collect();
    StructView {
        name: &c.r#struct,
        count: c.count,
        cost: ops_text(&c.cost),
        lets,
        values: &c.values,
    }
}

/// The `let`s of a body: constants, argument elements, the joints' `sin_cos`, angle sums'
/// compounds, then the CSE temporaries.
fn lets(f: &Function) -> Vec<LetView> {
    let plain = |name: &String, value: &String| LetView {
        pattern: name.clone(),
        value: value.clone(),
    };
    let mut out: Vec<LetView> = f
        .constants
        .iter()
        .map(|c| plain(&c.name, &c.rust))
        .collect();
    out.extend(f.bindings.iter().map(|b| plain(&b.name, &b.access)));
    out.extend(f.trig.iter().map(|t| LetView {
        pattern: format!("({}, {})", t.sin, t.cos),
        value: format!("crate::trig::sin_cos({})", t.angle),
    }));
    out.extend(f.compounds.iter().map(|c| plain(&c.name, &c.rust)));
    out.extend(f.temporaries.iter().map(|t| plain(&t.name, &t.rust)));
    out
}

/// `a[3]` of a column, `a[(1, 2)]` of a matrix.
fn element(o: &Output, row: usize, col: usize) -> String {
    if o.cols == 1 {
        format!("{}[{row}]", o.name)
    } else {
        format!("{}[({row}, {col})]", o.name)
    }
}

/// The lower triangle of a symmetric output, copied from the upper.
fn mirrored(o: &Output) -> Vec<Assignment> {
    if !o.symmetric {
        return Vec::new();
    }
    o.entries
        .iter()
        .filter(|e| e.row != e.col)
        .map(|e| Assignment {
            target: format!("{}[({}, {})]", o.name, e.col, e.row),
            value: format!("{}[({}, {})]", o.name, e.row, e.col),
        })
        .collect()
}

/// A closed form assigns each output's entries (and their mirror images) after declaring it; an
/// instruction sequence declares every output, then its slots, runs its steps, and mirrors.
fn body_view(f: &Function, result: String) -> Result<BodyView<'_>, RenderError> {
    let Some(sequence) = &f.sequence else {
        let outputs = f
            .outputs
            .iter()
            .map(|o| {
                let mut assignments = o
                    .entries
                    .iter()
                    .map(|e| {
                        let value = e.rust.clone().ok_or_else(|| {
                            bad(
                                f,
                                &format!("output {} has an entry without its rust", o.name),
                            )
                        })?;
                        Ok(Assignment {
                            target: element(o, e.row, e.col),
                            value,
                        })
                    })
                    .collect::<Result<Vec<_>, RenderError>>()?;
                assignments.extend(mirrored(o));
                let binding = if o.entries.is_empty() {
                    o.name.clone()
                } else {
                    format!("mut {}", o.name)
                };
                Ok(OutputView {
                    doc: comment(&o.doc),
                    binding,
                    rust_type: &o.rust_type,
                    assignments,
                })
            })
            .collect::<Result<Vec<_>, RenderError>>()?;
        return Ok(BodyView {
            lets: lets(f),
            outputs,
            slots: Vec::new(),
            steps: &[],
            mirrors: Vec::new(),
            result,
        });
    };
    Ok(BodyView {
        lets: lets(f),
        outputs: f
            .outputs
            .iter()
            .map(|o| OutputView {
                doc: comment(&o.doc),
                // An output the steps never write (a sensitivity that is zero by structure,
                // the static gain's ∂θ̇/∂U) stays immutable.
                binding: if o.entries.is_empty() {
                    o.name.clone()
                } else {
                    format!("mut {}", o.name)
                },
                rust_type: &o.rust_type,
                assignments: Vec::new(),
            })
            .collect(),
        slots: sequence
            .slots
            .iter()
            .map(|s| {
                if s.mutable {
                    format!("mut {}", s.name)
                } else {
                    s.name.clone()
                }
            })
            .collect(),
        steps: &sequence.steps,
        mirrors: f.outputs.iter().flat_map(mirrored).collect(),
        result,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture() -> crate::ir::Ir {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/fixtures/pendulum.json");
        crate::ir::read_ir(&path).expect("fixture")
    }

    fn coefficients<'a>(views: &'a [FunctionView], name: &str) -> &'a CoefficientsView<'a> {
        let f = views.iter().find(|f| f.name == name).expect(name);
        f.coefficients.as_ref().expect("coefficients")
    }

    #[test]
    fn different_coefficients_are_two_structs() {
        let ir = fixture();
        let views = function_views(&ir.functions, &[]).unwrap();
        let (d, j) = (
            coefficients(&views, "dynamics"),
            coefficients(&views, "dynamics_jacobian"),
        );
        assert_eq!(
            (d.r#struct, j.r#struct),
            ("DynamicsCoefficients", "DynamicsJacobianCoefficients")
        );
        assert!(d.definition.is_some() && j.definition.is_some());
        assert!(d.alias.is_none() && j.alias.is_none());
    }

    #[test]
    fn the_same_coefficients_are_one_struct_and_an_alias() {
        let mut ir = fixture();
        let first = ir.functions[0].coefficients.clone().unwrap();
        let second = ir.functions[1].coefficients.as_mut().unwrap();
        let own = second.r#struct.clone();
        second.count = first.count;
        second.constants = first.constants;
        second.bindings = first.bindings;
        second.temporaries = first.temporaries;
        second.values = first.values;
        second.cost = first.cost;
        let views = function_views(&ir.functions, &[]).unwrap();
        let j = coefficients(&views, "dynamics_jacobian");
        assert_eq!(j.r#struct, "DynamicsCoefficients");
        assert!(j.definition.is_none());
        assert_eq!(
            j.alias,
            Some(AliasView {
                name: &own,
                first: "dynamics"
            })
        );
        assert_eq!(
            j.call,
            "dynamics_jacobian_with(x, u, &DynamicsCoefficients::new(params))"
        );
        assert!(j
            .with_signature
            .contains(&"coefficients: &DynamicsCoefficients".to_string()));
    }
}
