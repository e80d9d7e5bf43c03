//! What the registry templates (templates/registry/, rendered once over all models into the
//! crate around them) see: each model's Rust names, the vector test's calls, the tool rules, the
//! tasks, and the package.

use serde::Serialize;

use crate::escape::comment;
use crate::ir::{Function, Ir, Task};
use crate::tasks::{
    binding_pattern, camel_case, cost_order, string_literal, task_choices, task_list, term_views,
    TaskView, TermView,
};
use crate::tool_rule::{tool_rule_view, ToolRuleView};
use crate::RenderError;

/// The crate the registry renders: its package name, and whether it is a crate of its own
/// (`make crate`: an empty `[workspace]` table, so that no enclosing workspace claims it) or a
/// member of toolconf's workspace (`generated/`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Package {
    pub name: String,
    pub standalone: bool,
}

impl Package {
    /// toolconf's own generated crate, `generated/`.
    pub fn in_repository() -> Self {
        Self {
            name: "toolconf-generated".into(),
            standalone: false,
        }
    }
}

/// The function that is a model's own rigid-body dynamics (U the joint torques), for
/// `generated::rigid_body`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RigidBody {
    pub function: &'static str,
    pub doc: &'static str,
}

/// What the vector test needs of one generated function: its argument and output names, and
/// the pattern binding its outputs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct VectorTestView<'a> {
    pub name: &'a str,
    pub args: Vec<&'a str>,
    pub outputs: Vec<&'a str>,
    pub pattern: String,
    /// For a task's ∂ln|Π^U|/∂p, the function giving its Π^U (the same arguments), whose
    /// condition number bounds how accurately any double evaluation gives it.
    pub conditioned_by: Option<&'a str>,
}

/// The registry's view of one model: what the runtime needs to name and size it. The marker
/// type is the model's name in CamelCase (`arm2_exact` → `Arm2Exact`), its tool type that plus
/// `Tool`, and the title a Rust literal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegistryModel<'a> {
    pub name: &'a str,
    /// The title, one line of a comment ([`comment`]), and as a Rust string literal.
    pub title: String,
    pub title_literal: String,
    pub marker: String,
    pub tool: String,
    /// The model description it was derived from, one line of a comment.
    pub description: String,
    /// `description` as a Rust string literal.
    pub description_literal: String,
    pub parameter_count: usize,
    pub functions: Vec<VectorTestView<'a>>,
    pub function_count: usize,
    pub tool_rule: ToolRuleView,
    pub rigid_body: RigidBody,
    /// The body of `generated::tip::<name>`: `Some(..)` of the model's `tip` function, or `None`
    /// for a model whose description gives no tip.
    pub tip_body: String,
    pub tip_bias_body: String,
    pub has_tip: bool,
    /// The tasks the model offers, as `TaskKind` variants (`TaskKind::Position`).
    pub task_variants: Vec<String>,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PackageView {
    pub name: String,
    /// The crate's name as Rust code names it (`toolconf_generated`).
    pub lib: String,
    pub standalone: bool,
    /// The command and the task definitions every model was derived by, and the models'
    /// descriptions, each one line of a comment.
    pub command: String,
    pub tasks: String,
    /// The models' descriptions and names, `, `-separated.
    pub descriptions: String,
    pub model_names: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegistryContext<'a> {
    pub models: Vec<RegistryModel<'a>>,
    pub model_count: usize,
    /// The most tool parameters of any model: the inline storage of a tool of any model.
    pub max_parameter_count: usize,
    pub tasks: Vec<TaskView<'a>>,
    pub task_count: usize,
    /// The free-energy terms (`derive/tasks.toml`'s `[[term]]`), the same for every model.
    pub terms: Vec<TermView<'a>>,
    pub term_count: usize,
    /// The names of the terms a goal is given for, and how many.
    pub goal_term_names: Vec<&'a str>,
    /// `Term::ThetaDdot, Term::U, ...`: the order J's summands are added in.
    pub cost_order: Vec<String>,
    /// `Term::U`: the term read from the control.
    pub control_variant: String,
    pub task_choices: String,
    pub package: PackageView,
}

pub fn registry_context<'a>(
    irs: &'a [Ir],
    package: &Package,
) -> Result<RegistryContext<'a>, RenderError> {
    if !crate_name(&package.name) {
        return Err(RenderError::Template(format!(
            "{:?} is not a crate name (an ASCII letter, then letters, digits, - or _)",
            package.name
        )));
    }
    let models = irs
        .iter()
        .map(registry_model)
        .collect::<Result<Vec<_>, _>>()?;
    let tasks = task_list(irs)?;
    let terms = irs
        .first()
        .map_or(Ok(Vec::new()), |ir| term_views(&ir.terms))?;
    let cost_order = irs.first().map_or(Ok(Vec::new()), cost_order)?;
    let list = |items: Vec<&str>| items.join(", ");
    Ok(RegistryContext {
        model_count: models.len(),
        max_parameter_count: models.iter().map(|m| m.parameter_count).max().unwrap_or(0),
        task_count: tasks.len(),
        task_choices: task_choices(&tasks),
        term_count: terms.len(),
        goal_term_names: terms
            .iter()
            .filter(|t| t.goal_range != "None")
            .map(|t| t.name)
            .collect(),
        cost_order,
        control_variant: terms
            .iter()
            .find(|t| !t.has_sensitivity)
            .map_or(String::new(), |t| format!("Term::{}", t.variant)),
        terms,
        package: PackageView {
            name: package.name.clone(),
            lib: package.name.replace('-', "_"),
            standalone: package.standalone,
            command: comment(&shared_generator(irs, "command", |ir| {
                &ir.generator.command
            })?),
            tasks: comment(&shared_generator(irs, "tasks", |ir| &ir.generator.tasks)?),
            descriptions: list(models.iter().map(|m| m.description.as_str()).collect()),
            model_names: list(models.iter().map(|m| m.name).collect()),
        },
        models,
        tasks,
    })
}

