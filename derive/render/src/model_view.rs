//! What the per-model templates (templates/model.rs.tera, report.md.tera and its variants) see:
//! the model's IR with every Rust name, count, joined list and wording decided here.
//!
//! No text of the IR reaches a template as it is: each is escaped for where it goes
//! ([`crate::escape`]): a Rust string literal (`*_literal`), or one line of a comment or of the
//! Markdown report ([`comment`], and [`comment_all`] for a part of the IR shown whole).

use serde::Serialize;
use serde_json::Value;

use crate::escape::{comment, rust_string};
use crate::functions::{function_views, FunctionView};
use crate::ir::{
    ClosedFormReport, Equilibrium, Ir, Model, Report, TaskReport, TestVectors, UrdfReport,
};
use crate::tasks::{task_views, TaskView};
use crate::tool_rule::{tool_rule_view, ToolRuleView};
use crate::RenderError;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelView<'a> {
    pub name: &'a str,
    /// The title and source, each one line of a comment ([`comment`]).
    pub title: String,
    pub source: String,
    pub dof: usize,
    pub state_dim: usize,
    pub tip_dim: usize,
    /// The parameters ([`comment_all`]), and their units as Rust string literals.
    pub parameters: Value,
    pub unit_literals: Vec<String>,
    pub parameter_count: usize,
    /// The parameters' names, space-separated, as the coefficient structs' docs list them.
    pub parameter_list: String,
    pub constants: Value,
    pub state: Value,
    pub control: Value,
    pub equilibrium: &'a Equilibrium,
}

/// `value` serialized with every string in it through [`comment`]: a part of the IR that a
/// template shows in a comment or the report (its names and numbers are unchanged).
pub fn comment_all<T: Serialize + ?Sized>(value: &T) -> Value {
    let mut value = serde_json::to_value(value).unwrap_or(Value::Null);
    let mut pending = vec![&mut value];
    while let Some(v) = pending.pop() {
        match v {
            Value::String(s) => *s = comment(s),
            Value::Array(items) => pending.extend(items.iter_mut()),
            Value::Object(map) => pending.extend(map.values_mut()),
            _ => {}
        }
    }
    value
}

/// The context of one model's templates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelContext<'a> {
    pub model: ModelView<'a>,
    /// What made the IR ([`comment_all`]).
    pub generator: Value,
    pub test_vectors: &'a TestVectors,
    pub functions: Vec<FunctionView<'a>>,
    pub function_count: usize,
    pub tasks: Vec<TaskView<'a>>,
    pub tool_rule: ToolRuleView,
    pub report: ReportView,
}

pub fn model_context(ir: &Ir) -> Result<ModelContext<'_>, RenderError> {
    let m: &Model = &ir.model;
    let tasks = task_views(ir)?;
    // A task's formulation, where it is not the paper's, in its sensitivity function's doc.
    let notes: Vec<(&str, Vec<String>)> = ir
        .tasks
        .iter()
        .zip(&tasks)
        .map(|(t, v)| (t.sensitivity_function.as_str(), v.sensitivity_notes.clone()))
        .collect();
    let functions = function_views(&ir.functions, &notes)?;
    Ok(ModelContext {
        model: ModelView {
            name: &m.name,
            title: comment(&m.title),
            source: comment(&m.source),
            dof: m.dof,
            state_dim: m.state_dim,
            tip_dim: m.tip_dim,
            parameters: comment_all(&m.parameters),
            unit_literals: m.parameters.iter().map(|p| rust_string(&p.unit)).collect(),
            parameter_count: m.parameters.len(),
            parameter_list: join(m.parameters.iter().map(|p| p.name.as_str()), " "),
            constants: comment_all(&m.constants),
            state: comment_all(&m.state),
            control: comment_all(&m.control),
            equilibrium: &m.equilibrium,
        },
        generator: comment_all(&ir.generator),
        test_vectors: &ir.test_vectors,
        function_count: ir.functions.len(),
        report: match &ir.report {
            Report::ClosedForm(r) => ReportView::ClosedForm(closed_form_report(m, r, &tasks)),
            Report::Urdf(r) => ReportView::Urdf(urdf_report(r)),
        },
        functions,
        tasks,
        tool_rule: tool_rule_view(m)?,
    })
}

