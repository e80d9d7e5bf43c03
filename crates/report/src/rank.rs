//! The report of a ranking (`toolconf rank --report DIR`): `report.md` and `report.html` (the
//! same text, figures inline), written for a reader who has not read the paper, with its
//! figures: confidence against task error, the best and worst tools over time, on a tip task
//! the tip's path, and on a URDF arm their episodes in 3-D in the HTML ([`crate::view3d`]).

use std::path::{Path, PathBuf};

use crate::experiments::figure_parts::wants_log;
use crate::experiments::plot::{self, Colour, Legend, Panel, Series, XyPanel};
use crate::experiments::report::{to_html, to_markdown, Block};
use crate::experiments::{write_atomically, ReproduceError};
use crate::view3d;
use toolconf::rank::{score, ModelTasks, RankedTool, ScreenBy, StageTimings, TaskTrace};
use toolconf::select::Objective;
use toolconf_generated::Read;
use toolconf_model::inputs::task_file::{PerJoint, PrecisionSpec, TaskSpec};
use toolconf_model::registry::{ModelKind, AXES};
use toolconf_model::{TaskKind, Term};
use toolconf_stats::spearman;

/// What the report describes.
pub struct ReportInput<'a> {
    pub command: &'a str,
    pub tools_file: &'a str,
    pub spec: &'a TaskSpec,
    pub tasks: &'a ModelTasks,
    pub objective: Objective,
    /// Tools read, rows skipped as bad, and the screen's K and criterion (if any).
    pub read: usize,
    pub skipped: usize,
    pub screen: Option<(usize, ScreenBy)>,
    /// Simulated tools in file order, and their order from best to worst.
    pub results: &'a [RankedTool],
    pub order: &'a [usize],
    /// Both stages' wall times (stated under "Run time"; they vary from run to run, so the
    /// report is not compared byte for byte).
    pub timing: Option<StageTimings>,
    /// Notes the output gives too: that confidence does not predict the task error among these
    /// tools (with a screen), that the task barely moved the tools.
    pub notes: Vec<String>,
}

/// How many tools the report lists, and how many of the best and worst it plots over time.
const LISTED: usize = 50;
const TRACED: usize = 3;

/// The files [`write_report`] writes into its folder (checked against the run's other files
/// before any work: [`toolconf_files::run_files`]).
pub const REPORT_FILES: [&str; 4] = ["report.md", "report.html", CONFIDENCE_SVG, TRAJECTORY_SVG];

/// Writes the report into `dir` (created if needed); returns the files written.
pub fn write_report(dir: &Path, input: &ReportInput) -> Result<Vec<PathBuf>, ReproduceError> {
    toolconf_files::file::create_folder(dir).map_err(ReproduceError::io(dir))?;
    let mut doc = introduction(input);
    for note in &input.notes {
        doc.push(Block::p(format!("**Note: {note}.**")));
    }
    doc.extend(ranking_table(input));
    doc.extend(confidence_figure(dir, input)?);
    doc.extend(trajectory_figure(dir, input)?);
    doc.push(Block::Heading(2, "How this was made".into()));
    doc.push(Block::p(format!(
        "Command: `{}`. Every episode is deterministic: the same files give the same numbers \
         whatever the number of threads.",
        input.command
    )));
    doc.extend(run_time(input));
    let md = dir.join("report.md");
    let html = dir.join("report.html");
    write_atomically(&md, &to_markdown(&doc))?;
    write_atomically(&html, &to_html(&doc))?;
    Ok(vec![
        md,
        html,
        dir.join(CONFIDENCE_SVG),
        dir.join(TRAJECTORY_SVG),
    ])
}

