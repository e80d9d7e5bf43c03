//! The IR as the derivation writes it (`derive/derive.py`: one JSON document per model), read into
//! types: a key this renderer does not know, a missing one or a value of the wrong kind is an error
//! naming the file, the line and the column, before any template runs.
//!
//! These structs are where the IR's fields are written, once: the derivation's dataclasses
//! (`derive/toolconf_derive/ir_types.py`) are built from their JSON Schema ([`crate::ir_schema`],
//! committed as `derive/ir_schema.json`), with the same names, the fields in the same order (the
//! order of the keys in the JSON) and their docs. A field left out of the JSON when it has no value
//! is `#[serde(default, skip_serializing_if = "Option::is_none")]` here; every other field is
//! always written, `null` where it has no value.

use std::collections::BTreeMap;
use std::path::Path;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::RenderError;

/// The IR schema this renderer understands (`schema` in the JSON, which the derivation takes
/// from `derive/ir_schema.json`). 4: each function carries its cost; 6: the model's `tip_dim`, the
/// tasks' formulation.
pub const IR_SCHEMA: u64 = 6;

/// One model's IR. `R` is its report: [`ClosedFormReport`] for a model derived by SymPy,
/// [`UrdfReport`] for a URDF arm (derived on CasADi SX).
#[derive(Debug, Clone, PartialEq, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(rename = "Ir")]
pub struct Ir<R = Report> {
    pub schema: u64,
    pub generator: Generator,
    pub model: Model,
    pub terms: Vec<Term>,
    /// The order J's summands are added in (`cost_order` of `derive/tasks.toml`).
    pub cost_order: Vec<String>,
    pub tasks: Vec<Task>,
    pub functions: Vec<Function>,
    pub test_vectors: TestVectors,
    pub report: R,
    /// Variants of the top-level templates this model renders through (`urdf/report.md.tera`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub templates: Option<Vec<String>>,
}

/// A model's derivation report, which of the two kinds its IR carries.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Report {
    ClosedForm(ClosedFormReport),
    Urdf(UrdfReport),
}

/// What made the IR, as the generated files name it.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Generator {
    pub command: String,
    pub model: String,
    pub tasks: String,
    pub ir: String,
    pub vectors: String,
    pub derive: String,
    pub render: String,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Model {
    pub name: String,
    pub title: String,
    pub source: String,
    pub dof: usize,
    pub state_dim: usize,
    /// TIP_DIM: the components of the tip the tip terms use (their first rows of the `dof`).
    pub tip_dim: usize,
    pub parameters: Vec<Parameter>,
    pub constants: Vec<Constant>,
    pub state: Vec<Variable>,
    pub control: Vec<Variable>,
    pub equilibrium: Equilibrium,
    /// Which tools are valid, where the description states it (a URDF tool); else the planar
    /// arms' rule ([`crate::tool_rule`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_rule: Option<ToolRule>,
}

/// A tool parameter.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Parameter {
    pub name: String,
    pub latex: String,
    pub unit: String,
    pub doc: String,
}

/// A named constant of the model (gravity, ...), with its Rust constant's name.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Constant {
    pub name: String,
    pub rust: String,
    pub value: f64,
    pub unit: String,
    pub doc: String,
}

/// A state or control variable.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Variable {
    pub name: String,
    pub latex: String,
}

/// X^e and U^e as Rust literals.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Equilibrium {
    pub x: Vec<String>,
    pub u: Vec<String>,
}

/// A description's rule for its tools (urdf_description.tool_rule).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ToolRule {
    pub domains: Vec<Domain>,
    pub constraints: Vec<Constraint>,
    /// Per parameter, the interval [lo, hi] random tools are drawn from.
    pub sample: Vec<[f64; 2]>,
    /// Per parameter, what a tools file that leaves its column out means (`None`: required).
    pub defaults: Vec<Option<f64>>,
    /// The parameters that are a rigid body's inertia tensor, if some are.
    pub inertia: Option<Inertia>,
    pub source: String,
}

/// The parameters that are a rigid body's inertia tensor about its centre of mass, by index (the
/// moments xx, yy, zz, the products xy, xz, yz): positive definite, its eigenvalues obeying the
/// triangle inequality to a relative `slack`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Inertia {
    pub moments: [usize; 3],
    pub products: [usize; 3],
    pub slack: f64,
}

/// One parameter's domain; a missing bound is none.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    pub lo: Option<f64>,
    pub hi: Option<f64>,
    pub lo_open: bool,
    pub hi_open: bool,
}

/// c · p ≤ 0, and the rule in words.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Constraint {
    pub coefficients: Vec<f64>,
    pub text: String,
}

