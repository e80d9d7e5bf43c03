//! The model registry: every generated model behind one object-safe trait, [`Model`], so that
//! code over all models (tool files, `rank`, the mixed sampler, the command line, the Python
//! package) dispatches once per tool or per batch instead of matching on models.
//!
//! * [`models`] is the one list of models (built from the generated registry,
//!   [`toolconf_generated::for_each_model!`], here and nowhere else); [`ModelKind`] is a `Copy` handle into it
//!   and [`ModelKind::from_str`] looks a model up by name.
//! * [`Model`] takes and returns data whose sizes are known only at run time (slices, `Vec`,
//!   [`Rows`]): what a model loaded at run time could implement as well. Its metadata is the
//!   generated [`ModelInfo`] table.
//! * Every generated model implements it through one generic struct over
//!   [`ArmModel`](crate::model::ArmModel) (`entry.rs`): inside a call, the const-generic code runs
//!   as before, with no dynamic call per step.
//! * [`Model::bind`] binds a task file's [`TaskSpec`] to the model once, as a [`BoundTask`]
//!   whose methods evaluate one tool (or a batch of tools) given as parameter slices.
//! * [`AnyTool`] is a validated tool of any model: its [`ModelKind`] and its parameters, stored
//!   inline (no allocation per tool).

pub(crate) mod entry;
mod flange;
mod results;
pub mod skeleton;

pub use flange::{flange_model, flange_models};

use std::fmt;
use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use crate::closed_loop::EpisodeOptions;
use crate::inputs::task_file::{TaskFileError, TaskSpec};
use crate::model::{ArmModel, Metrics, ModelSimulationError, ToolN};
use crate::prediction::{LinearSystem, Prediction, PredictionError};
use crate::{Error, TaskKind};
use toolconf_generated as generated;
use toolconf_generated::validity::ParameterDomain;

pub use entry::paper_options;
pub use generated::{Constraint, ModelInfo, MAX_PARAMETER_COUNT};
pub use results::{
    AnyEpisode, BatchError, Confidences, Linearisation, Rows, TaskTrace, TrajectoryTable, AXES,
};

/// One model, with the sizes known only at run time: its metadata, the rule its tools obey,
/// and the operations `rank`, `select`, `simulate`, `confidence` and the Python package ask of
/// it. Object-safe; every generated model implements it (`entry.rs`).
pub trait Model: Send + Sync {
    /// Names, sizes, units, tool rule, equilibrium and tasks.
    fn info(&self) -> &'static ModelInfo;

    /// Whether `params` (in [`ModelInfo::parameter_names`] order) is a valid tool: the right
    /// count, each parameter in its domain, every constraint held.
    fn check_tool(&self, params: &[f64]) -> Result<(), Error>;

    /// The spec's task bound to this model (its goals and precisions checked against the
    /// model's size), with the episode options and the task's validation kept for the
    /// operations that need them.
    fn bind(&self, spec: &TaskSpec) -> Result<Arc<dyn BoundTask>, TaskFileError>;

    /// ln|Π^U| and the episode's metrics of the tool `params` on the model's own paper-style
    /// `kind` task ([`ArmModel::paper_task`]), with `common`'s horizon, grid, perturbation,
    /// learning rate and integrator, X0 the model's equilibrium and U0 = `common.u0[0]` on
    /// every joint: what the mixed sampler's tools are evaluated by.
    fn paper_evaluation(
        &self,
        params: &[f64],
        kind: TaskKind,
        common: &EpisodeOptions,
    ) -> (Result<f64, Error>, Result<Metrics, ModelSimulationError>);

    /// The robot's own rigid-body dynamics Ẋ = [q̇; q̈] (U the joint torques) of `k` rows into
    /// `out` (k × NX, row major); each argument one row shared by every state or one row per
    /// state. The error names the row, or is the allocation that failed.
    fn rigid_body_dynamics(
        &self,
        k: usize,
        params: &Rows,
        x: &Rows,
        u: &Rows,
        out: &mut [f64],
    ) -> Result<(), BatchError>;