/// Both stages' wall time and throughput (the only part of the report that varies from run
/// to run).
fn run_time(input: &ReportInput) -> Vec<Block> {
    let Some(t) = input.timing else {
        return Vec::new();
    };
    let (c, s) = (&t.confidence, &t.simulation);
    let threads = if s.threads == 1 { "" } else { "s" };
    vec![
        Block::Heading(2, "Run time".into()),
        Block::table(
            &[
                "stage",
                "work",
                "wall time [s]",
                "throughput",
                "mean per item",
            ],
            vec![
                vec![
                    "confidence ln|Π^U| (reading the file included)".into(),
                    format!("{} tools", c.tools),
                    format!("{:.3}", c.wall.as_secs_f64()),
                    format!("{:.0} tools/s", c.tools_per_second()),
                    format!("{:.0} ns per tool", c.ns_per_tool()),
                ],
                vec![
                    format!("simulation ({} thread{threads})", s.threads),
                    format!("{} episodes", s.episodes),
                    format!("{:.3}", s.wall.as_secs_f64()),
                    format!("{:.0} episodes/s", s.episodes_per_second()),
                    format!("{:.1} µs per episode", s.us_per_episode()),
                ],
            ],
        ),
    ]
}

/// The task's error term, as a symbol and an axis label (`joint angle θ [rad]`).
fn variable(kind: TaskKind) -> (&'static str, String) {
    let term = kind.error_term();
    let axis = format!("{} {} [{}]", term.label(), term.symbol(), term.unit());
    (term.symbol(), axis)
}

fn introduction(input: &ReportInput) -> Vec<Block> {
    let spec = input.spec;
    let (var, _) = variable(spec.kind);
    let goal = spec.kind.doc();
    let screened = match input.screen {
        Some((k, ScreenBy::Confidence)) => format!(
            "Only the {} most confident of the {} tools were simulated (`--screen {k}`).",
            input.results.len(),
            input.read
        ),
        Some((k, ScreenBy::Predicted(_))) => format!(
            "Only the {} of the {} tools whose episode the closed loop linearised at the \
             equilibrium predicts cheapest were simulated (`--screen {k} --screen-by predicted`).",
            input.results.len(),
            input.read
        ),
        None => format!("All {} tools were simulated.", input.read),
    };
    let skipped = if input.skipped > 0 {
        format!(
            " {} bad rows were skipped (`--skip-bad-rows`).",
            input.skipped
        )
    } else {
        String::new()
    };
    vec![
        Block::Heading(1, format!("Ranking the tools of {}", input.tools_file)),
        Block::p(format!(
            "Each tool is {}, that an \
             active-inference controller drives to do one task: **{}**{}. {goal} The controller changes its torque U to lower a free energy F, a weighted sum of \
             squared errors (how far the arm is from the goal, how much torque it uses). \
             Following Anil Meera & Lanillos, *Confidence-Aware Decision-Making and Control \
             for Tool Selection*, each tool is judged by four numbers:",
            what_a_tool_is(input.results),
            spec.label(),
            spec.description
                .as_ref()
                .map_or(String::new(), |d| format!(" ({d})"))
        )),
        Block::Bullets(vec![
            "**Control confidence ln|Π^U|**: Π^U = ∂²F/∂U² says how sharply the free energy \
             reacts to the torque, i.e. how precisely the controller can steer this arm for this \
             task. It depends only on the arm and the task's weights, so it costs microseconds \
             and needs no simulation. Higher is more confident."
                .into(),
            format!(
                "**Task error**: the weighted squared distance of {var} from its goal, \
                 (x − x_goal)ᵀ P (x − x_goal), summed over every output time of a simulated \
                 episode. Lower is better."
            ),
            "**∫F dt** (free energy): the controller's whole objective over the episode, \
             errors and torque minus ½ ln|Π^U|: good tools reach the goal cheaply *and* are \
             confident. This is the paper's criterion. Lower is better."
                .into(),
            "**∫J dt**: the same without the confidence term, the classic optimal-control \
             cost. Lower is better."
                .into(),
        ]),
        Block::p(format!(
            "The ranking below is by **{}**. {screened}{skipped} A tool whose simulation \
             failed keeps its error message and is listed last.",
            objective_words(input.objective)
        )),
    ]
    .into_iter()
    .chain(task_table(input))
    .collect()
}

