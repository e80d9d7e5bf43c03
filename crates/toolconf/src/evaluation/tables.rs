//! The evaluation as tables, one per file of the paper's reproduction (`fig2_*.csv` …): what
//! `toolconf reproduce --model` writes and `toolconf.reproduce` returns as DataFrames.

use toolconf_files::csv::Cell;

use super::records::{Run, ToolRecord};
use super::trials::{Trial, MEASURES, RULES};
use super::Evaluation;
use toolconf_model::registry::AXES;

/// A table: its file's name (without `.csv`), header and rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub name: &'static str,
    pub header: Vec<String>,
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    fn new(name: &'static str, header: Vec<String>) -> Self {
        Self {
            name,
            header,
            rows: Vec::new(),
        }
    }
}

/// Every table, in the files' order.
pub fn tables(e: &Evaluation) -> Vec<Table> {
    vec![
        fig2(e),
        fig3_tools(e),
        fig3_trajectories(e),
        fig4(e),
        fig5(e),
        trial_table(e, "fig6_selection_grid", &e.grid, false),
        trial_table(e, "fig7_benchmark", &e.trials, true),
        fig7_choices(e),
    ]
}

fn header(lead: &[&str], e: &Evaluation, tail: &[&str]) -> Vec<String> {
    lead.iter()
        .copied()
        .chain(e.setup.model.parameter_names().iter().copied())
        .chain(tail.iter().copied())
        .map(String::from)
        .collect()
}

/// A table of rows about tools: each row the tool's index, row, name and parameters
/// ([`tool_cells`]), then its cells under the columns `tail`; `rows` gives each row's tool and
/// cells.
fn tools_table(
    e: &Evaluation,
    name: &'static str,
    tail: &[&str],
    rows: impl Iterator<Item = (usize, Vec<Cell>)>,
) -> Table {
    let mut t = Table::new(name, header(&["tool", "row", "name"], e, tail));
    for (tool, cells) in rows {
        let mut row = tool_cells(e, tool);
        row.extend(cells);
        t.rows.push(row);
    }
    t
}

/// Tool i's lead cells: its index, row and name, then its parameters.
fn tool_cells(e: &Evaluation, i: usize) -> Vec<Cell> {
    let p = &e.population;
    let mut cells = vec![
        Cell::from(i),
        Cell::from(p.rows[i]),
        p.names[i].clone().map_or(Cell::Empty, Cell::from),
    ];
    cells.extend(p.tools[i].parameters().iter().map(|v| Cell::from(*v)));
    cells
}

fn run_cells(run: &Run) -> [Cell; 5] {
    match run {
        Ok(n) => [
            Cell::from(n.task_error),
            Cell::from(n.free_energy),
            Cell::from(n.cost_j),
            Cell::from(n.progress),
            Cell::Int(n.rhs_evals as i64),
        ],
        Err(_) => [
            Cell::Empty,
            Cell::Empty,
            Cell::Empty,
            Cell::Empty,
            Cell::Empty,
        ],
    }
}

fn fig2(e: &Evaluation) -> Table {
    let tail = [
        "logdet",
        "task_error",
        "free_energy",
        "cost_j",
        "progress",
        "rhs_evals",
        "error",
    ];
    let rows = e.records.iter().map(|r| {
        let mut cells = vec![Cell::from(r.logdet())];
        cells.extend(run_cells(&r.base));
        cells.push(Cell::from(r.error_of_base()));
        (r.index, cells)
    });
    tools_table(e, "fig2_confidence_vs_error", &tail, rows)
}

fn fig3_tools(e: &Evaluation) -> Table {
    let rows = e.records[..e.highlight.sample].iter().map(|r| {
        let role = e
            .highlight
            .runs
            .iter()
            .find(|h| h.tool == r.index)
            .map_or("", |h| h.role);
        (r.index, vec![Cell::from(r.logdet()), Cell::from(role)])
    });
    tools_table(e, "fig3_tools", &["logdet", "role"], rows)
}

/// The four runs on the output grid: the task variable's components, its distance to the goal,
/// and on a tip task the tip's path.
fn fig3_trajectories(e: &Evaluation) -> Table {
    let components = e.task_components();
    let tip = e.reads_tip();
    let mut head: Vec<String> = ["role", "tool", "logdet", "perturbed", "t"]
        .map(String::from)
        .to_vec();
    head.extend(components.iter().cloned());
    head.push("distance_to_goal".into());
    if tip {
        head.extend(AXES.iter().map(|a| format!("tip_{a}")));
    }
    head.push("error".into());
    let mut t = Table::new("fig3_trajectories", head);
    for run in &e.highlight.runs {
        let lead = [
            Cell::from(run.role),
            Cell::from(run.tool),
            Cell::from(run.logdet),
            Cell::from(run.perturbed),
        ];
        let (Ok(tr), Some(distance)) = (&run.trace, run.distance()) else {
            let mut row = lead.to_vec();
            row.extend((0..t.header.len() - 5).map(|_| Cell::Empty));
            row.push(Cell::from(
                run.trace.as_ref().err().cloned().unwrap_or_default(),
            ));
            t.rows.push(row);
            continue;
        };
        for i in 0..tr.t.len() {
            let mut row = lead.to_vec();
            row.push(Cell::from(tr.t[i]));
            row.extend((0..components.len()).map(|j| Cell::from(tr.value.get(j).map(|v| v[i]))));
            row.push(Cell::from(distance[i].1));
            if tip {
                let path = tr.tip_path.as_ref();
                row.extend((0..3).map(|j| Cell::from(path.and_then(|p| p.get(j)).map(|v| v[i]))));
            }
            row.push(Cell::Empty);
            t.rows.push(row);
        }
    }
    t
}

