//! Task files: a task of the user's own, in TOML, for any model.
//!
//! ```toml
//! kind = "position"              # position | velocity | acceleration: the paper's three task structures;
//!                                # tip_position | tip_velocity | tip_acceleration: on the tool's tip (goal
//!                                # keys tip, tip_dot, tip_ddot: the tip's components in the base frame,
//!                                # m, m/s and m/s², 3 for a URDF arm, 2 for a planar one; a scalar
//!                                # precision weighs those components alone)
//! description = "reach 45°"      # optional, shown in reports
//! [goal]                         # optional, each key defaulting to the model's paper goal
//! theta = [0.7853981633974483, 0.0]
//! [precision]                    # a scalar is that multiple of I; a matrix is given row by row
//! theta = 80.0
//! theta_dot = [[50.0, 0.0], [0.0, 50.0]]
//! [episode]                      # optional; the paper's defaults otherwise
//! t_end = 5.0
//! dt = 0.05
//! perturbation = 0.0             # ΔT on every joint, or one value per joint: [0.2, -0.1]
//! learning_rate = 1.0            # γ
//! initial_theta = [-1.5707963267948966, -1.5707963267948966]   # default: the hanging equilibrium
//! initial_theta_dot = [0.0, 0.0]
//! initial_torque = 0.1           # U0 on every joint, or one value per joint
//! rtol = 1e-3                    # integrator tolerances (MATLAB ode45's by default)
//! atol = 1e-6
//! ```
//!
//! Parsing checks everything that does not depend on the model (unknown keys, shapes, finite
//! numbers, symmetric positive semi-definite precisions, episode options); [`TaskSpec::task`] and
//! [`TaskSpec::episode`] then check sizes against one model and fill what the file leaves out
//! from that model's paper-style task. Every error names the file and the key (or the line, for
//! TOML syntax) and the value.

use std::fmt;
use std::path::Path;

use nalgebra::{DMatrix, SMatrix, SVector};
use serde::Deserialize;

use crate::inputs::bounded_read::read_text_file;
use crate::model::closed_loop_n::check_grid;
use crate::model::{ArmModel, EpisodeOptionsN, TaskN};
use crate::validate::goal_range;
use crate::{TaskKind, Term};
use toolconf_core::{term_components, term_identity};
use toolconf_generated::TERMS;
use toolconf_messages::{Clip, ClipMessage, ClipPath, Short, ShortList, ShortRows as Rows};

mod tip_goal;
pub use tip_goal::{at_initial_tip, TipGoal};
use tip_goal::{RelativeKeys, RELATIVE_KEYS};

/// A bad task file: the file, where in it (a key or a line), and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct TaskFileError {
    pub file: String,
    /// `key goal.theta`, `line 4`, or empty when the whole file is meant.
    pub place: String,
    pub message: String,
}

impl fmt::Display for TaskFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        super::write_located(f, &self.file, &self.place, &self.message)
    }
}

/// A precision as written: `s` means s·I, or a full matrix.
#[derive(Debug, Clone, PartialEq)]
pub enum PrecisionSpec {
    Scalar(f64),
    Matrix(Vec<Vec<f64>>),
}

/// A per-joint quantity as written: one value for every joint, or one per joint.
#[derive(Debug, Clone, PartialEq)]
pub enum PerJoint {
    All(f64),
    Each(Vec<f64>),
}

impl PerJoint {
    /// The value on every joint, if it is the same on all of them.
    pub fn uniform(&self) -> Option<f64> {
        match self {
            PerJoint::All(v) => Some(*v),
            PerJoint::Each(v) if v.windows(2).all(|w| w[0] == w[1]) => v.first().copied(),
            PerJoint::Each(_) => None,
        }
    }
}

/// The `[episode]` table; `None` is the paper's default.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EpisodeSpec {
    pub t_end: Option<f64>,
    pub dt: Option<f64>,
    pub perturbation: Option<PerJoint>,
    pub learning_rate: Option<f64>,
    pub initial_theta: Option<Vec<f64>>,
    pub initial_theta_dot: Option<Vec<f64>>,
    pub initial_torque: Option<PerJoint>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    /// The integration method (not a task-file key: the command line's `--method`).
    pub method: Option<toolconf_integrators::Method>,
}