fn join<'s>(items: impl Iterator<Item = &'s str>, separator: &str) -> String {
    items.collect::<Vec<_>>().join(separator)
}

/// The report's view, of the kind the IR carries.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ReportView {
    ClosedForm(ClosedFormReportView),
    Urdf(UrdfReportView),
}

/// templates/report.md.tera's report: every text of the IR through [`comment`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClosedFormReportView {
    pub equation_refs: String,
    pub equations: Value,
    pub equilibrium_x: String,
    pub equilibrium_u: String,
    pub a: String,
    pub b: String,
    /// The state's and the control's LaTeX, `\ `-separated.
    pub state: String,
    pub control: String,
    /// The comparison with the printed matrices, where the description gives them.
    pub compared: Option<ComparedView>,
    pub tasks: Vec<TaskReportView>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComparedView {
    pub printed_where: String,
    pub count: usize,
    /// "1 differs", "0 differ".
    pub differing: String,
    pub differences: Value,
    pub has_differences: bool,
    pub rows: Vec<ComparisonRow>,
}

/// A compared entry, `equal` in words ("yes", "**no**").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComparisonRow {
    pub entry: String,
    pub derived: String,
    pub printed: String,
    pub equal: &'static str,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskReportView {
    pub name: String,
    pub title: String,
    pub doc: String,
    pub sensitivities: Value,
    pub confidence_formula: String,
    pub default_precisions: String,
    pub confidence_default: String,
    pub gradient_reference: String,
    /// `∂ln|Π^U|/∂m = 1.2, ...`
    pub gradient_values: String,
    pub gradient_closed: Option<Value>,
    pub remarks: Vec<RemarkView>,
    /// The formulation of its sensitivities in this model, in words.
    pub formulation: String,
}

/// A task's remark, the comparison in words ("equals", "is **not** equal to").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RemarkView {
    pub what: String,
    pub text: String,
    pub alternative_formula: String,
    pub alternative: String,
    pub used: String,
    pub relation: &'static str,
}

fn closed_form_report(m: &Model, r: &ClosedFormReport, tasks: &[TaskView]) -> ClosedFormReportView {
    let latex =
        |vs: &[crate::ir::Variable]| comment(&join(vs.iter().map(|v| v.latex.as_str()), "\\ "));
    let compared = (!r.comparisons.is_empty()).then(|| compared_view(r));
    let tasks = r
        .tasks
        .iter()
        .map(|t| {
            let formulation = tasks
                .iter()
                .find(|v| v.name == t.name)
                .map_or_else(String::new, |v| v.formulation.clone());
            task_report_view(t, formulation)
        })
        .collect();
    ClosedFormReportView {
        equation_refs: comment(&r.equation_refs.join(", ")),
        equations: comment_all(&r.equations),
        equilibrium_x: comment(&r.equilibrium_x),
        equilibrium_u: comment(&r.equilibrium_u),
        a: comment(&r.a),
        b: comment(&r.b),
        state: latex(&m.state),
        control: latex(&m.control),
        compared,
        tasks,
    }
}

/// The comparison of the derived matrices with the printed ones.
fn compared_view(r: &ClosedFormReport) -> ComparedView {
    ComparedView {
        printed_where: comment(&r.printed_where),
        count: r.comparisons.len(),
        differing: format!(
            "{} {}",
            r.differences.len(),
            if r.differences.len() == 1 {
                "differs"
            } else {
                "differ"
            }
        ),
        differences: comment_all(&r.differences),
        has_differences: !r.differences.is_empty(),
        rows: r
            .comparisons
            .iter()
            .map(|c| ComparisonRow {
                entry: comment(&c.entry),
                derived: comment(&c.derived),
                printed: comment(&c.printed),
                equal: if c.equal { "yes" } else { "**no**" },
            })
            .collect(),
    }
}