/// What the tools are, from their models: "a tool of `arm2` (2-DOF arm in the vertical plane
/// ...), given by m1 (kg), m2 (kg), ...", one clause per model among the results.
fn what_a_tool_is(results: &[RankedTool]) -> String {
    let mut models: Vec<ModelKind> = results.iter().map(|r| r.row.tool.model()).collect();
    models.sort();
    models.dedup();
    let clauses: Vec<String> = models
        .iter()
        .map(|m| {
            let params: Vec<String> = m
                .parameter_names()
                .iter()
                .zip(m.parameter_units())
                .map(|(p, u)| format!("{p} ({u})"))
                .collect();
            format!(
                "a tool of `{m}` ({}), given by {}",
                m.title(),
                params.join(", ")
            )
        })
        .collect();
    clauses.join("; or ")
}

fn objective_words(o: Objective) -> &'static str {
    match o {
        Objective::FreeEnergy => "∫F dt, lowest first",
        Objective::CostJ => "∫J dt, lowest first",
        Objective::Confidence => "control confidence ln|Π^U|, highest first",
    }
}

fn per_joint(p: &PerJoint) -> String {
    match p {
        PerJoint::All(x) => format!("{x} on every joint"),
        PerJoint::Each(v) => format!("{v:?} (joint by joint)"),
    }
}

fn precision(p: &PrecisionSpec) -> String {
    match p {
        PrecisionSpec::Scalar(s) => format!("{s}·I"),
        PrecisionSpec::Matrix(rows) => format!("{rows:?}"),
    }
}

/// A term's goal in words: the file's (with how a relative tip goal is resolved), else
/// `paper`.
fn goal_words(spec: &TaskSpec, term: Term, paper: &str) -> String {
    use toolconf_model::inputs::task_file::TipGoal;
    let given = spec.goal[term.index()]
        .as_ref()
        .map_or_else(|| paper.to_string(), |v| format!("{v:?}"));
    match (&spec.tip_goal, term) {
        (TipGoal::Offset(_), Term::Tip) => spec.tip_goal.describe(),
        (TipGoal::Motion { .. }, Term::TipDot | Term::TipDdot) => {
            format!("{given} ({})", spec.tip_goal.describe())
        }
        _ => given,
    }
}

/// What the task sets, in words; what it leaves out is each model's paper value.
fn task_table(input: &ReportInput) -> Vec<Block> {
    let spec = input.spec;
    let e = &spec.episode;
    let paper = "the paper's (per model)";
    let given = |v: Option<String>, default: &str| v.unwrap_or_else(|| default.to_string());
    let vector = |v: &Option<Vec<f64>>| v.as_ref().map(|v| format!("{v:?}"));
    let number = |v: Option<f64>| v.map(|v| v.to_string());
    let mut rows = vec![vec!["task kind".to_string(), spec.kind.to_string()]];
    let mut add = |name: &str, value: String| rows.push(vec![name.to_string(), value]);
    // A tip task file's precisions left out come from the robot's own scales on a URDF arm.
    let scaled = !spec.file.is_empty()
        && spec
            .kind
            .terms()
            .iter()
            .any(|t| matches!(t.read(), Read::Tip { .. }));
    let default_precision = |term: Term| match toolconf_model::robot_scales::default_words(term) {
        Some(words) if scaled => {
            format!("on a URDF arm {words} (the robot's own scale), else {paper}")
        }
        _ => paper.to_string(),
    };
    for term in Term::ALL.into_iter().filter(|t| spec.kind.uses(*t)) {
        let i = term.index();
        if term.has_goal() {
            let name = format!("goal {} [{}]", term.symbol(), term.unit());
            add(&name, goal_words(spec, term, paper));
        }
        let name = format!("precision P^{}", term.symbol());
        add(
            &name,
            given(
                spec.precision[i].as_ref().map(precision),
                &default_precision(term),
            ),
        );
    }
    add(
        "integration method",
        e.method.unwrap_or_default().describe().to_string(),
    );
    add("episode length t_end [s]", given(number(e.t_end), "5"));
    add("output step dt [s]", given(number(e.dt), "0.05"));
    add(
        "constant torque perturbation ΔT [N m]",
        given(e.perturbation.as_ref().map(per_joint), "0"),
    );
    add(
        "initial joint angles [rad]",
        given(
            vector(&e.initial_theta),
            "the model's equilibrium q^e (the planar arms: hanging straight down)",
        ),
    );
    add(
        "initial joint velocities [rad/s]",
        given(vector(&e.initial_theta_dot), "0"),
    );
    add(
        "initial torque U0 [N m]",
        given(
            e.initial_torque.as_ref().map(per_joint),
            "0.1 on every joint",
        ),
    );
    add("learning rate γ", given(number(e.learning_rate), "1"));
    vec![
        Block::p(
            "The task: a precision P weighs an error term (a larger P means the controller \
             cares more about it; P·I weighs every joint alike). What the task file leaves out \
             is the paper's value."
                .to_string(),
        ),
        Block::table(&["setting", "value"], rows),
    ]
}