/// A task: one of the paper's built-in tasks, or a task file's, not yet bound to a model.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskSpec {
    /// The file it came from ("" for a built-in task).
    pub file: String,
    pub kind: TaskKind,
    pub description: Option<String>,
    /// The goals the file gives, by [`Term::index`] (`None`: the model's paper goal).
    pub goal: [Option<Vec<f64>>; TERMS],
    /// The precisions the file gives, by [`Term::index`] (`None`: the model's paper precision,
    /// or on a tip task file the robot's own scales: [`crate::robot_scales`]).
    pub precision: [Option<PrecisionSpec>; TERMS],
    pub episode: EpisodeSpec,
    /// Whether the tip goal is absolute or relative to each tool's own tip ([`TipGoal`]).
    pub tip_goal: TipGoal,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTask {
    kind: String,
    description: Option<String>,
    #[serde(default)]
    goal: RawGoal,
    #[serde(default)]
    precision: TermTable<toml::Value, false>,
    #[serde(default)]
    episode: RawEpisode,
}

/// A table keyed by term names ([`Term::name`]), as serde's `deny_unknown_fields` would read a
/// struct with one optional field per term: `[goal]` (`GOALS`: the terms with a goal) or
/// `[precision]` (every term). An unknown key is serde's own "unknown field" error, so a task
/// file's message and place are those of any other misspelt key.
struct TermTable<V, const GOALS: bool> {
    values: [Option<V>; TERMS],
}

impl<V, const GOALS: bool> Default for TermTable<V, GOALS> {
    fn default() -> Self {
        Self {
            values: std::array::from_fn(|_| None),
        }
    }
}

impl<V, const GOALS: bool> TermTable<V, GOALS> {
    /// The keys it accepts, and the name its messages give it.
    const NAMES: &'static [&'static str] = if GOALS {
        &Term::GOAL_NAMES
    } else {
        &Term::NAMES
    };
    const STRUCT: &'static str = if GOALS { "RawGoal" } else { "RawPrecision" };
}

impl<'de, V: Deserialize<'de>, const GOALS: bool> Deserialize<'de> for TermTable<V, GOALS> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Keys<V, const GOALS: bool>(std::marker::PhantomData<V>);
        impl<'de, V: Deserialize<'de>, const GOALS: bool> serde::de::Visitor<'de> for Keys<V, GOALS> {
            type Value = TermTable<V, GOALS>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "struct {}", TermTable::<V, GOALS>::STRUCT)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Self::Value, A::Error> {
                let names = TermTable::<V, GOALS>::NAMES;
                let mut table = TermTable::default();
                while let Some(term) = map.next_key_seed(term_key(names))? {
                    if table.values[term.index()].is_some() {
                        return Err(serde::de::Error::duplicate_field(term.name()));
                    }
                    table.values[term.index()] = Some(map.next_value()?);
                }
                Ok(table)
            }
        }
        let (name, names) = (Self::STRUCT, Self::NAMES);
        deserializer.deserialize_struct(name, names, Keys::<V, GOALS>(std::marker::PhantomData))
    }
}

/// A table's key, read as serde's derived field identifiers are: `read` gives its meaning, and
/// a key it does not know is refused, as one of `known`, while the key itself is read, so that
/// the file's reader points the message at the key's line, not the table's.
struct Key<F> {
    read: F,
    known: &'static [&'static str],
}

impl<'de, T, F: FnOnce(&str) -> Option<T>> serde::de::DeserializeSeed<'de> for Key<F> {
    type Value = T;
    fn deserialize<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<T, D::Error> {
        deserializer.deserialize_identifier(self)
    }
}

impl<'de, T, F: FnOnce(&str) -> Option<T>> serde::de::Visitor<'de> for Key<F> {
    type Value = T;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("field identifier")
    }
    fn visit_str<E: serde::de::Error>(self, key: &str) -> Result<T, E> {
        (self.read)(key).ok_or_else(|| E::unknown_field(key, self.known))
    }
}

/// A `[goal]`/`[precision]` key: a term among `names`.
fn term_key(names: &'static [&'static str]) -> Key<impl FnOnce(&str) -> Option<Term>> {
    Key {
        read: move |key: &str| Term::from_name(key).filter(|t| names.contains(&t.name())),
        known: names,
    }
}

/// `[goal]`: the terms' goals by name ([`Term::GOAL_NAMES`]) and the relative tip goal's keys
/// ([`RELATIVE_KEYS`]); an unknown key is serde's "unknown field" error at its own line, listing
/// both.
#[derive(Default)]
struct RawGoal {
    terms: [Option<Vec<f64>>; TERMS],
    relative: RelativeKeys,
}

/// Every key `[goal]` takes, for the message of an unknown one.
fn goal_keys() -> &'static [&'static str] {
    static KEYS: std::sync::OnceLock<Vec<&'static str>> = std::sync::OnceLock::new();
    KEYS.get_or_init(|| {
        Term::GOAL_NAMES
            .iter()
            .chain(&RELATIVE_KEYS)
            .copied()
            .collect()
    })
}