fn fig4(e: &Evaluation) -> Table {
    let tail = [
        "logdet",
        "task_error",
        "task_error_perturbed",
        "abs_change",
        "error",
    ];
    let rows = e.records.iter().map(|r| {
        let cells = vec![
            Cell::from(r.logdet()),
            Cell::from(r.task_error()),
            Cell::from(r.perturbed_error()),
            Cell::from(r.abs_change()),
            Cell::from(r.error()),
        ];
        (r.index, cells)
    });
    tools_table(e, "fig4_perturbation_change", &tail, rows)
}

fn fig5(e: &Evaluation) -> Table {
    let tail = [
        "logdet",
        "scale",
        "task_error",
        "task_error_unperturbed",
        "abs_change",
        "error",
    ];
    let swept = e.records.iter().filter(|r| !r.sweep.is_empty());
    let rows = swept.flat_map(|r| {
        r.sweep.iter().enumerate().map(move |(k, run)| {
            let cells = vec![
                Cell::from(r.logdet()),
                Cell::from(e.setup.scales[k]),
                Cell::from(run.as_ref().ok().map(|n| n.task_error)),
                Cell::from(r.task_error()),
                Cell::from(r.sweep_change(k)),
                Cell::from(run.as_ref().err().cloned().unwrap_or_default()),
            ];
            (r.index, cells)
        })
    });
    tools_table(e, "fig5_perturbation_sweep", &tail, rows)
}

/// A selection experiment: one row per trial and tool, with a 0/1 column per rule.
fn trial_table(e: &Evaluation, name: &'static str, trials: &[Trial], perturbed: bool) -> Table {
    let mut tail = vec!["logdet", "task_error", "free_energy", "cost_j"];
    if perturbed {
        tail.extend(["task_error_perturbed", "abs_change"]);
    }
    let chosen: Vec<String> = RULES
        .iter()
        .map(|r| format!("chosen_by_{}", r.name()))
        .collect();
    let mut head = header(&["trial", "position", "tool"], e, &tail);
    head.extend(chosen);
    head.push("error".into());
    let mut t = Table::new(name, head);
    for (k, trial) in trials.iter().enumerate() {
        for (pos, &i) in trial.tools.iter().enumerate() {
            let r = &e.records[i];
            let mut row = vec![Cell::from(k), Cell::from(pos), Cell::from(i)];
            row.extend(
                e.population.tools[i]
                    .parameters()
                    .iter()
                    .map(|v| Cell::from(*v)),
            );
            row.push(Cell::from(r.logdet()));
            row.extend(run_cells(&r.base).into_iter().take(3));
            if perturbed {
                row.extend([Cell::from(r.perturbed_error()), Cell::from(r.abs_change())]);
            }
            row.extend(trial.chosen.iter().map(|c| Cell::from(*c == Some(pos))));
            row.push(Cell::from(if perturbed {
                r.error()
            } else {
                r.error_of_base()
            }));
            t.rows.push(row);
        }
    }
    t
}

/// The columns of a benchmark's choices: one row per trial and rule, the chosen tool and its
/// confidence, task error and |Δ task error| (the paper's reproduction writes the same file).
pub const CHOICES_HEADER: [&str; 6] = [
    "trial",
    "rule",
    "tool",
    "logdet",
    "task_error",
    "abs_change",
];

fn fig7_choices(e: &Evaluation) -> Table {
    let mut t = Table::new("fig7_choices", CHOICES_HEADER.map(String::from).to_vec());
    for (k, trial) in e.trials.iter().enumerate() {
        for (r, rule) in RULES.iter().enumerate() {
            let tool = trial.chosen_tool(r);
            let at = |m: usize| tool.and_then(|i| super::trials::measure(&e.records, m, i));
            t.rows.push(vec![
                Cell::from(k),
                Cell::from(rule.name()),
                tool.map_or(Cell::Empty, Cell::from),
                Cell::from(at(0)),
                Cell::from(at(1)),
                Cell::from(at(2)),
            ]);
        }
    }
    debug_assert_eq!(MEASURES.len(), 3);
    t
}

impl ToolRecord {
    /// The first reason the confidence or the unperturbed episode failed ("" if neither did).
    pub fn error_of_base(&self) -> String {
        match (&self.logdet, &self.base) {
            (Err(e), _) | (_, Err(e)) => e.clone(),
            _ => String::new(),
        }
    }
}
