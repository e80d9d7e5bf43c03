//! The paper's three tasks with their goals and precisions ("Implementation details").

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::{Error, Matrix2, Vector2};

/// Which task-specific controller (appendix "Task specific controllers").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TaskKind {
    /// Task 1: reach a goal configuration θ^g.
    Position,
    /// Task 2: hold a goal joint velocity θ̇^g.
    Velocity,
    /// Task 3: hold a goal joint acceleration θ̈^g.
    Acceleration,
}

impl TaskKind {
    pub const ALL: [TaskKind; 3] = [
        TaskKind::Position,
        TaskKind::Velocity,
        TaskKind::Acceleration,
    ];

    /// The task's number in the paper (1, 2, 3).
    pub fn paper_index(self) -> u8 {
        match self {
            TaskKind::Position => 1,
            TaskKind::Velocity => 2,
            TaskKind::Acceleration => 3,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            TaskKind::Position => "position",
            TaskKind::Velocity => "velocity",
            TaskKind::Acceleration => "acceleration",
        }
    }
}

impl fmt::Display for TaskKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for TaskKind {
    type Err = Error;

    /// Accepts the name (`position`, `velocity`, `acceleration`) or the paper's number.
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.trim().to_ascii_lowercase().as_str() {
            "position" | "1" => Ok(TaskKind::Position),
            "velocity" | "2" => Ok(TaskKind::Velocity),
            "acceleration" | "3" => Ok(TaskKind::Acceleration),
            _ => Err(Error::UnknownTask(s.to_string())),
        }
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