impl<'de> Deserialize<'de> for RawGoal {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Keys;
        impl<'de> serde::de::Visitor<'de> for Keys {
            type Value = RawGoal;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("struct RawGoal")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<RawGoal, A::Error> {
                let mut goal = RawGoal::default();
                while let Some(key) = map.next_key_seed(goal_key())? {
                    goal.take(key, &mut map)?;
                }
                Ok(goal)
            }
        }
        deserializer.deserialize_struct("RawGoal", goal_keys(), Keys)
    }
}

impl RawGoal {
    /// The value of `key`, refused if the key was given before.
    fn take<'de, A: serde::de::MapAccess<'de>>(
        &mut self,
        key: GoalKeyName,
        map: &mut A,
    ) -> Result<(), A::Error> {
        fn once<T, E: serde::de::Error>(
            slot: &mut Option<T>,
            v: T,
            name: &'static str,
        ) -> Result<(), E> {
            if slot.is_some() {
                return Err(E::duplicate_field(name));
            }
            *slot = Some(v);
            Ok(())
        }
        let r = &mut self.relative;
        match key {
            GoalKeyName::Term(t) => once(&mut self.terms[t.index()], map.next_value()?, t.name()),
            GoalKeyName::Relative(0) => once(&mut r.offset, map.next_value()?, RELATIVE_KEYS[0]),
            GoalKeyName::Relative(1) => once(&mut r.direction, map.next_value()?, RELATIVE_KEYS[1]),
            GoalKeyName::Relative(2) => once(&mut r.speed, map.next_value()?, RELATIVE_KEYS[2]),
            GoalKeyName::Relative(_) => {
                once(&mut r.acceleration, map.next_value()?, RELATIVE_KEYS[3])
            }
        }
    }
}

/// A `[goal]` key: a term's goal or one of [`RELATIVE_KEYS`] (by its index).
enum GoalKeyName {
    Term(Term),
    Relative(usize),
}