    /// The tool's tip y(q) (base frame, m) and its Jacobian ∂y/∂q of `k` rows of joint
    /// positions into `position` (k × 3) and `jacobian` (k × 3 × N, row major); `params` one row
    /// shared by every state or one per state. An error for a model without a tip.
    fn tip(
        &self,
        k: usize,
        params: &Rows,
        q: &Rows,
        position: &mut [f64],
        jacobian: &mut [f64],
    ) -> Result<(), BatchError>;

    /// The tip's acceleration at zero joint acceleration, J̇(q, q̇) q̇ (base frame, m/s²), of `k`
    /// rows of joint positions and rates into `bias` (k × 3), so that ÿ = J q̈ + J̇ q̇; `params`
    /// one row shared by every state or one per state. An error for a model without a tip.
    fn tip_bias(
        &self,
        k: usize,
        params: &Rows,
        q: &Rows,
        q_dot: &Rows,
        bias: &mut [f64],
    ) -> Result<(), BatchError>;
}

/// A task bound to one model ([`Model::bind`]): every method takes a tool as its parameters in
/// the model's order and checks them first.
pub trait BoundTask: Send + Sync + fmt::Debug {
    fn kind(&self) -> TaskKind;

    /// Why the spec's `[episode]` does not fit the model, if it does not.
    fn episode_error(&self) -> Option<&TaskFileError>;

    /// Why the task's goals and precisions are refused ([`crate::model::TaskN::validated`]),
    /// if they are.
    fn validation_error(&self) -> Option<&Error>;

    /// ln|Π^U| (eq. control_conf): the cheap stage.
    fn logdet(&self, params: &[f64]) -> Result<f64, Error>;

    /// ln|Π^U| and its gradient ∂ln|Π^U|/∂p (the generated closed form), in the model's
    /// parameter order: what `toolconf design` climbs.
    fn logdet_and_gradient(&self, params: &[f64]) -> Result<(f64, Vec<f64>), Error>;

    /// A, B, the task's sensitivities, Π^U and ln|Π^U| (`confidence --model`).
    fn linearisation(&self, params: &[f64]) -> Result<Linearisation, Error>;

    /// [`BoundTask::linearisation`] of k tools (`params`: k × NP, row major) as flat arrays,
    /// in parallel, every number checked finite; the error is the first bad tool's, with its
    /// index, or the output's allocation, which fails as an error rather than an abort.
    fn confidences(&self, params: &[f64]) -> Result<Confidences, BatchError>;

    /// The episode's metrics.
    fn simulate(&self, params: &[f64]) -> Result<Metrics, ModelSimulationError>;

    /// One episode, with its trajectory if `record`.
    fn episode(&self, params: &[f64], record: bool) -> Result<AnyEpisode, ModelSimulationError>;

    /// The task variable (θ, θ̇ or θ̈ as the task kind says) over time, with its goal.
    fn trace(&self, params: &[f64]) -> Result<TaskTrace, ModelSimulationError>;

    /// The episode's cost predicted by the closed loop linearised at the equilibrium
    /// ([`crate::prediction`]).
    fn predict(&self, params: &[f64]) -> Result<Prediction, PredictionError>;

    /// The linear system [`BoundTask::predict`] steps.
    fn linear_system(&self, params: &[f64]) -> Result<LinearSystem, PredictionError>;
}

/// One [`entry::Generated`] per generated model, in registry order.
macro_rules! registry {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        static MODELS: [&(dyn Model + 'static); generated::MODEL_NAMES.len()] = [$(
            &entry::Generated::<
                crate::model::$marker,
                { generated::$module::DOF },
                { generated::$module::STATE_DIM },
                { generated::$module::PARAMETER_COUNT },
                { generated::$module::STATE_DIM + generated::$module::DOF },
            >::new(&generated::MODELS[registry_index($name)]),
        )*];

        /// Handles of the generated models by their marker names (`ModelKind::Arm2`).
        #[allow(non_upper_case_globals)]
        impl ModelKind {
            $(
                #[doc = $title]
                pub const $marker: ModelKind = ModelKind::builtin($name);
            )*
        }
    };
}