/// A free-energy term (eq. free_energy) of `derive/tasks.toml`'s `[[term]]` list.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Term {
    pub name: String,
    pub symbol: String,
    pub latex: String,
    pub doc: String,
    /// One component of it, on a plot's axis (`joint angle`).
    pub label: String,
    pub unit: String,
    pub read: TermRead,
    /// The documented range its goal lies in; none for the control's term (no goal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal_range: Option<String>,
}

/// Where a term's value is read: `block` (n rows) of the state X, of its rate Ẋ, or the control;
/// for the tool's tip, `block` is the order of the derivative (0: y(q), 1: J(q) q̇).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TermRead {
    pub source: Source,
    pub block: usize,
}

/// What a term is read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    State,
    StateRate,
    Control,
    Tip,
}

impl Term {
    /// Whether it has a sensitivity ∂(term)/∂U (the control's term has none).
    pub fn has_sensitivity(&self) -> bool {
        self.read.source != Source::Control
    }
}

/// A task of `derive/tasks.toml`, with this model's default goals and precisions.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Task {
    pub name: String,
    pub index: u8,
    pub title: String,
    pub doc: String,
    pub terms: Vec<String>,
    pub sensitivity_terms: Vec<String>,
    pub error: String,
    pub sensitivity_function: String,
    pub confidence_function: String,
    pub gradient_function: String,
    pub goals: Vec<Goal>,
    pub precisions: Vec<Precision>,
    pub formulation: Formulation,
}

/// Which formulation of its sensitivities a task has in this model: `paper` (the formulas of
/// `derive/tasks.toml`'s task) or one of the task's named `[task.formulations]`, and why.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Formulation {
    pub name: String,
    /// The named formulation's doc (empty for the paper's).
    pub doc: String,
    pub chosen_by: ChosenBy,
}

impl Formulation {
    /// The name of the task's own formulas.
    pub const PAPER: &'static str = "paper";
}

/// Why a task has its formulation in a model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ChosenBy {
    /// Nothing chose another: the paper's.
    Default,
    /// The formulation's `default_for` names the model's dynamics kind.
    DefaultFor,
    /// The model description's `[formulation]` names it.
    Description,
}

/// A default goal, one Rust literal per joint (a goal at the tip: its TIP_DIM components, then
/// zeros).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Goal {
    pub term: String,
    pub rust: Vec<String>,
}

/// A default precision P = value · I.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Precision {
    pub term: String,
    pub rust: String,
    pub value: f64,
}

/// One generated function: a closed form (its CSE'd `temporaries` and each output entry's
/// `rust`) or CasADi's instruction `sequence`, with optional per-tool `coefficients`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Function {
    pub name: String,
    pub doc: String,
    pub equation: String,
    pub args: Vec<Arg>,
    pub coefficients: Option<Coefficients>,
    pub cost: Cost,
    /// What one call would take with the parameters inline; set where `coefficients` is.
    pub unhoisted_cost: Option<Cost>,
    pub outputs: Vec<Output>,
    pub constants: Vec<Let>,
    pub bindings: Vec<Binding>,
    pub trig: Vec<Trig>,
    pub compounds: Vec<Let>,
    pub temporaries: Vec<Let>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sequence: Option<Sequence>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Arg {
    pub name: String,
    pub doc: String,
    pub rows: usize,
    pub cols: usize,
    pub rust_type: String,
    pub symmetric: bool,
    /// Whether the body reads it (an unread argument is named `_<name>`).
    pub used: bool,
}

/// The parameter-only factors of a function, computed once per tool (derive/toolconf_derive/hoist.py).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Coefficients {
    pub r#struct: String,
    pub count: usize,
    pub constants: Vec<Let>,
    pub bindings: Vec<Binding>,
    pub temporaries: Vec<Let>,
    pub values: Vec<String>,
    pub cost: Cost,
    /// The arguments of `<function>_with`: the function's own but `params`, then the coefficients.
    pub args: Vec<CoefficientArg>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CoefficientArg {
    pub name: String,
    pub rust_type: String,
    pub used: bool,
}

/// Operation counts (derive/toolconf_derive/cost.py): `kinds` by count_ops' names, in name order.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Cost {
    pub ops: u64,
    pub weighted: u64,
    pub kinds: BTreeMap<String, u64>,
    pub sin_cos: u64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Output {
    pub name: String,
    pub doc: String,
    pub rows: usize,
    pub cols: usize,
    pub rust_type: String,
    /// Only the upper triangle is in `entries`; the rest mirrors it.
    pub symmetric: bool,
    pub entries: Vec<Entry>,
}

/// A nonzero output entry; `rust` is its closed form (absent where an instruction sequence
/// writes it).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    pub row: usize,
    pub col: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rust: Option<String>,
}

/// `let name = rust;`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Let {
    pub name: String,
    pub rust: String,
}

/// `let name = access;`, an element of argument `arg`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Binding {
    pub name: String,
    pub arg: String,
    pub access: String,
}