/// Reads a `[goal]` key, refusing an unknown one at its own line.
fn goal_key() -> Key<impl FnOnce(&str) -> Option<GoalKeyName>> {
    Key {
        read: |key: &str| {
            if let Some(t) = Term::from_name(key).filter(|t| Term::GOAL_NAMES.contains(&t.name())) {
                return Some(GoalKeyName::Term(t));
            }
            RELATIVE_KEYS
                .iter()
                .position(|k| *k == key)
                .map(GoalKeyName::Relative)
        },
        known: goal_keys(),
    }
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawEpisode {
    t_end: Option<f64>,
    dt: Option<f64>,
    perturbation: Option<toml::Value>,
    learning_rate: Option<f64>,
    initial_theta: Option<Vec<f64>>,
    initial_theta_dot: Option<Vec<f64>>,
    initial_torque: Option<toml::Value>,
    rtol: Option<f64>,
    atol: Option<f64>,
}

impl TaskSpec {
    /// The paper's task `kind`: every model's own paper-style task, with the paper's episode.
    pub fn builtin(kind: TaskKind) -> Self {
        Self {
            file: String::new(),
            kind,
            description: None,
            goal: std::array::from_fn(|_| None),
            precision: std::array::from_fn(|_| None),
            episode: EpisodeSpec::default(),
            tip_goal: TipGoal::Absolute,
        }
    }

    /// Reads and checks a task file.
    pub fn from_file(path: &Path) -> Result<Self, TaskFileError> {
        let file = ClipPath(&path.to_string_lossy()).to_string();
        let text = read_text_file(path, "task file").map_err(|message| TaskFileError {
            file: file.clone(),
            place: String::new(),
            message,
        })?;
        Self::parse(&text, &file)
    }

    /// Parses and checks task-file text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, TaskFileError> {
        let raw: RawTask = toml::from_str(text).map_err(|e| TaskFileError {
            file: file.into(),
            place: e
                .span()
                .map(|s| syntax_place(text, s.start))
                .unwrap_or_default(),
            message: ClipMessage(&e.message().trim().replace('\n', " ")).to_string(),
        })?;
        Self::from_raw(raw, file)
    }

    /// The checks and conversions after TOML has been read into [`RawTask`].
    fn from_raw(raw: RawTask, file: &str) -> Result<Self, TaskFileError> {
        let err = |key: &str, message: String| TaskFileError {
            file: file.into(),
            place: format!("key {key}"),
            message,
        };
        let kind: TaskKind = raw.kind.parse().map_err(|_| {
            err(
                "kind",
                format!(
                    "'{}' is not a task kind: expected {}",
                    Clip(&raw.kind),
                    crate::task::task_choices()
                ),
            )
        })?;
        let mut precision: [Option<PrecisionSpec>; TERMS] = std::array::from_fn(|_| None);
        for (term, v) in Term::ALL.into_iter().zip(raw.precision.values) {
            let key = format!("precision.{term}");
            precision[term.index()] = v
                .map(|v| precision_spec(&v).map_err(|m| err(&key, m)))
                .transpose()?;
        }
        let per_joint = |key: &str, v: Option<toml::Value>| {
            v.map(|v| per_joint_spec(&v).map_err(|m| err(key, m)))
                .transpose()
        };
        let e = raw.episode;
        let mut goal = raw.goal.terms;
        let tip_goal =
            tip_goal::resolve(kind, raw.goal.relative, &mut goal).map_err(|(k, m)| err(&k, m))?;
        let spec = TaskSpec {
            file: file.into(),
            kind,
            description: raw.description,
            goal,
            tip_goal,
            precision,
            episode: EpisodeSpec {
                t_end: e.t_end,
                dt: e.dt,
                perturbation: per_joint("episode.perturbation", e.perturbation)?,
                learning_rate: e.learning_rate,
                initial_theta: e.initial_theta,
                initial_theta_dot: e.initial_theta_dot,
                initial_torque: per_joint("episode.initial_torque", e.initial_torque)?,
                rtol: e.rtol,
                atol: e.atol,
                method: None,
            },
        };
        spec.check().map_err(|(key, m)| err(&key, m))?;
        Ok(spec)
    }

    /// A short name: the file, or the built-in task's name.
    pub fn label(&self) -> String {
        if self.file.is_empty() {
            format!("{} (task {})", self.kind, self.kind.paper_index())
        } else {
            format!("{} ({})", self.file, self.kind)
        }
    }

    /// An error at `key` of this task: the file, or `task <kind>` for a built-in task.
    pub fn error(&self, key: &str, message: String) -> TaskFileError {
        TaskFileError {
            file: if self.file.is_empty() {
                format!("task {}", self.kind)
            } else {
                self.file.clone()
            },
            place: format!("key {key}"),
            message,
        }
    }

    /// The checks that need no model: terms the task uses, finite numbers, precisions symmetric
    /// positive semi-definite, episode options in range. Returns (key, message).
    fn check(&self) -> Result<(), (String, String)> {
        for term in Term::ALL {
            if self.kind.uses(term) {
                continue;
            }
            let key = match (&self.goal[term.index()], &self.precision[term.index()]) {
                (Some(_), _) => format!("goal.{term}"),
                (None, Some(_)) => format!("precision.{term}"),
                (None, None) => continue,
            };
            let used_by: Vec<&str> = TaskKind::ALL
                .iter()
                .filter(|k| k.uses(term))
                .map(|k| k.name())
                .collect();
            let message = format!(
                "a {} task does not use it ({} only)",
                self.kind,
                used_by.join(" and ")
            );
            return Err((key, message));
        }
        for term in Term::ALL {
            if let (Some(v), Some(range)) = (&self.goal[term.index()], goal_range(term)) {
                in_range(v, range).map_err(|m| (format!("goal.{term}"), m))?;
            }
        }
        for term in Term::ALL {
            if let Some(p) = &self.precision[term.index()] {
                check_precision(p).map_err(|m| (format!("precision.{term}"), m))?;
            }
        }
        self.episode.check().map_err(|(k, m)| (k.to_string(), m))
    }

    /// The task for model `M`: the file's goals and precisions, the rest from `M`'s paper-style
    /// task (on a tip task file for a URDF arm, from the robot's own scales:
    /// [`crate::robot_scales`]). Errors when a goal or precision has the wrong size for `M`, and
    /// for a tip goal relative to each tool's tip, which needs the tool
    /// ([`TaskSpec::task_and_offset`]).
    pub fn task<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
    ) -> Result<TaskN<N>, TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        match self.task_and_offset::<M, N, NX, NP, NZ>()? {
            (task, None) => Ok(task),
            (_, Some(_)) => Err(tip_goal::needs_absolute(&self.file)),
        }
    }

    /// The task for model `M` and, for a `tip_offset` goal, the offset (padded as the task's tip
    /// rows are): each tool's goal is then [`at_initial_tip`]. Until then the task's tip goal is
    /// zero, which nothing but the episode reads (Π^U does not depend on goals).
    pub fn task_and_offset<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
    ) -> Result<(TaskN<N>, Option<SVector<f64, N>>), TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let mut task = M::paper_task(self.kind);
        for term in Term::ALL {
            if let Some(v) = &self.goal[term.index()] {
                task.goal[term.index()] =
                    self.term_vector::<M, N, NX, NP, NZ>(term, &format!("goal.{term}"), v)?;
            }
        }
        let offset = match &self.tip_goal {
            TipGoal::Offset(v) => {
                let offset =
                    self.term_vector::<M, N, NX, NP, NZ>(Term::Tip, "goal.tip_offset", v)?;
                task.goal[Term::Tip.index()] = SVector::zeros();
                Some(offset)
            }
            _ => None,
        };
        self.robot_scale_precisions::<M, N, NX, NP, NZ>(&mut task)?;
        for term in Term::ALL {
            let Some(given) = &self.precision[term.index()] else {
                continue;
            };
            let d = term_components(term, N, M::tip_dim());
            task.precision[term.index()] = match given {
                PrecisionSpec::Scalar(s) => term_identity::<N>(term, M::tip_dim()) * *s,
                PrecisionSpec::Matrix(rows) => {
                    if rows.len() != d {
                        return Err(self.error(
                            &format!("precision.{term}"),
                            format!(
                                "a {0}×{0} matrix, but {term} of model {1} has {d} components",
                                rows.len(),
                                M::name()
                            ),
                        ));
                    }
                    SMatrix::from_fn(|i, j| if i < d && j < d { rows[i][j] } else { 0.0 })
                }
            };
        }
        task.validate()
            .map_err(|e| self.error("precision", e.to_string()))?;
        Ok((task, offset))
    }

    /// On a tip task file (not a built-in task) for a URDF arm, every precision the file leaves
    /// out from the robot's own scales ([`crate::robot_scales`]); other models and built-in tasks
    /// keep the paper's. A URDF arm whose rated torques cannot be read is an error naming the
    /// first precision that would need them.
    fn robot_scale_precisions<
        M,
        const N: usize,
        const NX: usize,
        const NP: usize,
        const NZ: usize,
    >(
        &self,
        task: &mut TaskN<N>,
    ) -> Result<(), TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let missing: Vec<Term> = Term::ALL
            .into_iter()
            .filter(|t| self.kind.uses(*t) && self.precision[t.index()].is_none())
            .collect();
        if self.file.is_empty() || !toolconf_core::reads_tip(self.kind) || missing.is_empty() {
            return Ok(());
        }
        let rated = match crate::robot_scales::rated_torques_of(M::name()) {
            Ok(Some(rated)) => rated,
            Ok(None) => return Ok(()),
            Err(why) => {
                return Err(self.error(
                    &format!("precision.{}", missing[0]),
                    format!(
                        "not given, and its default comes from the robot's rated torques, \
                         which cannot be read ({why}): give precision.{} in the task",
                        missing[0]
                    ),
                ))
            }
        };
        for term in missing {
            let Some(diagonal) = crate::robot_scales::default_precision(term, &rated, M::tip_dim())
            else {
                continue;
            };
            let mut p = SMatrix::<f64, N, N>::zeros();
            for (i, v) in diagonal.iter().enumerate().take(N) {
                p[(i, i)] = *v;
            }
            task.precision[term.index()] = p;
        }
        Ok(())
    }

    /// The episode options for model `M`: the file's `[episode]`, the rest the paper's.
    pub fn episode<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
    ) -> Result<EpisodeOptionsN<N, NX>, TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let e = &self.episode;
        let mut o = EpisodeOptionsN::<N, NX>::paper::<M, NP, NZ>();
        o.t_end = e.t_end.unwrap_or(o.t_end);
        o.dt = e.dt.unwrap_or(o.dt);
        o.learning_rate = e.learning_rate.unwrap_or(o.learning_rate);
        o.integrator.rtol = e.rtol.unwrap_or(o.integrator.rtol);
        o.integrator.atol = e.atol.unwrap_or(o.integrator.atol);
        o.integrator.method = e.method.unwrap_or(o.integrator.method);
        if let Some(v) = &e.initial_theta {
            let theta = self.vector::<M, N, NX, NP, NZ>("episode.initial_theta", v)?;
            o.x0.fixed_rows_mut::<N>(0).copy_from(&theta);
        }
        if let Some(v) = &e.initial_theta_dot {
            let rate = self.vector::<M, N, NX, NP, NZ>("episode.initial_theta_dot", v)?;
            o.x0.fixed_rows_mut::<N>(N).copy_from(&rate);
        }
        if let Some(u0) = &e.initial_torque {
            o.u0 = self.per_joint::<M, N, NX, NP, NZ>("episode.initial_torque", u0)?;
        }
        match &e.perturbation {
            Some(PerJoint::All(v)) => o.perturbation = *v,
            Some(each @ PerJoint::Each(_)) => {
                o.joint_perturbation =
                    self.per_joint::<M, N, NX, NP, NZ>("episode.perturbation", each)?;
            }
            None => {}
        }
        Ok(o)
    }

    /// A goal of `term` for model `M`: N values for a joint term, the tip's
    /// [`ArmModel::tip_dim`] for a tip term, padded with zeros ([`TaskN`]).
    fn term_vector<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        term: Term,
        key: &str,
        v: &[f64],
    ) -> Result<SVector<f64, N>, TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        if !matches!(term.read(), toolconf_generated::Read::Tip { .. }) {
            return self.vector::<M, N, NX, NP, NZ>(key, v);
        }
        let d = term_components(term, N, M::tip_dim());
        if v.len() != d {
            let axes = crate::registry::AXES[..d.min(3)].join(", ");
            let tip = format!("the tip of model {} has {d} components ({axes})", M::name());
            return Err(self.wrong_count(key, v, &tip));
        }
        Ok(SVector::from_fn(|i, _| if i < d { v[i] } else { 0.0 }))
    }

    fn vector<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        key: &str,
        v: &[f64],
    ) -> Result<SVector<f64, N>, TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        if v.len() != N {
            let joints = format!("model {} has {N} joints", M::name());
            return Err(self.wrong_count(key, v, &joints));
        }
        Ok(SVector::from_column_slice(v))
    }

    /// `key`'s list `v` has the wrong length: "3 values [..], but `expected`".
    fn wrong_count(&self, key: &str, v: &[f64], expected: &str) -> TaskFileError {
        let given = format!("{} values {}", v.len(), ShortList(v));
        self.error(key, format!("{given}, but {expected}"))
    }

    fn per_joint<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        key: &str,
        v: &PerJoint,
    ) -> Result<SVector<f64, N>, TaskFileError>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        match v {
            PerJoint::All(x) => Ok(SVector::repeat(*x)),
            PerJoint::Each(v) => self.vector::<M, N, NX, NP, NZ>(key, v),
        }
    }
}

