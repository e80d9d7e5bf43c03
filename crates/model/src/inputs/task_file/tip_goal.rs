//! Tip goals relative to each tool's own tip where the episode starts.
//!
//! An absolute tip goal is a point (or a velocity, an acceleration) in the base frame; every tool
//! rests somewhere else, so on a tip position task the task error and ∫F mostly rank tools by
//! where their tip starts. A relative goal makes every tool make the same motion:
//!
//! ```toml
//! kind = "tip_position"
//! [goal]
//! tip_offset = [0.05, 0.03, -0.04]     # m from the tool's own tip at the episode's start
//! ```
//!
//! ```toml
//! kind = "tip_velocity"                # or tip_acceleration, with tip_acceleration = … m/s²
//! [goal]
//! tip_direction = [1.0, 0.0, 0.0]      # base frame; normalised
//! tip_speed = 0.03                     # m/s along it
//! ```
//!
//! The offset is resolved per tool: the goal is y(q0; p) + offset, y the tool's tip at the
//! episode's initial joint angles q0 (the model's rest pose q^e unless `[episode] initial_theta`
//! says otherwise), so every tool's initial distance to its goal is |offset|. A direction and a
//! speed (or an acceleration) are the same goal ẏ^g = speed·d/|d| for every tool, whose tip
//! starts at rest: they are resolved when the file is read, and the goal is reported as
//! relative.

use nalgebra::SVector;

use super::TaskFileError;
use crate::model::{ArmModel, TaskN, ToolN};
use crate::validate::goal_range;
use crate::{Error, TaskKind, Term};
use toolconf_messages::ShortList;

/// How a task gives its tip goal.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum TipGoal {
    /// In the base frame as written (`tip`, `tip_dot`, `tip_ddot`), or no tip goal at all.
    #[default]
    Absolute,
    /// `tip_offset`: m from each tool's own tip where the episode starts.
    Offset(Vec<f64>),
    /// `tip_direction` with `tip_speed` (m/s) or `tip_acceleration` (m/s²) along it; already
    /// written into the task's `tip_dot` or `tip_ddot` goal.
    Motion { direction: Vec<f64>, magnitude: f64 },
}

impl TipGoal {
    pub fn is_relative(&self) -> bool {
        !matches!(self, TipGoal::Absolute)
    }

    /// "absolute" or "relative": the `goal` key of JSON output.
    pub fn kind_name(&self) -> &'static str {
        if self.is_relative() {
            "relative"
        } else {
            "absolute"
        }
    }

    /// How reports describe it.
    pub fn describe(&self) -> String {
        match self {
            TipGoal::Absolute => {
                "absolute (in the base frame, the same point for every tool)".into()
            }
            TipGoal::Offset(v) => format!(
                "relative: an offset of {} m from each tool's own tip where the episode starts",
                ShortList(v)
            ),
            TipGoal::Motion {
                direction,
                magnitude,
            } => format!(
                "relative: {} along {} (base frame) from each tool's own tip, at rest where the \
                 episode starts",
                toolconf_messages::Short(*magnitude),
                ShortList(direction)
            ),
        }
    }
}

/// The relative keys of `[goal]`, as read.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct RelativeKeys {
    pub offset: Option<Vec<f64>>,
    pub direction: Option<Vec<f64>>,
    pub speed: Option<f64>,
    pub acceleration: Option<f64>,
}

/// The keys [`RelativeKeys`] reads, after the terms' goal keys.
pub(super) const RELATIVE_KEYS: [&str; 4] = [
    "tip_offset",
    "tip_direction",
    "tip_speed",
    "tip_acceleration",
];

