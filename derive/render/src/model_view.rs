//! What the per-model templates (templates/model.rs.tera, report.md.tera and its variants) see:
//! the model's IR with every Rust name, count, joined list and wording decided here.

use serde::Serialize;

use crate::functions::{function_views, FunctionView};
use crate::ir::{
    Body, ClosedFormReport, Comparison, Constant, Equation, Equilibrium, Generator,
    GradientClosedForm, Ir, Model, Parameter, Report, SensitivityReport, TestVectors, UrdfReport,
    Variable,
};
use crate::tasks::{task_views, TaskView};
use crate::tool_rule::{tool_rule_view, ToolRuleView};
use crate::RenderError;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelView<'a> {
    pub name: &'a str,
    pub title: &'a str,
    pub source: &'a str,
    pub dof: usize,
    pub state_dim: usize,
    pub tip_dim: usize,
    pub parameters: &'a [Parameter],
    pub parameter_count: usize,
    /// The parameters' names, space-separated, as the coefficient structs' docs list them.
    pub parameter_list: String,
    pub constants: &'a [Constant],
    pub state: &'a [Variable],
    pub control: &'a [Variable],
    pub equilibrium: &'a Equilibrium,
}

/// The context of one model's templates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelContext<'a> {
    pub model: ModelView<'a>,
    pub generator: &'a Generator,
    pub test_vectors: &'a TestVectors,
    pub functions: Vec<FunctionView<'a>>,
    pub function_count: usize,
    pub tasks: Vec<TaskView<'a>>,
    pub tool_rule: ToolRuleView,
    pub report: ReportView<'a>,
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
            title: &m.title,
            source: &m.source,
            dof: m.dof,
            state_dim: m.state_dim,
            tip_dim: m.tip_dim,
            parameters: &m.parameters,
            parameter_count: m.parameters.len(),
            parameter_list: join(m.parameters.iter().map(|p| p.name.as_str()), " "),
            constants: &m.constants,
            state: &m.state,
            control: &m.control,
            equilibrium: &m.equilibrium,
        },
        generator: &ir.generator,
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
pub enum ReportView<'a> {
    ClosedForm(ClosedFormReportView<'a>),
    Urdf(UrdfReportView<'a>),
}

/// templates/report.md.tera's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClosedFormReportView<'a> {
    pub equation_refs: String,
    pub equations: &'a [Equation],
    pub equilibrium_x: &'a str,
    pub equilibrium_u: &'a str,
    pub a: &'a str,
    pub b: &'a str,
    /// The state's and the control's LaTeX, `\ `-separated.
    pub state: String,
    pub control: String,
    /// The comparison with the printed matrices, where the description gives them.
    pub compared: Option<ComparedView<'a>>,
    pub tasks: Vec<TaskReportView<'a>>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComparedView<'a> {
    pub printed_where: &'a str,
    pub count: usize,
    /// "1 differs", "0 differ".
    pub differing: String,
    pub differences: &'a [Comparison],
    pub has_differences: bool,
    pub rows: Vec<ComparisonRow<'a>>,
}

/// A compared entry, `equal` in words ("yes", "**no**").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComparisonRow<'a> {
    pub entry: &'a str,
    pub derived: &'a str,
    pub printed: &'a str,
    pub equal: &'static str,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskReportView<'a> {
    pub name: &'a str,
    pub title: &'a str,
    pub doc: &'a str,
    pub sensitivities: &'a [SensitivityReport],
    pub confidence_formula: &'a str,
    pub default_precisions: &'a str,
    pub confidence_default: &'a str,
    pub gradient_reference: &'a str,
    /// `∂ln|Π^U|/∂m = 1.2, ...`
    pub gradient_values: String,
    pub gradient_closed: Option<&'a [GradientClosedForm]>,
    pub remarks: Vec<RemarkView<'a>>,
    /// The formulation of its sensitivities in this model, in words.
    pub formulation: String,
}

/// A task's remark, the comparison in words ("equals", "is **not** equal to").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RemarkView<'a> {
    pub what: &'a str,
    pub text: &'a str,
    pub alternative_formula: &'a str,
    pub alternative: &'a str,
    pub used: &'a str,
    pub relation: &'static str,
}

