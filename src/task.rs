//! The paper's three tasks with their goals and precisions ("Implementation details").

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::generated::arm2;
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
    /// `derive/tasks.toml` and the model's goals).
    pub fn paper(kind: TaskKind) -> Self {
        let eye = Matrix2::identity();
        let zero = Vector2::zeros();
        match kind {
            TaskKind::Position => {
                use arm2::position as p;
                Task {
                    kind,
                    goal_theta: Vector2::from(p::GOAL_THETA),
                    goal_theta_dot: Vector2::from(p::GOAL_THETA_DOT),
                    goal_theta_ddot: Vector2::from(p::GOAL_THETA_DDOT),
                    precision_theta: eye * p::PRECISION_THETA,
                    precision_theta_dot: eye * p::PRECISION_THETA_DOT,
                    precision_theta_ddot: eye * p::PRECISION_THETA_DDOT,
                    precision_u: eye * p::PRECISION_U,
                }
            }
            TaskKind::Velocity => {
                use arm2::velocity as p;
                Task {
                    kind,
                    goal_theta: zero,
                    goal_theta_dot: Vector2::from(p::GOAL_THETA_DOT),
                    goal_theta_ddot: Vector2::from(p::GOAL_THETA_DDOT),
                    precision_theta: Matrix2::zeros(),
                    precision_theta_dot: eye * p::PRECISION_THETA_DOT,
                    precision_theta_ddot: eye * p::PRECISION_THETA_DDOT,
                    precision_u: eye * p::PRECISION_U,
                }
            }
            TaskKind::Acceleration => {
                use arm2::acceleration as p;
                Task {
                    kind,
                    goal_theta: zero,
                    goal_theta_dot: zero,
                    goal_theta_ddot: Vector2::from(p::GOAL_THETA_DDOT),
                    precision_theta: Matrix2::zeros(),
                    precision_theta_dot: Matrix2::zeros(),
                    precision_theta_ddot: eye * p::PRECISION_THETA_DDOT,
                    precision_u: eye * p::PRECISION_U,
                }
            }
        }
    }

    /// Checks goals are finite and precisions finite, symmetric and positive semi-definite.
    pub fn validate(&self) -> Result<(), Error> {
        for (name, goal) in [
            ("theta_g", &self.goal_theta),
            ("theta_dot_g", &self.goal_theta_dot),
            ("theta_ddot_g", &self.goal_theta_ddot),
        ] {
            if let Some(&value) = goal.iter().find(|v| !v.is_finite()) {
                return Err(Error::InvalidGoal {
                    name: name.into(),
                    value,
                });
            }
        }
        for (name, p) in [
            ("P_theta", &self.precision_theta),
            ("P_theta_dot", &self.precision_theta_dot),
            ("P_theta_ddot", &self.precision_theta_ddot),
            ("P_u", &self.precision_u),
        ] {
            check_precision(name, p)?;
        }
        Ok(())
    }
}

fn check_precision(name: &str, p: &Matrix2) -> Result<(), Error> {
    let invalid = |reason: String| Error::InvalidPrecision {
        name: name.into(),
        reason,
    };
    if p.iter().any(|v| !v.is_finite()) {
        return Err(invalid(format!(
            "has a non-finite entry: {:?}",
            p.as_slice()
        )));
    }
    if (p[(0, 1)] - p[(1, 0)]).abs() > 1e-12 * p.amax().max(1.0) {
        return Err(invalid(format!(
            "is not symmetric ({} vs {})",
            p[(0, 1)],
            p[(1, 0)]
        )));
    }
    // Positive semi-definite 2×2: non-negative diagonal and determinant.
    let det = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)];
    if p[(0, 0)] < 0.0 || p[(1, 1)] < 0.0 || det < -1e-12 * p.amax().powi(2) {
        return Err(invalid("is not positive semi-definite".into()));
    }
    Ok(())
}