/// Each relative key given is one the task's kind takes. Errors are (key, message).
fn check_kinds(kind: TaskKind, keys: &RelativeKeys) -> Result<(), (String, String)> {
    use TaskKind::{TipAcceleration, TipPosition, TipVelocity};
    let given: [(&str, bool, &[TaskKind]); 4] = [
        ("tip_offset", keys.offset.is_some(), &[TipPosition]),
        (
            "tip_direction",
            keys.direction.is_some(),
            &[TipVelocity, TipAcceleration],
        ),
        ("tip_speed", keys.speed.is_some(), &[TipVelocity]),
        (
            "tip_acceleration",
            keys.acceleration.is_some(),
            &[TipAcceleration],
        ),
    ];
    for (key, present, takes) in given {
        if present && !takes.contains(&kind) {
            let takes: Vec<&str> = takes.iter().map(|k| k.name()).collect();
            return Err((
                format!("goal.{key}"),
                format!(
                    "a {kind} task has no such goal: {key} gives a {} task's goal relative to \
                     each tool's own tip",
                    takes.join(" or ")
                ),
            ));
        }
    }
    Ok(())
}

/// Checks the relative keys against the task's kind and writes a direction's goal into `goal`;
/// returns how the tip goal is given. Errors are (key, message).
pub(super) fn resolve(
    kind: TaskKind,
    keys: RelativeKeys,
    goal: &mut [Option<Vec<f64>>],
) -> Result<TipGoal, (String, String)> {
    check_kinds(kind, &keys)?;
    let both = |relative: &str, absolute: Term| {
        (
            format!("goal.{relative}"),
            format!(
                "give the goal as {absolute} (absolute, in the base frame) or as {relative} \
                 (relative to each tool's own tip), not both"
            ),
        )
    };
    if let Some(offset) = keys.offset {
        if goal[Term::Tip.index()].is_some() {
            return Err(both("tip_offset", Term::Tip));
        }
        let range = goal_range(Term::Tip).expect("the tip's goal has a range");
        super::in_range(&offset, range).map_err(|m| ("goal.tip_offset".into(), m))?;
        return Ok(TipGoal::Offset(offset));
    }
    motion(kind, keys, goal, both)
}

/// A direction with a speed (tip_velocity) or an acceleration (tip_acceleration).
fn motion(
    kind: TaskKind,
    keys: RelativeKeys,
    goal: &mut [Option<Vec<f64>>],
    both: impl Fn(&str, Term) -> (String, String),
) -> Result<TipGoal, (String, String)> {
    let (magnitude_key, magnitude, term) = match (keys.speed, keys.acceleration) {
        (None, None) => match keys.direction {
            None => return Ok(TipGoal::Absolute),
            Some(_) => {
                let key = if kind == TaskKind::TipAcceleration {
                    "tip_acceleration (m/s²)"
                } else {
                    "tip_speed (m/s)"
                };
                return Err((
                    "goal.tip_direction".into(),
                    format!("needs goal.{key} along it"),
                ));
            }
        },
        (Some(s), _) => ("tip_speed", s, Term::TipDot),
        (None, Some(a)) => ("tip_acceleration", a, Term::TipDdot),
    };
    let Some(direction) = keys.direction else {
        return Err((
            format!("goal.{magnitude_key}"),
            "needs goal.tip_direction, the direction in the base frame it is along".into(),
        ));
    };
    if goal[term.index()].is_some() {
        return Err(both("tip_direction", term));
    }
    let norm = direction.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err((
            "goal.tip_direction".into(),
            format!(
                "{} is not a direction (its length is 0 or not finite)",
                ShortList(&direction)
            ),
        ));
    }
    let value: Vec<f64> = direction.iter().map(|d| magnitude * d / norm).collect();
    let range = goal_range(term).expect("the tip's goals have ranges");
    super::in_range(&value, range).map_err(|m| (format!("goal.{magnitude_key}"), m))?;
    goal[term.index()] = Some(value);
    Ok(TipGoal::Motion {
        direction,
        magnitude,
    })
}