fn number(v: f64) -> String {
    format!("{v:.6}")
}

fn ranking_table(input: &ReportInput) -> Vec<Block> {
    let mut rows = Vec::new();
    let failed: Vec<usize> = input
        .order
        .iter()
        .copied()
        .filter(|&i| input.results[i].episode.is_err())
        .collect();
    for (rank, &i) in input.order.iter().enumerate() {
        let r = &input.results[i];
        if rank >= LISTED && r.episode.is_ok() {
            continue;
        }
        let logdet = r.logdet.as_ref().map_or("–".into(), |l| number(*l));
        let metrics = match &r.episode {
            Ok(m) => vec![
                number(m.task_error),
                number(m.free_energy),
                number(m.cost_j),
                m.progress.map_or("–".into(), |p| format!("{p:.3}")),
            ],
            Err(e) => vec![
                format!("failed: {e}"),
                String::new(),
                String::new(),
                String::new(),
            ],
        };
        let mut row = vec![
            (rank + 1).to_string(),
            r.row.label(),
            r.row.tool.model().name().to_string(),
            r.parameters_text(),
            logdet,
            // The prediction, or why there is none (an unstable linearised loop).
            r.prediction
                .as_ref()
                .map_or_else(|e| format!("– ({})", e.reason()), |p| number(p.task_error)),
        ];
        row.extend(metrics);
        rows.push(row);
    }
    let shown = input.order.len().min(LISTED).max(rows.len());
    let mut blocks = vec![Block::Heading(2, "Ranking".into())];
    if input.order.len() > shown || (input.order.len() > LISTED) {
        blocks.push(Block::p(format!(
            "The best {LISTED} of {} simulated tools (and every failed one, {}); the full list \
             is in the JSON or CSV output.",
            input.order.len(),
            failed.len()
        )));
    }
    blocks.push(Block::table(
        &[
            "rank",
            "tool",
            "model",
            "parameters",
            "ln|Π^U|",
            "predicted task error",
            "task error",
            "∫F dt",
            "∫J dt",
            "progress",
        ],
        rows,
    ));
    blocks
}

const CONFIDENCE_SVG: &str = "confidence_vs_task_error.svg";
const TRAJECTORY_SVG: &str = "best_and_worst.svg";