toolconf_generated::for_each_model!(registry);

/// The most models one process loads at run time ([`crate::loaded`]).
pub const MAX_LOADED: usize = 64;

/// The models registered at run time (loaded model libraries), after the generated ones: a
/// slot is filled once, then [`LOADED_COUNT`] counts it, so a reader that sees the count sees
/// the model.
static LOADED: [OnceLock<&'static dyn Model>; MAX_LOADED] = [const { OnceLock::new() }; MAX_LOADED];
static LOADED_COUNT: AtomicUsize = AtomicUsize::new(0);
static REGISTERING: Mutex<()> = Mutex::new(());

/// Registers a model made at run time after every model there is; its handle.
pub(crate) fn register(model: &'static dyn Model) -> Result<ModelKind, String> {
    let _one_at_a_time = REGISTERING.lock().unwrap_or_else(|p| p.into_inner());
    let i = LOADED_COUNT.load(Ordering::Acquire);
    if i >= MAX_LOADED {
        return Err(format!(
            "{MAX_LOADED} models are loaded already, the most one process holds"
        ));
    }
    if LOADED[i].set(model).is_err() {
        return Err("the registry's slot was filled meanwhile".into());
    }
    LOADED_COUNT.store(i + 1, Ordering::Release);
    Ok(ModelKind((MODELS.len() + i) as u16))
}

/// Every model, in registry order: the generated ones, then those loaded at run time.
pub fn models() -> Vec<&'static dyn Model> {
    ModelKind::all().into_iter().map(ModelKind::model).collect()
}

/// A model by name (case and surrounding blanks ignored), or the error naming the models there
/// are.
pub fn lookup(name: &str) -> Result<ModelKind, String> {
    name.parse()
}

/// A model of the registry: a `Copy` handle into [`models`], ordered as the registry is.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ModelKind(u16);

/// `name`'s place in the generated registry, at compile time.
const fn registry_index(name: &str) -> usize {
    let mut i = 0;
    while i < generated::MODEL_NAMES.len() {
        if const_eq(generated::MODEL_NAMES[i], name) {
            return i;
        }
        i += 1;
    }
    panic!("a model the generated registry does not list");
}

const fn const_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

impl ModelKind {
    /// Every model: the generated ones ([`ModelKind::BUILT_IN`]), then those loaded at run time.
    pub fn all() -> Vec<ModelKind> {
        let count = MODELS.len() + LOADED_COUNT.load(Ordering::Acquire);
        (0..count).map(|i| ModelKind(i as u16)).collect()
    }

    /// Every generated model, in registry order.
    pub const BUILT_IN: [ModelKind; generated::MODEL_NAMES.len()] = {
        let mut all = [ModelKind(0); generated::MODEL_NAMES.len()];
        let mut i = 0;
        while i < all.len() {
            all[i] = ModelKind(i as u16);
            i += 1;
        }
        all
    };

    /// The paper's 2-link arm (`arm2`): the model where none is named (a tools file without a
    /// `model` column, `select` without `--models`), whose tools the typed 2-link API
    /// ([`crate::Arm`], [`crate::closed_loop::Plant`]) runs.
    pub const PAPER_ARM: ModelKind = ModelKind::builtin(generated::arm2::NAME);

    const fn builtin(name: &str) -> Self {
        ModelKind(registry_index(name) as u16)
    }