fn registry_model(ir: &Ir) -> Result<RegistryModel<'_>, RenderError> {
    let m = &ir.model;
    let marker = camel_case(&m.name);
    Ok(RegistryModel {
        name: &m.name,
        title: comment(&m.title),
        title_literal: string_literal(&m.title),
        tool: format!("{marker}Tool"),
        marker,
        description: comment(&ir.generator.model),
        description_literal: string_literal(&ir.generator.model),
        parameter_count: m.parameters.len(),
        functions: ir
            .functions
            .iter()
            .map(|f| vector_test_view(f, &ir.tasks))
            .collect(),
        function_count: ir.functions.len(),
        tool_rule: tool_rule_view(m)?,
        rigid_body: rigid_body(&ir.functions),
        tip_body: tip_body(&m.name, &ir.functions),
        tip_bias_body: tip_bias_body(&m.name, &ir.functions),
        has_tip: ir.functions.iter().any(|f| f.name == "tip"),
        task_variants: ir
            .tasks
            .iter()
            .map(|t| format!("TaskKind::{}", camel_case(&t.name)))
            .collect(),
    })
}

/// A Cargo package name (make crate's rule: derive/make_crate.py's crate_name).
fn crate_name(name: &str) -> bool {
    name.len() <= 64
        && name.bytes().next().is_some_and(|b| b.is_ascii_alphabetic())
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
}

/// `generated::tip::<name>`'s body: the model's `tip` (position and Jacobian) where it has one.
fn tip_body(name: &str, functions: &[Function]) -> String {
    if functions.iter().any(|f| f.name == "tip") {
        format!("Some(crate::{name}::tip(q, params))")
    } else {
        "let _ = (q, params);\n        None".to_string()
    }
}

/// `generated::tip_bias::<name>`'s body: the model's `tip_bias` (J̇ q̇) where it has one.
fn tip_bias_body(name: &str, functions: &[Function]) -> String {
    if functions.iter().any(|f| f.name == "tip_bias") {
        format!("Some(crate::{name}::tip_bias(q, q_dot, params))")
    } else {
        "let _ = (q, q_dot, params);\n        None".to_string()
    }
}

/// The URDF arms' `rigid_body_dynamics` (their plant adds joint impedance), else the model's
/// plant `dynamics`, which for the other kinds is the equations of motion with U the torques
/// (or force) itself.
fn rigid_body(functions: &[Function]) -> RigidBody {
    if functions.iter().any(|f| f.name == "rigid_body_dynamics") {
        RigidBody {
            function: "rigid_body_dynamics",
            doc: "the rigid-body dynamics alone (the model's plant adds joint impedance)",
        }
    } else {
        RigidBody {
            function: "dynamics",
            doc: "the model's plant, which is its rigid-body dynamics",
        }
    }
}

fn vector_test_view<'a>(f: &'a Function, tasks: &'a [Task]) -> VectorTestView<'a> {
    let outputs: Vec<String> = f.outputs.iter().map(|o| o.name.clone()).collect();
    VectorTestView {
        name: &f.name,
        args: f.args.iter().map(|a| a.name.as_str()).collect(),
        outputs: f.outputs.iter().map(|o| o.name.as_str()).collect(),
        pattern: binding_pattern(&outputs),
        conditioned_by: tasks
            .iter()
            .find(|t| t.gradient_function == f.name)
            .map(|t| t.confidence_function.as_str()),
    }
}

/// The same `generator` entry of every IR (the command, the task definitions), or an error
/// naming the first model that differs.
fn shared_generator(
    irs: &[Ir],
    key: &str,
    of: impl Fn(&Ir) -> &String,
) -> Result<String, RenderError> {
    let first = irs.first().map(|ir| of(ir).clone()).unwrap_or_default();
    match irs.iter().find(|ir| *of(ir) != first) {
        Some(ir) => Err(RenderError::Template(format!(
            "model {:?} has generator.{key} {:?}, the first model {first:?}: the models of one crate come from one run",
            ir.model.name,
            of(ir)
        ))),
        None => Ok(first),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gradients_vector_test_is_conditioned_by_its_tasks_confidence() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/fixtures/pendulum.json");
        let irs = [crate::ir::read_ir(&path).expect("fixture")];
        let context = registry_context(&irs, &Package::in_repository()).unwrap();
        let view = |name: &str| {
            context.models[0]
                .functions
                .iter()
                .find(|f| f.name == name)
                .unwrap_or_else(|| panic!("{name}"))
                .conditioned_by
        };
        assert_eq!(
            view("tip_position_logdet_gradient"),
            Some("tip_position_control_confidence")
        );
        assert_eq!(view("tip_position_control_confidence"), None);
        assert_eq!(view("dynamics"), None);
    }
}