fn closed_form_report<'a>(
    m: &'a Model,
    r: &'a ClosedFormReport,
    tasks: &[TaskView],
) -> ClosedFormReportView<'a> {
    let latex = |vs: &'a [Variable]| join(vs.iter().map(|v| v.latex.as_str()), "\\ ");
    let compared = (!r.comparisons.is_empty()).then(|| ComparedView {
        printed_where: &r.printed_where,
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
        differences: &r.differences,
        has_differences: !r.differences.is_empty(),
        rows: r
            .comparisons
            .iter()
            .map(|c| ComparisonRow {
                entry: &c.entry,
                derived: &c.derived,
                printed: &c.printed,
                equal: if c.equal { "yes" } else { "**no**" },
            })
            .collect(),
    });
    let tasks = r
        .tasks
        .iter()
        .map(|t| TaskReportView {
            name: &t.name,
            title: &t.title,
            doc: &t.doc,
            sensitivities: &t.sensitivities,
            confidence_formula: &t.confidence_formula,
            default_precisions: &t.default_precisions,
            confidence_default: &t.confidence_default,
            gradient_reference: &t.gradient.reference,
            gradient_values: t
                .gradient
                .values
                .iter()
                .map(|g| format!("∂ln|Π^U|/∂{} = {}", g.name, g.value))
                .collect::<Vec<_>>()
                .join(", "),
            gradient_closed: t.gradient.closed.as_deref(),
            remarks: t
                .remarks
                .iter()
                .map(|x| RemarkView {
                    what: &x.what,
                    text: &x.text,
                    alternative_formula: &x.alternative_formula,
                    alternative: &x.alternative,
                    used: &x.used,
                    relation: if x.equal {
                        "equals"
                    } else {
                        "is **not** equal to"
                    },
                })
                .collect(),
            formulation: tasks
                .iter()
                .find(|v| v.name == t.name)
                .map_or_else(String::new, |v| v.formulation.clone()),
        })
        .collect();
    ClosedFormReportView {
        equation_refs: r.equation_refs.join(", "),
        equations: &r.equations,
        equilibrium_x: &r.equilibrium_x,
        equilibrium_u: &r.equilibrium_u,
        a: &r.a,
        b: &r.b,
        state: latex(&m.state),
        control: latex(&m.control),
        compared,
        tasks,
    }
}

/// templates/urdf/report.md.tera's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UrdfReportView<'a> {
    pub urdf: &'a str,
    pub robot: &'a str,
    pub base: &'a str,
    pub flange: &'a str,
    pub gravity: &'a str,
    pub impedance_source: &'a str,
    pub equilibrium: &'a str,
    pub bodies: &'a [Body],
    /// The equations' references, `; `-separated.
    pub equation_refs: String,
    pub tools: Vec<ReportToolView<'a>>,
    pub costs: Vec<CostRowView<'a>>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportToolView<'a> {
    pub name: &'a str,
    pub parameters: &'a str,
    pub gravity_sv: &'a str,
    pub stiffness_sv: &'a str,
    /// `position -12.3, velocity ...`
    pub logdets: String,
}

/// A row of the generated functions' costs; the per-tool and inline counts empty where the
/// function has no coefficients.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostRowView<'a> {
    pub name: &'a str,
    pub ops: u64,
    pub sin_cos: u64,
    pub coefficients: String,
    pub unhoisted: String,
    pub agreement: &'a str,
}

fn urdf_report(r: &UrdfReport) -> UrdfReportView<'_> {
    let count = |n: Option<u64>| n.map(|n| n.to_string()).unwrap_or_default();
    UrdfReportView {
        urdf: &r.urdf,
        robot: &r.robot,
        base: &r.base,
        flange: &r.flange,
        gravity: &r.gravity,
        impedance_source: &r.impedance_source,
        equilibrium: &r.equilibrium,
        bodies: &r.bodies,
        equation_refs: r.equation_refs.join("; "),
        tools: r
            .tools
            .iter()
            .map(|t| ReportToolView {
                name: &t.name,
                parameters: &t.parameters,
                gravity_sv: &t.gravity_sv,
                stiffness_sv: &t.stiffness_sv,
                logdets: t
                    .logdets
                    .iter()
                    .map(|l| format!("{} {}", l.task, l.value))
                    .collect::<Vec<_>>()
                    .join(", "),
            })
            .collect(),
        costs: r
            .costs
            .iter()
            .map(|c| CostRowView {
                name: &c.name,
                ops: c.ops,
                sin_cos: c.sin_cos,
                coefficients: count(c.coefficients),
                unhoisted: count(c.unhoisted),
                agreement: &c.agreement,
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