impl EpisodeSpec {
    /// Every option against its documented range ([`crate::validate`]), dt against t_end and
    /// the grid's size, the defaults standing in for what is not given. Returns (key, message).
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        use crate::validate::{
            ATOL, DT, JOINT_ANGLE, JOINT_RATE, LEARNING_RATE, RTOL, TORQUE, T_END,
        };
        let within = |key: &'static str, v: Option<f64>, range: crate::validate::Range| match v {
            Some(x) => range.check(x).map(|_| ()).map_err(|m| (key, m)),
            None => Ok(()),
        };
        within("episode.t_end", self.t_end, T_END)?;
        within("episode.dt", self.dt, DT)?;
        within("episode.learning_rate", self.learning_rate, LEARNING_RATE)?;
        within("episode.rtol", self.rtol, RTOL)?;
        within("episode.atol", self.atol, ATOL)?;
        let (t_end, dt) = (self.t_end.unwrap_or(5.0), self.dt.unwrap_or(0.05));
        if dt > t_end {
            return Err((
                "episode.dt",
                format!(
                    "the output step dt = {} s is larger than t_end = {} s",
                    Short(dt),
                    Short(t_end)
                ),
            ));
        }
        check_grid(t_end, dt).map_err(|e| ("episode.t_end", e.to_string()))?;
        for (key, v, range) in [
            ("episode.perturbation", &self.perturbation, TORQUE),
            ("episode.initial_torque", &self.initial_torque, TORQUE),
        ] {
            match v {
                Some(PerJoint::All(x)) => within(key, Some(*x), range)?,
                Some(PerJoint::Each(v)) => in_range(v, range).map_err(|m| (key, m))?,
                None => {}
            }
        }
        for (key, v, range) in [
            ("episode.initial_theta", &self.initial_theta, JOINT_ANGLE),
            (
                "episode.initial_theta_dot",
                &self.initial_theta_dot,
                JOINT_RATE,
            ),
        ] {
            if let Some(v) = v {
                in_range(v, range).map_err(|m| (key, m))?;
            }
        }
        Ok(())
    }
}