fn confidence_figure(dir: &Path, input: &ReportInput) -> Result<Vec<Block>, ReproduceError> {
    let points: Vec<(f64, f64)> = input
        .results
        .iter()
        .filter_map(|r| {
            Some((
                *r.logdet.as_ref().ok()?,
                r.episode.as_ref().ok()?.task_error,
            ))
        })
        .collect();
    let (x, y): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    let panel = XyPanel {
        title: format!("{} simulated tools", points.len()),
        x_label: "control confidence ln|Π^U|".into(),
        y_label: "task error".into(),
        dots: vec![Series::new("tools", Colour(0, 114, 178), points.clone())],
        lines: Vec::new(),
        log_y: wants_log(&y),
        legend: Legend::UpperRight,
        headroom: 0.1,
    };
    let svg = plot::save(&dir.join(CONFIDENCE_SVG), &[Panel::Xy(panel)], (640, 420))?;
    let verdict = match spearman(&x, &y) {
        Ok(rho) => format!(
            "Spearman's rank correlation between confidence and task error is ρ = {rho:.3} \
             over {} tools. {}",
            points.len(),
            if rho <= -0.3 {
                "Here, as the paper found, the more confident tools tend to do the task \
                 better: confidence alone is a useful first screen."
            } else if rho < 0.0 {
                "More confident tools do the task slightly better here, but confidence alone \
                 is a weak guide for this tool set."
            } else {
                "Here confidence does not predict the task error: rank these tools by \
                 simulation, not by confidence alone."
            }
        ),
        Err(e) => format!("The rank correlation cannot be computed here: {e}."),
    };
    Ok(vec![
        Block::Heading(2, "Does confidence predict the task error?".into()),
        Block::p(
            "Confidence costs nothing to compute, the task error needs a simulation. If the \
             two agree (points falling from left to right), confidence can pick good tools \
             from a large set before anything is simulated (`--screen K`)."
                .to_string(),
        ),
        Block::Figure {
            file: CONFIDENCE_SVG.into(),
            caption: "Each dot is a simulated tool: its control confidence ln|Π^U| against \
                      its task error."
                .into(),
            svg,
        },
        Block::p(verdict),
    ])
}

/// A traced tool: its legend ("#rank name"), colour, whether dashed (a worst tool), and its
/// task variable over the episode.
type Traced = (String, Colour, bool, TaskTrace);

/// The [`TRACED`] best tools by the objective, and the [`TRACED`] worst not among them, each
/// as indices into the results, best or worst first.
fn best_and_worst(input: &ReportInput) -> (Vec<usize>, Vec<usize>) {
    let ok: Vec<usize> = input
        .order
        .iter()
        .copied()
        .filter(|&i| score(input.objective, &input.results[i]).is_some())
        .collect();
    let best: Vec<usize> = ok.iter().copied().take(TRACED).collect();
    let worst: Vec<usize> = ok
        .iter()
        .rev()
        .copied()
        .filter(|i| !best.contains(i))
        .take(TRACED)
        .collect();
    (best, worst)
}

/// Each tool's trace of `best` (solid, blues) and `worst` (dashed, reds); the (result, trace)
/// indices of the best and the worst tool, for the 3-D view; and a note per tool whose trace
/// failed.
fn traces_of(
    input: &ReportInput,
    best: &[usize],
    worst: &[usize],
) -> (Vec<Traced>, Vec<(usize, usize)>, Vec<String>) {
    const BEST: [Colour; TRACED] = [
        Colour(0, 90, 200),
        Colour(60, 150, 230),
        Colour(120, 190, 240),
    ];
    const WORST: [Colour; TRACED] = [
        Colour(200, 30, 30),
        Colour(230, 110, 60),
        Colour(240, 170, 110),
    ];
    let mut traces: Vec<Traced> = Vec::new();
    let mut ends: Vec<(usize, usize)> = Vec::new();
    let mut notes = Vec::new();
    for (group, colours, dashed) in [(best, BEST, false), (worst, WORST, true)] {
        for (k, &i) in group.iter().enumerate() {
            let r = &input.results[i];
            let rank = input.order.iter().position(|&j| j == i).unwrap_or(0) + 1;
            match input.tasks.trace(&r.row.tool) {
                Ok(t) => {
                    if k == 0 {
                        ends.push((i, traces.len()));
                    }
                    traces.push((format!("#{rank} {}", r.row.label()), colours[k], dashed, t))
                }
                Err(e) => notes.push(format!("#{rank} {}: {e}", r.row.label())),
            }
        }
    }
    (traces, ends, notes)
}

