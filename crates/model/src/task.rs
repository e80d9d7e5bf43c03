//! The paper's three tasks with their goals and precisions ("Implementation details").

use crate::model::TaskN;
use crate::Error;

/// Which task-specific controller: generated from `derive/tasks.toml` (a task added there appears
/// after `make derive`), with its name, number, terms and error term.
pub use toolconf_generated::{TaskKind, Term};

/// A task of the paper's 2-DOF arm: goals θ^g, θ̇^g, θ̈^g and prior precisions P^θ, P^θ̇, P^θ̈,
/// P^U (eq. free_energy); `Task::paper(kind)` is the paper's.
pub type Task = TaskN<2>;

/// The task names and numbers a command line accepts, for messages and `--help`:
/// "position, velocity or acceleration (or 1, 2, 3)".
pub fn task_choices() -> String {
    toolconf_generated::TASK_CHOICES.to_string()
}

/// A task by its name (`position`, ...) or number (`1`, ...), or [`Error::UnknownTask`] naming
/// the text.
pub fn parse_task(text: &str) -> Result<TaskKind, Error> {
    text.parse()
        .map_err(|_| Error::UnknownTask(text.to_string()))
}