/// `line N (text of the line)` for a byte offset into the file.
fn syntax_place(text: &str, offset: usize) -> String {
    let Some(before) = text.get(..offset) else {
        return String::new();
    };
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    let line = text[start..].lines().next().unwrap_or("").trim();
    let number = 1 + text[..start].matches('\n').count();
    if line.is_empty() {
        format!("line {number}")
    } else {
        format!("line {number} ({})", Clip(line))
    }
}

/// A non-empty list whose every value is in `range`.
fn in_range(v: &[f64], range: crate::validate::Range) -> Result<(), String> {
    if v.is_empty() {
        return Err("is an empty list".into());
    }
    match v.iter().find(|x| !range.contains(**x)) {
        Some(&x) => Err(format!(
            "{} in {}",
            range.check(x).unwrap_err(),
            ShortList(v)
        )),
        None => Ok(()),
    }
}

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn numbers(v: &toml::Value) -> Option<Vec<f64>> {
    v.as_array()?.iter().map(number).collect()
}

fn precision_spec(v: &toml::Value) -> Result<PrecisionSpec, String> {
    let shape = "expected a number (that multiple of I) or a matrix given row by row, \
                 e.g. [[80.0, 0.0], [0.0, 80.0]]";
    if let Some(x) = number(v) {
        return Ok(PrecisionSpec::Scalar(x));
    }
    let rows: Option<Vec<Vec<f64>>> = v
        .as_array()
        .and_then(|rows| rows.iter().map(numbers).collect());
    rows.map(PrecisionSpec::Matrix)
        .ok_or_else(|| format!("{shape}; got {}", Clip(&v.to_string())))
}