/// The tip goal of `tool` for an offset goal: its tip at the initial joint angles `q0` plus
/// `offset` (padded as [`TaskN`]'s tip rows are), checked against the tip's goal range.
pub fn at_initial_tip<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task: &TaskN<N>,
    offset: &SVector<f64, N>,
    tool: &ToolN<M, N, NX, NP, NZ>,
    q0: &SVector<f64, N>,
) -> Result<TaskN<N>, Error>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let Some((tip, _)) = tool.tip(q0) else {
        return Err(Error::Unsupported(format!(
            "model {} has no tip, so a goal relative to the tool's tip cannot be given",
            M::name()
        )));
    };
    let d = M::tip_dim();
    let goal = SVector::<f64, N>::from_fn(|i, _| if i < d { tip[i] + offset[i] } else { 0.0 });
    let range = goal_range(Term::Tip).expect("the tip's goal has a range");
    if let Some(&v) = goal.iter().take(d).find(|v| !range.contains(**v)) {
        return Err(Error::Unsupported(format!(
            "the tool's tip at the start plus goal.tip_offset is {} m, outside the tip's goal \
             range: {}",
            ShortList(&goal.as_slice()[..d]),
            range.check(v).unwrap_err()
        )));
    }
    let mut task = *task;
    task.goal[Term::Tip.index()] = goal;
    Ok(task)
}