/// The panel of component `j` of the task variable: each trace that has it, and its goal.
fn trace_panel(j: usize, traces: &[Traced], kind: TaskKind, axis: &str) -> Panel {
    let mut lines: Vec<Series> = traces
        .iter()
        .filter(|t| j < t.3.value.len())
        .map(|(label, colour, dashed, t)| {
            let s = Series::new(
                label.clone(),
                *colour,
                t.t.iter()
                    .copied()
                    .zip(t.value[j].iter().copied())
                    .collect(),
            );
            if *dashed {
                s.dashed()
            } else {
                s
            }
        })
        .collect();
    if let Some((_, _, _, t)) = traces.iter().find(|t| j < t.3.value.len()) {
        let end = t.t.last().copied().unwrap_or(0.0);
        lines.push(
            Series::new(
                "goal",
                plot::GOAL_GREY,
                vec![(0.0, t.goal[j]), (end, t.goal[j])],
            )
            .dashed(),
        );
    }
    Panel::Xy(XyPanel {
        title: component_title(kind, j),
        x_label: "time t [s]".into(),
        y_label: axis.into(),
        dots: Vec::new(),
        lines,
        log_y: false,
        legend: Legend::LowerRight,
        headroom: 0.35,
    })
}

fn trajectory_figure(dir: &Path, input: &ReportInput) -> Result<Vec<Block>, ReproduceError> {
    let (best, worst) = best_and_worst(input);
    let (var, axis) = variable(input.spec.kind);
    let (traces, ends, notes) = traces_of(input, &best, &worst);
    let joints = traces.iter().map(|t| t.3.value.len()).max().unwrap_or(0);
    let panels: Vec<Panel> = (0..joints.max(1))
        .map(|j| trace_panel(j, &traces, input.spec.kind, &axis))
        .collect();
    let svg = plot::save(&dir.join(TRAJECTORY_SVG), &panels, (560, 420))?;
    let mut blocks = vec![
        Block::Heading(2, "The best and the worst tools over time".into()),
        Block::p(format!(
            "The task variable {var} of the {} best (solid, blue) and {} worst (dashed, red) \
             tools by {}, one panel per {}; the grey dashed line is the goal. A good tool \
             gets to the goal quickly and stays there.",
            best.len(),
            worst.len(),
            objective_words(input.objective),
            match input.spec.kind.error_term().read() {
                Read::Tip { .. } => "component of the tip in the base frame",
                _ => "joint",
            }
        )),
        Block::Figure {
            file: TRAJECTORY_SVG.into(),
            caption: format!("{var} over one episode; #k is the tool's rank."),
            svg,
        },
    ];
    if !notes.is_empty() {
        blocks.push(Block::Bullets(notes));
    }
    blocks.extend(tip_path_figure(dir, input, &traces)?);
    blocks.extend(arm_view(input, &ends, &traces));
    Ok(blocks)
}

/// The 3-D view of the best and the worst tool's episodes (`ends`: their result and trace
/// indices), with the goal point of a tip position task; on a model without a URDF flange, the
/// line saying why there is none.
fn arm_view(input: &ReportInput, ends: &[(usize, usize)], traces: &[Traced]) -> Vec<Block> {
    let shown: Vec<view3d::Shown> = ends
        .iter()
        .zip(["best", "worst"])
        .filter_map(|(&(i, k), which)| {
            let (label, _, _, trace) = traces.get(k)?;
            Some(view3d::Shown {
                label: format!("{which}: {label}"),
                tool: &input.results[i].row.tool,
                trace,
            })
        })
        .collect();
    view3d::section(view3d::tip_goal(input.spec.kind, &shown), &shown)
}