    /// The handle of the model `M` implements (registered: every generated model is, and a
    /// loaded one from its loading on).
    pub fn of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>() -> Self
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let name = M::name();
        Self::all()
            .into_iter()
            .find(|k| k.name() == name)
            .expect("a model's marker is used only once the model is registered")
    }

    /// Whether the model was loaded at run time (a model library), not generated.
    pub fn is_loaded(self) -> bool {
        self.index() >= MODELS.len()
    }

    /// Its place in [`models`].
    pub fn index(self) -> usize {
        usize::from(self.0)
    }

    /// The model's operations.
    pub fn model(self) -> &'static dyn Model {
        match MODELS.get(self.index()) {
            Some(model) => *model,
            None => *LOADED[self.index() - MODELS.len()]
                .get()
                .expect("a handle is made only for a registered model"),
        }
    }

    pub fn info(self) -> &'static ModelInfo {
        self.model().info()
    }

    /// The generated module's name.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The model's title (its description's `model.title`).
    pub fn title(self) -> &'static str {
        self.info().title
    }

    /// The control dimension n (joints).
    pub fn dof(self) -> usize {
        self.info().dof
    }

    /// The tool parameters' names, in the order a tool takes them.
    pub fn parameter_names(self) -> &'static [&'static str] {
        self.info().parameter_names
    }

    /// The tool parameters' units (kg, m, kg m^2, ...), in the same order.
    pub fn parameter_units(self) -> &'static [&'static str] {
        self.info().parameter_units
    }

    /// Each tool parameter's domain (`generated::validity`), in the same order.
    pub fn parameter_domains(self) -> &'static [ParameterDomain] {
        self.info().domains
    }

    /// The constraints across the tool parameters, each c · p ≤ 0 as (c, its text).
    pub fn parameter_constraints(self) -> Vec<(&'static [f64], &'static str)> {
        self.info()
            .constraints
            .iter()
            .map(|c| (c.coefficients, c.rule))
            .collect()
    }

    /// The box random tools are drawn from, (lo, hi) per parameter.
    pub fn sample_box(self) -> &'static [(f64, f64)] {
        self.info().sample
    }

    /// Per parameter, what a tools file that leaves its column out means (`None`: required).
    pub fn parameter_defaults(self) -> &'static [Option<f64>] {
        self.info().defaults
    }

    /// How many parameters a tool must give: all but the trailing ones with a default.
    pub fn required_parameters(self) -> usize {
        let d = self.parameter_defaults();
        d.len() - d.iter().rev().take_while(|v| v.is_some()).count()
    }

    /// `params` with the trailing defaults added when it gives exactly the required ones (a
    /// URDF tool of toolconf's earlier 7 parameters: no products of inertia, tip at the flange);
    /// `None` when it needs none.
    pub fn with_defaults(self, params: &[f64]) -> Option<Vec<f64>> {
        let (required, d) = (self.required_parameters(), self.parameter_defaults());
        (params.len() == required && required < d.len()).then(|| {
            let tail = d[required..].iter().map(|v| v.unwrap_or(0.0));
            params.iter().copied().chain(tail).collect()
        })
    }

    /// Whether the model's tools have a tip ([`Model::tip`]).
    pub fn has_tip(self) -> bool {
        self.info().has_tip
    }

    /// The equilibrium X^e = [q^e; q̇^e] the model is linearised at.
    pub fn equilibrium_state(self) -> &'static [f64] {
        self.info().equilibrium_state
    }

    /// The equilibrium torque U^e.
    pub fn equilibrium_control(self) -> &'static [f64] {
        self.info().equilibrium_control
    }
}

impl fmt::Debug for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ModelKind({})", self.name())
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim().to_ascii_lowercase();
        let all = ModelKind::all();
        all.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<&str> = all.iter().map(|m| m.name()).collect();
            format!(
                "unknown model '{}': expected one of {} (or a model library loaded with \
                 --model-path, {} or toolconf.load_model)",
                toolconf_messages::Clip(&s),
                names.join(", "),
                crate::loaded::ENVIRONMENT
            )
        })
    }
}