/// The error of a command that takes absolute goals only, given an offset goal.
pub(super) fn needs_absolute(file: &str) -> TaskFileError {
    TaskFileError {
        file: file.into(),
        place: "key goal.tip_offset".into(),
        message: "a goal relative to each tool's own tip needs the tool: this command takes an \
                  absolute goal (tip); rank, select --models, simulate --model and reproduce \
                  take relative ones"
            .into(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::TaskSpec;
    use super::*;
    use crate::model::{Arm2, Panda};

    fn refused(text: &str) -> (String, String) {
        let e = TaskSpec::parse(text, "t.toml").unwrap_err();
        (e.place, e.message)
    }

    #[test]
    fn an_offset_is_resolved_at_each_tools_own_tip() {
        let text = "kind = \"tip_position\"\n[goal]\ntip_offset = [0.05, 0.03, -0.04]\n";
        let spec = TaskSpec::parse(text, "t.toml").unwrap();
        assert_eq!(spec.tip_goal, TipGoal::Offset(vec![0.05, 0.03, -0.04]));
        assert_eq!(spec.tip_goal.kind_name(), "relative");
        let e = spec.task::<Panda, 7, 14, 13, 21>().unwrap_err();
        assert_eq!(e.place, "key goal.tip_offset");
        let (task, offset) = spec.task_and_offset::<Panda, 7, 14, 13, 21>().unwrap();
        let offset = offset.unwrap();
        let q0 = Panda::equilibrium_state().fixed_rows::<7>(0).into_owned();
        for tip_z in [0.05, 0.3] {
            let mut p = [0.0; 13];
            p[..7].copy_from_slice(&[0.7, 0.0, 0.0, 0.05, 3e-3, 3e-3, 1e-3]);
            p[12] = tip_z;
            let tool = ToolN::<Panda, 7, 14, 13, 21>::new(p).unwrap();
            let own = at_initial_tip(&task, &offset, &tool, &q0).unwrap();
            let (rest, _) = tool.tip(&q0).unwrap();
            let goal = own.goal(Term::Tip);
            for i in 0..3 {
                assert_eq!(goal[i], rest[i] + offset[i]);
            }
        }
    }

    #[test]
    fn a_direction_and_speed_are_the_same_goal_for_every_tool() {
        let text =
            "kind = \"tip_velocity\"\n[goal]\ntip_direction = [3.0, 0.0, 4.0]\ntip_speed = 0.05\n";
        let spec = TaskSpec::parse(text, "t.toml").unwrap();
        assert!(spec.tip_goal.is_relative());
        let task = spec.task::<Panda, 7, 14, 13, 21>().unwrap();
        let goal = task.goal(Term::TipDot);
        assert!((goal[0] - 0.03).abs() < 1e-17 && goal[1] == 0.0 && (goal[2] - 0.04).abs() < 1e-17);
        let text = "kind = \"tip_acceleration\"\n[goal]\ntip_direction = [0, 1, 0]\ntip_acceleration = 0.2\n";
        let task = TaskSpec::parse(text, "t.toml")
            .unwrap()
            .task::<Panda, 7, 14, 13, 21>()
            .unwrap();
        assert_eq!(task.goal(Term::TipDdot)[1], 0.2);
    }

    #[test]
    fn relative_keys_are_refused_where_they_do_not_belong() {
        let (place, message) = refused("kind = \"position\"\n[goal]\ntip_offset = [0.1, 0.0]\n");
        assert_eq!(place, "key goal.tip_offset");
        assert!(
            message.contains("a position task has no such goal"),
            "{message}"
        );
        let (place, _) = refused(
            "kind = \"tip_position\"\n[goal]\ntip = [0.1, 0, 0]\ntip_offset = [0.1, 0.0, 0]\n",
        );
        assert_eq!(place, "key goal.tip_offset");
        let (place, message) =
            refused("kind = \"tip_velocity\"\n[goal]\ntip_direction = [1, 0, 0]\n");
        assert_eq!(place, "key goal.tip_direction");
        assert!(message.contains("tip_speed"), "{message}");
        let (place, _) = refused("kind = \"tip_velocity\"\n[goal]\ntip_speed = 0.1\n");
        assert_eq!(place, "key goal.tip_speed");
        let (_, message) = refused(
            "kind = \"tip_velocity\"\n[goal]\ntip_direction = [0, 0, 0]\ntip_speed = 0.1\n",
        );
        assert!(message.contains("not a direction"), "{message}");
        let (place, _) = refused("kind = \"tip_position\"\n[goal]\ntip_speed = 0.1\n");
        assert_eq!(place, "key goal.tip_speed");
        let (place, _) = refused("kind = \"tip_position\"\n[goal]\ntip_offset = [20.0, 0, 0]\n");
        assert_eq!(place, "key goal.tip_offset");
        let (place, message) =
            refused("kind = \"tip_position\"\n[goal]\ntip_ofset = [0.1, 0, 0]\n");
        assert!(place.starts_with("line 3"), "{place}");
        assert!(message.contains("tip_offset"), "{message}");
        // An offset of the wrong length for the model's tip names the key.
        let spec = TaskSpec::parse(
            "kind = \"tip_position\"\n[goal]\ntip_offset = [0.1, 0.0, 0]\n",
            "t.toml",
        )
        .unwrap();
        let e = spec.task_and_offset::<Arm2, 2, 4, 4, 6>().unwrap_err();
        assert_eq!(e.place, "key goal.tip_offset");
    }

    /// A goal-only tip task file for the Panda gets the precisions the shipped touch task states
    /// by hand (σ = 1 mm, 5 mm/s, 10 % of the rated torques 87 and 12 N m).
    #[test]
    fn a_goal_only_tip_task_gets_the_robots_own_scales() {
        let root = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/tasks/panda_touch_point.toml"
        );
        let shipped = TaskSpec::from_file(std::path::Path::new(root)).unwrap();
        let shipped = shipped.task::<Panda, 7, 14, 13, 21>().unwrap();
        let text = "kind = \"tip_position\"\n[goal]\ntip = [0.357, 0.030, 0.390]\n";
        let bare = TaskSpec::parse(text, "t.toml")
            .unwrap()
            .task::<Panda, 7, 14, 13, 21>()
            .unwrap();
        for term in [Term::Tip, Term::TipDot, Term::U] {
            assert_eq!(bare.precision(term), shipped.precision(term), "{term}");
        }
        // A planar arm keeps the paper's precisions; so does a built-in task.
        let text = "kind = \"tip_position\"\n[goal]\ntip = [0.3, 0.1]\n";
        let arm2 = TaskSpec::parse(text, "t.toml")
            .unwrap()
            .task::<Arm2, 2, 4, 4, 6>()
            .unwrap();
        assert_eq!(
            arm2.precision(Term::U),
            Arm2::paper_task(TaskKind::TipPosition).precision(Term::U)
        );
        let builtin = TaskSpec::builtin(TaskKind::TipPosition)
            .task::<Panda, 7, 14, 13, 21>()
            .unwrap();
        assert_eq!(
            builtin.precision(Term::U),
            Panda::paper_task(TaskKind::TipPosition).precision(Term::U)
        );
    }
}