/// A panel's title: `joint 2`, or `tip y` for a component of a tip term.
fn component_title(kind: TaskKind, j: usize) -> String {
    match kind.error_term().read() {
        Read::Tip { .. } => format!("tip {}", AXES.get(j).copied().unwrap_or("?")),
        _ => format!("joint {}", j + 1),
    }
}

const TIP_PATH_SVG: &str = "tip_paths.svg";

/// The tips' paths projected on the base frame's axes (a, b), with each start and, where the
/// goal is a point, the goal.
fn projected_tip_paths(
    paths: &[(&Traced, &[Vec<f64>])],
    (a, b, title): (usize, usize, &str),
    goal_is_point: bool,
) -> Panel {
    let lines: Vec<Series> = paths
        .iter()
        .map(|((label, colour, dashed, _), path)| {
            let points = path[a]
                .iter()
                .copied()
                .zip(path[b].iter().copied())
                .collect();
            let s = Series::new(label.clone(), *colour, points);
            if *dashed {
                s.dashed()
            } else {
                s
            }
        })
        .collect();
    let mut dots = Vec::new();
    if let Some(((_, _, _, t), _)) = paths.first().filter(|_| goal_is_point) {
        dots.push(Series::new(
            "goal",
            plot::GOAL_GREY,
            vec![(t.goal[a], t.goal[b])],
        ));
    }
    let starts: Vec<(f64, f64)> = paths
        .iter()
        .filter_map(|p| Some((*p.1[a].first()?, *p.1[b].first()?)))
        .collect();
    dots.push(Series::new("start", Colour(190, 190, 190), starts));
    plot::tip_path_panel(title, (a, b), dots, lines)
}

/// On a tip task, the tip's path of the best and worst tools in two projections of the base
/// frame (x–y seen from above, x–z from the side; the plane of a planar arm alone), with the
/// goal point of a tip position task marked.
fn tip_path_figure(
    dir: &Path,
    input: &ReportInput,
    traces: &[Traced],
) -> Result<Vec<Block>, ReproduceError> {
    let paths: Vec<(&Traced, &[Vec<f64>])> = traces
        .iter()
        .filter_map(|t| Some((t, t.3.tip_path.as_deref()?)))
        .collect();
    let Some(dims) = paths.iter().map(|p| p.1.len()).min().filter(|&d| d >= 2) else {
        return Ok(Vec::new());
    };
    let goal_is_point = matches!(input.spec.kind.error_term().read(), Read::Tip { order: 0 });
    let projections: &[(usize, usize, &str)] = if dims >= 3 {
        &[
            (0, 1, "seen from above (x–y)"),
            (0, 2, "seen from the side (x–z)"),
        ]
    } else {
        &[(0, 1, "in the arm's plane (x–y)")]
    };
    let panels: Vec<Panel> = projections
        .iter()
        .map(|&projection| projected_tip_paths(&paths, projection, goal_is_point))
        .collect();
    let svg = plot::save(&dir.join(TIP_PATH_SVG), &panels, (560, 420))?;
    Ok(vec![
        Block::Heading(2, "Where the tool's tip went".into()),
        Block::p(format!(
            "The path of the tool's tip y(q(t)) in the robot's base frame, for the same best \
             (solid) and worst (dashed) tools{}. Each tool starts where its own tip rests (the \
             light grey dots), so tools of different lengths start at different points.",
            if goal_is_point {
                "; the grey dot is the goal point"
            } else {
                ""
            }
        )),
        Block::Figure {
            file: TIP_PATH_SVG.into(),
            caption: "The tip's path over one episode, in two projections; #k is the tool's \
                      rank."
                .into(),
            svg,
        },
    ])
}