fn per_joint_spec(v: &toml::Value) -> Result<PerJoint, String> {
    if let Some(x) = number(v) {
        return Ok(PerJoint::All(x));
    }
    numbers(v).map(PerJoint::Each).ok_or_else(|| {
        format!(
            "expected a number (every joint) or a list (one per joint); got {}",
            Clip(&v.to_string())
        )
    })
}

/// Finite; a matrix square, symmetric (to 1e-12 relative) and positive semi-definite, with the
/// tolerances [`TaskN::validate`] applies once the model is known.
fn check_precision(p: &PrecisionSpec) -> Result<(), String> {
    let entry = crate::validate::PRECISION_ENTRY;
    let rows = match p {
        PrecisionSpec::Scalar(s) if !(entry.contains(*s) && *s >= 0.0) => {
            return Err(format!("{} must be a number ≥ 0 in {entry}", Short(*s)))
        }
        PrecisionSpec::Scalar(_) => return Ok(()),
        PrecisionSpec::Matrix(rows) => rows,
    };
    let n = rows.len();
    if n == 0 || rows.iter().any(|r| r.len() != n) {
        let lengths: Vec<usize> = rows.iter().map(Vec::len).collect();
        return Err(format!(
            "a matrix must be square, given row by row; got rows of lengths {}",
            Clip(&format!("{lengths:?}"))
        ));
    }
    let most = toolconf_generated::MODELS
        .iter()
        .map(|m| m.dof)
        .max()
        .unwrap_or(0);
    if n > most {
        return Err(format!(
            "a {n}×{n} matrix, but no model has more than {most} joints"
        ));
    }
    let m = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
    if let Some(&x) = m.iter().find(|x| !entry.contains(**x)) {
        return Err(format!("{} in {}", entry.check(x).unwrap_err(), Rows(rows)));
    }
    let scale = m.amax().max(1.0);
    for i in 0..n {
        for j in (i + 1)..n {
            if (m[(i, j)] - m[(j, i)]).abs() > 1e-12 * scale {
                return Err(format!(
                    "{} is not symmetric: entry ({}, {}) = {} but ({}, {}) = {}",
                    Rows(rows),
                    i + 1,
                    j + 1,
                    Short(m[(i, j)]),
                    j + 1,
                    i + 1,
                    Short(m[(j, i)])
                ));
            }
        }
    }
    let smallest = m.symmetric_eigenvalues().min();
    if smallest < -1e-12 * scale {
        return Err(format!(
            "{} is not positive semi-definite (smallest eigenvalue {})",
            Rows(rows),
            Short(smallest)
        ));
    }
    Ok(())
}

/// Tasks given as data rather than as a file (the Python binding's task dicts).
impl TaskSpec {
    /// A task given as a TOML table with a task file's keys, checked exactly as a task file is;
    /// `source` names it in errors (`task dict, key precision.theta: …`). A value of the wrong
    /// type or an unknown key is named by its dotted key, as a file's would be by its line.
    pub fn from_table(table: toml::Table, source: &str) -> Result<Self, TaskFileError> {
        let raw: RawTask = table.try_into().map_err(|e| {
            // toml names the value's place as a last line "in `goal.theta`" (no text, no span).
            let text = e.to_string();
            let (message, place) = match text.trim_end().rsplit_once("\nin `") {
                Some((message, key)) => (message, format!("key {}", key.trim_end_matches('`'))),
                None => (text.trim_end(), String::new()),
            };
            TaskFileError {
                file: source.into(),
                place: Clip(&place).to_string(),
                message: ClipMessage(&message.trim().replace('\n', " ")).to_string(),
            }
        })?;
        Self::from_raw(raw, source)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Arm2, Arm3};

    const FORMAT_EXAMPLE: &str = r#"
kind = "position"
[goal]
theta = [0.7853981633974483, 0.0]
[precision]
theta = 80.0
theta_dot = 50.0
theta_ddot = 1.0
u = 1.0
[episode]
t_end = 5.0
dt = 0.05
perturbation = 0.0
"#;