/// `let (sin, cos) = crate::trig::sin_cos(angle);`, `_` for a side the body does not read.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Trig {
    pub angle: String,
    pub sin: String,
    pub cos: String,
}

/// CasADi's instructions on its work slots (derive/toolconf_derive/sequence.py).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Sequence {
    pub slots: Vec<Slot>,
    pub steps: Vec<Step>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Slot {
    pub name: String,
    pub mutable: bool,
}

/// `target = rust;`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Step {
    pub target: String,
    pub rust: String,
}

/// Where the test vectors are, and how many per function.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TestVectors {
    pub file: String,
    pub per_function: u64,
}

/// The report of a model derived in closed form (derive/toolconf_derive/report.py).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ClosedFormReport {
    pub printed_where: String,
    pub equations: Vec<Equation>,
    pub equation_refs: Vec<String>,
    pub equilibrium_x: String,
    pub equilibrium_u: String,
    pub a: String,
    pub b: String,
    pub comparisons: Vec<Comparison>,
    pub differences: Vec<Comparison>,
    pub tasks: Vec<TaskReport>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Equation {
    pub lhs: String,
    pub rhs: String,
}

/// A derived matrix entry against the one the paper prints.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Comparison {
    pub entry: String,
    pub derived: String,
    pub printed: String,
    pub equal: bool,
    pub difference: String,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TaskReport {
    pub name: String,
    pub index: u8,
    pub title: String,
    pub doc: String,
    pub sensitivities: Vec<SensitivityReport>,
    pub confidence_formula: String,
    pub default_precisions: String,
    pub confidence_default: String,
    pub gradient: GradientReport,
    pub remarks: Vec<Remark>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensitivityReport {
    pub term: String,
    pub what: String,
    pub formula: String,
    pub latex: String,
}

/// d ln|Π^U|/dp at the reference tool, and its closed form for a one-joint model.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GradientReport {
    pub reference: String,
    pub values: Vec<GradientValue>,
    pub closed: Option<Vec<GradientClosedForm>>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GradientValue {
    pub name: String,
    pub value: String,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GradientClosedForm {
    pub name: String,
    pub latex: String,
}

/// A task's note on an alternative reading of one of its sensitivities.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Remark {
    pub what: String,
    pub text: String,
    pub alternative_formula: String,
    pub alternative: String,
    pub used: String,
    pub equal: bool,
}

/// The report of a URDF arm (derive/toolconf_derive/urdf_functions.py).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UrdfReport {
    pub urdf: String,
    pub robot: String,
    pub base: String,
    pub flange: String,
    pub gravity: String,
    pub impedance_source: String,
    pub equilibrium: String,
    pub bodies: Vec<Body>,
    pub tools: Vec<ReportTool>,
    pub costs: Vec<CostRow>,
    pub equation_refs: Vec<String>,
}

/// A body of the chain, its numbers as the report prints them.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body {
    pub joint: String,
    pub kind: String,
    pub axis: String,
    pub mass: String,
    pub stiffness: String,
    pub damping: String,
}

/// One of the report's example tools.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReportTool {
    pub name: String,
    pub parameters: String,
    pub gravity_sv: String,
    pub stiffness_sv: String,
    pub logdets: Vec<Logdet>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Logdet {
    pub task: String,
    pub value: String,
}

/// A generated function's cost and its agreement with the reference graph.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CostRow {
    pub name: String,
    pub ops: u64,
    pub weighted: u64,
    pub sin_cos: u64,
    pub agreement: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coefficients: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unhoisted: Option<u64>,
}

/// What is read before the whole document: its schema (so that an IR of another schema is named
/// as such, not as a list of keys this renderer does not know) and its template variants, which
/// say its report's kind.
#[derive(Deserialize)]
struct Header {
    #[serde(default)]
    schema: Option<u64>,
    #[serde(default)]
    templates: Vec<String>,
}

/// The template variant a URDF model's IR names (templates/urdf/report.md.tera).
pub const URDF_REPORT_TEMPLATE: &str = "urdf/report.md.tera";

impl<R> Ir<R> {
    fn with_report(self, kind: impl FnOnce(R) -> Report) -> Ir {
        Ir {
            schema: self.schema,
            generator: self.generator,
            model: self.model,
            terms: self.terms,
            cost_order: self.cost_order,
            tasks: self.tasks,
            functions: self.functions,
            test_vectors: self.test_vectors,
            report: kind(self.report),
            templates: self.templates,
        }
    }
}

/// The largest IR read: the Panda's is 5.5 MB, and a derivation's code grows as the cube of the
/// joints (at most 12: derive/toolconf_derive/urdf.py); a larger file is no IR of a model.
pub const MAX_IR_BYTES: u64 = 128 << 20;

