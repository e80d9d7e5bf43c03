//! Small pieces the figure modules share: labels, tool columns, axis choices.

use toolconf::select::ToolResult;
use toolconf_model::{Arm, TaskKind};
use toolconf_stats::summary;

use super::report::Block;
use toolconf_files::csv::Cell;

/// The paper's three tasks, which its Results section runs (a task added to
/// `derive/tasks.toml` is everywhere else, but not in the paper's figures).
pub const PAPER_TASKS: [TaskKind; 3] = [
    TaskKind::Position,
    TaskKind::Velocity,
    TaskKind::Acceleration,
];

/// "task 1 (position)".
pub fn task_label(kind: TaskKind) -> String {
    format!("task {} ({})", kind.paper_index(), kind.name())
}

/// Fig. 5's mean lines: the mean of `change(tool, k)` at each `xs[k]` over all the tools, and
/// over the least and the most confident third ([`mean_lines`]).
pub struct MeanLines {
    pub all: Line,
    /// How many tools a third is, the least and the most confident third's lines; none with
    /// fewer than six tools.
    pub thirds: Option<(usize, Line, Line)>,
}

/// A line's points (x, y).
pub type Line = Vec<(f64, f64)>;

/// [`MeanLines`] of `tools`, ordered by their confidence ln|Π^U| (`logdet`; a missing one as 0).
pub fn mean_lines<T>(
    mut tools: Vec<T>,
    logdet: impl Fn(&T) -> Option<f64>,
    xs: &[f64],
    change: impl Fn(&T, usize) -> Option<f64>,
) -> MeanLines {
    tools.sort_by(|a, b| {
        logdet(a)
            .unwrap_or(0.0)
            .total_cmp(&logdet(b).unwrap_or(0.0))
    });
    let line = |group: &[T]| -> Line {
        (0..xs.len())
            .filter_map(|k| {
                let v: Vec<f64> = group.iter().filter_map(|t| change(t, k)).collect();
                Some((xs[k], summary(&v).ok()?.mean))
            })
            .collect()
    };
    let third = tools.len() / 3;
    MeanLines {
        all: line(&tools),
        thirds: (third >= 2).then(|| {
            let most = &tools[tools.len() - third..];
            (third, line(&tools[..third]), line(most))
        }),
    }
}

/// The four parameter cells m1, m2, l1, l2 of a tool.
pub fn arm_cells(arm: &Arm) -> [Cell; 4] {
    let p = arm.params();
    [p[0], p[1], p[2], p[3]].map(Cell::from)
}

pub const ARM_COLUMNS: [&str; 4] = ["m1", "m2", "l1", "l2"];

/// The columns that name a 2-link tool and its confidence in every experiment's CSV: the tool,
/// its parameters and ln|Π^U|.
pub const TOOL_COLUMNS: [&str; 6] = ["tool", "m1", "m2", "l1", "l2", "logdet"];

/// `parts` one after the other, `N` their total length (checked when compiling): a CSV header
/// from its parts.
pub const fn columns<const N: usize>(parts: &[&[&'static str]]) -> [&'static str; N] {
    let mut out = [""; N];
    let (mut i, mut k) = (0, 0);
    while i < parts.len() {
        let mut j = 0;
        while j < parts[i].len() {
            out[k] = parts[i][j];
            (j, k) = (j + 1, k + 1);
        }
        i += 1;
    }
    assert!(k == N, "the parts' lengths add up to N");
    out
}

/// The right-hand-side evaluations of those of `results`' episodes that ran.
pub fn rhs_evals<'a>(results: impl IntoIterator<Item = &'a ToolResult>) -> u64 {
    results
        .into_iter()
        .filter_map(|r| r.episode.as_ref().ok())
        .map(|m| m.rhs_evals as u64)
        .sum()
}

/// A log y axis when the positive values span more than a factor 30 (and none is ≤ 0).
pub fn wants_log(values: &[f64]) -> bool {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    lo > 0.0 && hi.is_finite() && hi / lo > 30.0
}

/// "ΔT = −0.8 N m" style label of a perturbation.
pub fn dt_label(dt: f64) -> String {
    let s = format!("{dt:+.1}");
    let s = if s == "+0.0" || s == "-0.0" {
        "0".to_string()
    } else {
        s
    };
    s.replace('-', "−")
}

/// The "data and files" paragraph of a section.
pub fn files_block(files: &[String], rows: usize, failed: usize, what: &str) -> Block {
    let names: Vec<String> = files.iter().map(|f| format!("`{f}`")).collect();
    Block::p(format!(
        "Data: {} ({rows} {what}; {failed} failed episode{} recorded with its error and left out \
         of the statistics).",
        names.join(", "),
        if failed == 1 { "" } else { "s" }
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels() {
        assert_eq!(task_label(TaskKind::Velocity), "task 2 (velocity)");
        assert_eq!(dt_label(-0.8), "−0.8");
        assert_eq!(dt_label(0.0), "0");
        assert_eq!(dt_label(0.4), "+0.4");
        assert!(wants_log(&[1.0, 100.0]));
        assert!(!wants_log(&[0.0, 100.0]));
        assert!(!wants_log(&[10.0, 100.0]));
    }
}