    #[test]
    fn the_format_example_parses_into_the_task_it_states() {
        let spec = TaskSpec::parse(FORMAT_EXAMPLE, "t.toml").unwrap();
        let task = spec.task::<Arm2, 2, 4, 4, 6>().unwrap();
        assert_eq!(
            *task.goal(Term::Theta),
            crate::Vector2::new(std::f64::consts::FRAC_PI_4, 0.0)
        );
        assert_eq!(
            *task.precision(Term::Theta),
            crate::Matrix2::identity() * 80.0
        );
        assert_eq!(
            *task.precision(Term::ThetaDot),
            crate::Matrix2::identity() * 50.0
        );
        let o = spec.episode::<Arm2, 2, 4, 4, 6>().unwrap();
        assert_eq!((o.t_end, o.dt, o.perturbation), (5.0, 0.05, 0.0));
        assert_eq!(o.x0, Arm2::equilibrium_state());
    }

    #[test]
    fn a_two_joint_goal_does_not_fit_three_joints() {
        let spec = TaskSpec::parse(FORMAT_EXAMPLE, "t.toml").unwrap();
        let e = spec.task::<Arm3, 3, 6, 6, 9>().unwrap_err();
        assert_eq!(e.place, "key goal.theta");
        assert!(e.message.contains("model arm3 has 3 joints"), "{e}");
    }

    #[test]
    fn syntax_errors_name_the_line_and_its_text() {
        let e =
            TaskSpec::parse("kind = \"position\"\n[goal]\ntheta = 0.5\n", "t.toml").unwrap_err();
        assert_eq!(e.place, "line 3 (theta = 0.5)");
        let e = TaskSpec::parse(
            "kind = \"velocity\"\n[episode]\nperturbation = [0.1, nan]\n",
            "t.toml",
        )
        .unwrap_err();
        assert_eq!(e.place, "key episode.perturbation");
        assert!(e.message.contains("NaN"), "{e}");
    }

    #[test]
    fn a_table_is_checked_as_a_file_is_and_errors_name_the_key() {
        let table: toml::Table = toml::from_str(FORMAT_EXAMPLE).unwrap();
        let from_table = TaskSpec::from_table(table, "task dict").unwrap();
        let from_text = TaskSpec::parse(FORMAT_EXAMPLE, "task dict").unwrap();
        assert_eq!(from_table, from_text);
        let table: toml::Table =
            toml::from_str("kind = \"position\"\n[goal]\ntheta = 0.5\n").unwrap();
        let e = TaskSpec::from_table(table, "task dict").unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.place.as_str()),
            ("task dict", "key goal.theta")
        );
        assert!(e.message.contains("expected a sequence"), "{e}");
        let table: toml::Table =
            toml::from_str("kind = \"velocity\"\n[episode]\nt_ned = 3.0\n").unwrap();
        let e = TaskSpec::from_table(table, "task dict").unwrap_err();
        assert_eq!(e.place, "key episode");
        assert!(e.message.contains("unknown field `t_ned`"), "{e}");
        let table: toml::Table =
            toml::from_str("kind = \"velocity\"\n[precision]\nu = [[1.0, 2.0], [0.0, 1.0]]\n")
                .unwrap();
        let e = TaskSpec::from_table(table, "task dict").unwrap_err();
        assert_eq!(e.place, "key precision.u");
        assert!(e.message.contains("is not symmetric"), "{e}");
    }

    /// An unknown term is refused at its own line, as serde's derived structs refuse a key.
    #[test]
    fn an_unknown_term_names_its_line_and_the_terms() {
        let text = "kind = \"velocity\"\n[goal]\ntheta_dott = [1.0, 2.0]\n";
        let e = TaskSpec::parse(text, "t.toml").unwrap_err().to_string();
        assert!(e.contains("line 3 (theta_dott = [1.0, 2.0])"), "{e}");
        assert!(
            e.contains(
                "unknown field `theta_dott`, expected one of `theta`, `theta_dot`, `theta_ddot`"
            ),
            "{e}"
        );
        let text = "kind = \"velocity\"\n[precision]\ntheta_dott = 1.0\n";
        let e = TaskSpec::parse(text, "t.toml").unwrap_err().to_string();
        assert!(
            e.contains("line 3") && e.contains("`theta_ddot`, `u`"),
            "{e}"
        );
        let table: toml::Table = toml::from_str(text).unwrap();
        let e = TaskSpec::from_table(table, "task dict").unwrap_err();
        assert_eq!(e.place, "key precision");
        assert!(e.message.contains("unknown field `theta_dott`"), "{e}");
    }

    #[test]
    fn per_joint_values_are_uniform_only_when_equal() {
        assert_eq!(PerJoint::Each(vec![0.2, 0.2]).uniform(), Some(0.2));
        assert_eq!(PerJoint::Each(vec![0.2, 0.1]).uniform(), None);
        assert_eq!(PerJoint::All(-0.8).uniform(), Some(-0.8));
    }
}