/// A validated tool of any model: the model and its parameters (the first
/// `model.parameter_names().len()` of an inline array; the rest zero).
#[derive(Clone, Copy, PartialEq)]
pub struct AnyTool {
    model: ModelKind,
    params: [f64; MAX_PARAMETER_COUNT],
}

impl AnyTool {
    /// Builds a validated tool of `model` from its parameters in the model's order.
    pub fn new(model: ModelKind, params: &[f64]) -> Result<Self, Error> {
        model.model().check_tool(params)?;
        let mut inline = [0.0; MAX_PARAMETER_COUNT];
        inline[..params.len()].copy_from_slice(params);
        Ok(Self {
            model,
            params: inline,
        })
    }

    pub fn model(&self) -> ModelKind {
        self.model
    }

    /// The parameters, in the model's order.
    pub fn parameters(&self) -> &[f64] {
        &self.params[..self.model.parameter_names().len()]
    }

    /// (name, value) of every parameter, in the model's order.
    pub fn named_parameters(&self) -> Vec<(&'static str, f64)> {
        self.model
            .parameter_names()
            .iter()
            .copied()
            .zip(self.parameters().iter().copied())
            .collect()
    }

    /// The tool as one of model `M`'s, if it is one: for code that runs a model's typed API
    /// (the exact 2-link plant, benchmarks).
    pub fn downcast<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
    ) -> Option<ToolN<M, N, NX, NP, NZ>>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        if self.model.name() != M::name() {
            return None;
        }
        ToolN::new(self.parameters().try_into().ok()?).ok()
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    From<ToolN<M, N, NX, NP, NZ>> for AnyTool
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn from(tool: ToolN<M, N, NX, NP, NZ>) -> Self {
        let mut params = [0.0; MAX_PARAMETER_COUNT];
        params[..NP].copy_from_slice(tool.params().as_slice());
        Self {
            model: ModelKind::of::<M, N, NX, NP, NZ>(),
            params,
        }
    }
}

impl fmt::Display for AnyTool {
    /// `model(m1=… m2=… …)`, as a model's own tool prints.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}(", self.model.name())?;
        for (i, (name, value)) in self.named_parameters().into_iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{name}={}", toolconf_messages::Short(value))?;
        }
        f.write_str(")")
    }
}

impl fmt::Debug for AnyTool {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trait objects, the handles and the generated table agree on every model's place.
    #[test]
    fn registry_order_is_the_generated_one() {
        assert_eq!(models().len(), generated::MODEL_NAMES.len());
        for (i, kind) in ModelKind::BUILT_IN.into_iter().enumerate() {
            assert_eq!(kind.index(), i);
            assert_eq!(models()[i].info().name, generated::MODEL_NAMES[i]);
            assert_eq!(kind.name(), generated::MODEL_NAMES[i]);
            assert_eq!(
                lookup(&format!(" {} ", kind.name().to_uppercase())),
                Ok(kind)
            );
        }
        assert_eq!(ModelKind::Arm2.name(), "arm2");
        assert_eq!(
            ModelKind::of::<crate::model::Panda, 7, 14, 13, 21>(),
            ModelKind::Panda
        );
    }

    /// A tool keeps its parameters, prints as its model's own tool and converts back.
    #[test]
    fn any_tool_round_trips() {
        let typed = crate::model::Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
        let any = AnyTool::from(typed);
        assert_eq!(
            any,
            AnyTool::new(ModelKind::Arm3, &[0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap()
        );
        assert_eq!(any.to_string(), format!("{typed:?}"));
        assert_eq!(
            any.downcast::<crate::model::Arm3, 3, 6, 6, 9>(),
            Some(typed)
        );
        assert!(any.downcast::<crate::model::Arm2, 2, 4, 4, 6>().is_none());
        assert!(matches!(
            AnyTool::new(ModelKind::Arm3, &[0.3; 4]),
            Err(Error::ParameterCount {
                expected: 6,
                found: 4,
                ..
            })
        ));
    }
}
