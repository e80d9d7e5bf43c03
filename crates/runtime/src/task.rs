//! The paper's three tasks with their goals and precisions ("Implementation details").

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::model::TaskN;
use crate::{Error, Matrix2, Vector2};

/// Which task-specific controller: generated from `derive/tasks.toml` (a task added there appears
/// after `make derive`), with its name, number, terms and error term.
pub use crate::generated::{TaskKind, Term};

impl fmt::Display for TaskKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for TaskKind {
    type Err = Error;

    /// Accepts a task's name (`position`, `velocity`, ...) or its number (`1`, `2`, ...).
    fn from_str(s: &str) -> Result<Self, Error> {
        let key = s.trim().to_ascii_lowercase();
        TaskKind::ALL
            .into_iter()
            .find(|k| k.name() == key || k.paper_index().to_string() == key)
            .ok_or_else(|| Error::UnknownTask(s.to_string()))
    }
}

/// The task names and numbers a command line accepts, for messages and `--help`:
/// "position, velocity or acceleration (or 1, 2, 3)".
pub fn task_choices() -> String {
    let names: Vec<&str> = TaskKind::ALL.iter().map(|k| k.name()).collect();
    let numbers: Vec<String> = TaskKind::ALL
        .iter()
        .map(|k| k.paper_index().to_string())
        .collect();
    let names = match names.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    format!("{names} (or {})", numbers.join(", "))
}

impl Serialize for TaskKind {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl TaskKind {
    /// Whether the task's controller uses `term` (the others have precision zero).
    #[must_use]
    pub fn uses(self, term: Term) -> bool {
        self.terms().contains(&term)
    }
}

/// A task: goals θ^g, θ̇^g, θ̈^g and prior precisions P^θ, P^θ̇, P^θ̈, P^U (eq. free_energy).
///
/// A term the task's controller does not use has precision zero: task 2 ignores θ, task 3
/// ignores θ and θ̇ (the controller and Π^U use only the task's own terms).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Task {
    pub kind: TaskKind,
    pub goal_theta: Vector2,
    pub goal_theta_dot: Vector2,
    pub goal_theta_ddot: Vector2,
    pub precision_theta: Matrix2,
    pub precision_theta_dot: Matrix2,
    pub precision_theta_ddot: Matrix2,
    pub precision_u: Matrix2,
}

impl Task {
    /// The paper's task with its published goals and precisions (generated from
    /// `derive/tasks.toml` and the model's goals): the 2-link model's [`crate::model::TaskN`].
    pub fn paper(kind: TaskKind) -> Self {
        (&crate::model::TaskN::paper::<crate::model::Arm2, 4, 4, 6>(kind)).into()
    }

    /// Checks goals are finite and precisions finite, symmetric and positive semi-definite
    /// (the checks of [`crate::model::TaskN::validate`]).
    pub fn validate(&self) -> Result<(), Error> {
        crate::model::TaskN::from(self).validate()
    }

    /// The task checked once, for ranking many tools by confidence
    /// ([`crate::model::ValidatedTaskN::control_confidence`], with `Arm2Tool::from(&arm)`).
    pub fn validated(&self) -> Result<crate::model::ValidatedTaskN<2>, Error> {
        crate::model::TaskN::from(self).validated()
    }
}

impl From<&Task> for TaskN<2> {
    fn from(t: &Task) -> Self {
        Self {
            kind: t.kind,
            goal_theta: t.goal_theta,
            goal_theta_dot: t.goal_theta_dot,
            goal_theta_ddot: t.goal_theta_ddot,
            precision_theta: t.precision_theta,
            precision_theta_dot: t.precision_theta_dot,
            precision_theta_ddot: t.precision_theta_ddot,
            precision_u: t.precision_u,
        }
    }
}

impl From<&TaskN<2>> for Task {
    fn from(t: &TaskN<2>) -> Self {
        Self {
            kind: t.kind,
            goal_theta: t.goal_theta,
            goal_theta_dot: t.goal_theta_dot,
            goal_theta_ddot: t.goal_theta_ddot,
            precision_theta: t.precision_theta,
            precision_theta_dot: t.precision_theta_dot,
            precision_theta_ddot: t.precision_theta_ddot,
            precision_u: t.precision_u,
        }
    }
}