/// Reads and checks an IR file: a regular file of at most [`MAX_IR_BYTES`], UTF-8 JSON of the
/// types here, every field of its kind ([`crate::ir_check`]).
pub fn read_ir(path: &Path) -> Result<Ir, RenderError> {
    let refused = |key: &str, problem: String| RenderError::Refused {
        path: path.into(),
        key: key.into(),
        problem,
    };
    let bytes = toolconf_files::input::read_regular(path, MAX_IR_BYTES).map_err(|e| match e {
        toolconf_files::input::InputError::TooLarge(limit) => refused(
            "",
            format!(
                "larger than {}, more than any model's IR (the Panda's is 5.5 MB)",
                toolconf_files::input::bytes(limit)
            ),
        ),
        e => refused("", e.to_string()),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        refused(
            "",
            format!(
                "not UTF-8 text (an invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    let ir = parse_ir(&text).map_err(|e| match e {
        ParseError::Json(source) => RenderError::Json {
            path: path.into(),
            source,
        },
        ParseError::Schema(found) => RenderError::Schema {
            path: path.into(),
            found,
            expected: IR_SCHEMA,
        },
    })?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|source| RenderError::Json {
            path: path.into(),
            source,
        })?;
    crate::ir_check::check_text(&value)
        .and_then(|()| crate::ir_check::check_ir(&ir))
        .map_err(|r| refused(&r.key, r.problem))?;
    Ok(ir)
}

/// The IR in `text` with the shape of these types, its fields not checked ([`read_ir`] checks
/// them): what the tests of the escaping render past the reader.
pub fn parse_shape(text: &str) -> Result<Ir, String> {
    parse_ir(text).map_err(|e| match e {
        ParseError::Json(e) => e.to_string(),
        ParseError::Schema(s) => format!("schema {s:?}"),
    })
}

enum ParseError {
    Json(serde_json::Error),
    Schema(Option<u64>),
}

/// The IR in `text`: its schema first, then the whole document as the report's kind has it.
fn parse_ir(text: &str) -> Result<Ir, ParseError> {
    let header: Header = serde_json::from_str(text).map_err(ParseError::Json)?;
    if header.schema != Some(IR_SCHEMA) {
        return Err(ParseError::Schema(header.schema));
    }
    if header.templates.iter().any(|t| t == URDF_REPORT_TEMPLATE) {
        let ir: Ir<UrdfReport> = serde_json::from_str(text).map_err(ParseError::Json)?;
        Ok(ir.with_report(Report::Urdf))
    } else {
        let ir: Ir<ClosedFormReport> = serde_json::from_str(text).map_err(ParseError::Json)?;
        Ok(ir.with_report(Report::ClosedForm))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture() -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/pendulum.json");
        std::fs::read_to_string(path).expect("tests/fixtures/pendulum.json")
    }

    fn error(text: &str) -> String {
        match parse_ir(text) {
            Err(ParseError::Json(e)) => e.to_string(),
            Err(ParseError::Schema(s)) => format!("schema {s:?}"),
            Ok(_) => panic!("accepted"),
        }
    }

    #[test]
    fn the_fixture_reads_as_a_closed_form_model() {
        let ir = parse_ir(&fixture()).ok().expect("the fixture");
        assert_eq!(ir.model.name, "pendulum");
        assert!(matches!(ir.report, Report::ClosedForm(_)));
        assert!(ir.functions.iter().any(|f| f.coefficients.is_some()));
    }

    #[test]
    fn an_unknown_key_a_missing_one_and_a_wrong_kind_are_errors_naming_them() {
        let text = fixture();
        let unknown = text.replacen("\"dof\":", "\"degrees\": 1, \"dof\":", 1);
        let e = error(&unknown);
        assert!(
            e.contains("unknown field `degrees`") && e.contains("line"),
            "{e}"
        );
        let missing = text.replacen("\"state_dim\": 2,", "", 1);
        assert_ne!(missing, text);
        assert!(
            error(&missing).contains("missing field `state_dim`"),
            "{}",
            error(&missing)
        );
        let wrong = text.replacen("\"dof\": 1", "\"dof\": \"one\"", 1);
        assert_ne!(wrong, text);
        assert!(
            error(&wrong).contains("invalid type: string \"one\""),
            "{}",
            error(&wrong)
        );
    }

    #[test]
    fn another_schema_is_named_before_any_key() {
        assert_eq!(
            error(r#"{"schema": 99, "whatever": true}"#),
            "schema Some(99)"
        );
        assert_eq!(error(r#"{"model": {}}"#), "schema None");
    }

    #[test]
    fn a_urdf_report_where_a_closed_form_one_is_expected_is_an_error() {
        // The template variant says the report's kind; a closed-form report under it is refused.
        let text = fixture().replacen("{", "{\"templates\": [\"urdf/report.md.tera\"],", 1);
        assert!(
            error(&text).contains("unknown field `printed_where`"),
            "{}",
            error(&text)
        );
    }
}