/// A task's part of the report; `formulation` its sensitivities' formulation in words.
fn task_report_view(t: &TaskReport, formulation: String) -> TaskReportView {
    TaskReportView {
        name: comment(&t.name),
        title: comment(&t.title),
        doc: comment(&t.doc),
        sensitivities: comment_all(&t.sensitivities),
        confidence_formula: comment(&t.confidence_formula),
        default_precisions: comment(&t.default_precisions),
        confidence_default: comment(&t.confidence_default),
        gradient_reference: comment(&t.gradient.reference),
        gradient_values: comment(
            &t.gradient
                .values
                .iter()
                .map(|g| format!("∂ln|Π^U|/∂{} = {}", g.name, g.value))
                .collect::<Vec<_>>()
                .join(", "),
        ),
        gradient_closed: t.gradient.closed.as_deref().map(comment_all),
        remarks: t
            .remarks
            .iter()
            .map(|x| RemarkView {
                what: comment(&x.what),
                text: comment(&x.text),
                alternative_formula: comment(&x.alternative_formula),
                alternative: comment(&x.alternative),
                used: comment(&x.used),
                relation: if x.equal {
                    "equals"
                } else {
                    "is **not** equal to"
                },
            })
            .collect(),
        formulation,
    }
}

/// templates/urdf/report.md.tera's report: every text of the IR through [`comment`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UrdfReportView {
    pub urdf: String,
    pub robot: String,
    pub base: String,
    pub flange: String,
    pub gravity: String,
    pub impedance_source: String,
    pub equilibrium: String,
    pub bodies: Value,
    /// The equations' references, `; `-separated.
    pub equation_refs: String,
    pub tools: Vec<ReportToolView>,
    pub costs: Vec<CostRowView>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportToolView {
    pub name: String,
    pub parameters: String,
    pub gravity_sv: String,
    pub stiffness_sv: String,
    /// `position -12.3, velocity ...`
    pub logdets: String,
}

/// A row of the generated functions' costs; the per-tool and inline counts empty where the
/// function has no coefficients.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostRowView {
    pub name: String,
    pub ops: u64,
    pub sin_cos: u64,
    pub coefficients: String,
    pub unhoisted: String,
    pub agreement: String,
}

fn urdf_report(r: &UrdfReport) -> UrdfReportView {
    let count = |n: Option<u64>| n.map(|n| n.to_string()).unwrap_or_default();
    UrdfReportView {
        urdf: comment(&r.urdf),
        robot: comment(&r.robot),
        base: comment(&r.base),
        flange: comment(&r.flange),
        gravity: comment(&r.gravity),
        impedance_source: comment(&r.impedance_source),
        equilibrium: comment(&r.equilibrium),
        bodies: comment_all(&r.bodies),
        equation_refs: comment(&r.equation_refs.join("; ")),
        tools: r
            .tools
            .iter()
            .map(|t| ReportToolView {
                name: comment(&t.name),
                parameters: comment(&t.parameters),
                gravity_sv: comment(&t.gravity_sv),
                stiffness_sv: comment(&t.stiffness_sv),
                logdets: comment(
                    &t.logdets
                        .iter()
                        .map(|l| format!("{} {}", l.task, l.value))
                        .collect::<Vec<_>>()
                        .join(", "),
                ),
            })
            .collect(),
        costs: r
            .costs
            .iter()
            .map(|c| CostRowView {
                name: comment(&c.name),
                ops: c.ops,
                sin_cos: c.sin_cos,
                coefficients: count(c.coefficients),
                unhoisted: count(c.unhoisted),
                agreement: comment(&c.agreement),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::{ChosenBy, Formulation};

    fn fixture() -> Ir {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/fixtures/pendulum.json");
        crate::ir::read_ir(&path).expect("fixture")
    }

    #[test]
    fn a_named_formulation_is_in_its_sensitivity_functions_doc_alone() {
        let mut ir = fixture();
        let paper = model_context(&ir).unwrap();
        assert!(paper.functions.iter().all(|f| f.notes.is_empty()));
        assert_eq!(paper.model.tip_dim, 1);
        ir.tasks[0].formulation = Formulation {
            name: "static_gain".into(),
            doc: "The static gain.".into(),
            chosen_by: ChosenBy::Description,
        };
        let named = model_context(&ir).unwrap();
        for f in &named.functions {
            let expected = usize::from(f.name == ir.tasks[0].sensitivity_function);
            assert_eq!(f.notes.len(), expected, "{}", f.name);
        }
        assert!(named.tasks[0].formulation.contains("`[formulation]`"));
    }
}
