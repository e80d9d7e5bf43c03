//! The design report (`toolconf design --report DIR`): `report.md` and `report.html` with the
//! designed tool beside the best random feasible tools, and, with `--sweep`, the trade-off
//! front as `sweep.csv` and `sweep.svg`.

use std::path::{Path, PathBuf};

use crate::experiments::plot::{self, Colour, Legend, Panel, Series, XyPanel};
use crate::experiments::report::{to_html, to_markdown, Block};
use crate::experiments::{write_atomically, ReproduceError};

use toolconf::design::sweep::{Sweep, SweepPoint};
use toolconf::design::DesignResult;
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::registry::{AnyTool, ModelKind};

use crate::view3d;

pub const SWEEP_CSV: &str = "sweep.csv";
pub const SWEEP_SVG: &str = "sweep.svg";

/// What the report describes.
pub struct ReportInput<'a> {
    pub command: &'a str,
    pub model: &'a str,
    pub task: &'a str,
    pub spec: &'a DesignSpec,
    pub result: &'a DesignResult,
    pub sweep: Option<(&'a Sweep, &'a [SweepPoint])>,
    /// The task bound to every model and the designed model: what the 3-D view's episodes run.
    pub tasks: &'a ModelTasks,
    pub model_kind: ModelKind,
}

pub use toolconf::design::parameters_text;

/// The files [`write_report`] writes into its folder, with a sweep or without (checked against
/// the run's other files before any work: [`toolconf_files::run_files`]).
pub fn report_files(sweep: bool) -> &'static [&'static str] {
    if sweep {
        &["report.md", "report.html", SWEEP_CSV, SWEEP_SVG]
    } else {
        &["report.md", "report.html"]
    }
}

/// Writes the report into `dir` (created if needed); returns the files written.
pub fn write_report(dir: &Path, input: &ReportInput) -> Result<Vec<PathBuf>, ReproduceError> {
    toolconf_files::file::create_folder(dir).map_err(ReproduceError::io(dir))?;
    let r = input.result;
    let mut doc = vec![
        Block::Heading(1, format!("Tool design for the {} task ({})", input.task, input.model)),
        Block::p(format!(
            "The designed tool maximises the controller's confidence ln|Π^U| (the curvature of its \
             free energy in the control: a precise, well-conditioned controller) within the bounds \
             and constraints of `{}`{}. Objective: {}.",
            input.spec.file,
            if input.spec.constraints.is_empty() {
                String::new()
            } else {
                format!(
                    " ({})",
                    input.spec.constraints.iter().map(|c| c.text.clone()).collect::<Vec<_>>().join(", ")
                )
            },
            r.objective.name()
        )),
        Block::p(format!(
            "Design: {} with ln|Π^U| = {:.6}. The SQP reached it from start {} in {} iterations; \
             KKT residual {:.2e}; the derived gradient agrees with central differences to {:.1e} \
             (relative).",
            parameters_text(&input.spec.names, &r.params),
            r.logdet,
            r.confidence_optimum.start,
            r.confidence_optimum.iterations,
            r.confidence_optimum.kkt_residual,
            r.gradient_check
        )),
        Block::Heading(2, "The design beside random feasible tools".into()),
        Block::p(format!(
            "{} random feasible tools were drawn ({} draws from the bounds); the most confident are \
             simulated beside the design. Sensitivity is |task error under ΔT = {} N m − task error|: \
             smaller is more robust.",
            r.random.feasible, r.random.drawn, input.spec.search.perturbation
        )),
        Block::table(
            &["tool", "ln|Π^U|", "task error", "∫F dt", "sensitivity to ΔT", "parameters"],
            r.checks
                .iter()
                .map(|c| {
                    let (e, f, s) = match &c.simulated {
                        Ok(m) => (format!("{:.6e}", m.task_error), format!("{:.6e}", m.free_energy), format!("{:.6e}", m.sensitivity)),
                        Err(err) => (err.clone(), String::new(), String::new()),
                    };
                    vec![c.label.clone(), format!("{:.6}", c.logdet), e, f, s, parameters_text(&input.spec.names, &c.params)]
                })
                .collect(),
        ),
    ];
    if let Some(note) = r.confidence_note() {
        doc.insert(2, Block::p(format!("**Note: {note}.**")));
    }
    let md = dir.join("report.md");
    let html = dir.join("report.html");
    let mut files = vec![md.clone(), html.clone()];
    if let Some((sweep, points)) = input.sweep {
        doc.extend(sweep_section(dir, input.spec, sweep, points)?);
        files.extend([dir.join(SWEEP_CSV), dir.join(SWEEP_SVG)]);
    }
    doc.extend(arm_view(input));
    doc.push(Block::Heading(2, "How this was made".into()));
    doc.push(Block::p(format!(
        "Command: `{}`. The same file and seed give the same design.",
        input.command
    )));
    write_atomically(&md, &to_markdown(&doc))?;
    write_atomically(&html, &to_html(&doc))?;
    Ok(files)
}

/// The sweep as CSV text: one row per value, the optimum's parameters and ln|Π^U|.
pub fn sweep_csv(names: &[&str], points: &[SweepPoint]) -> String {
    let mut out = format!("budget,logdet,kkt_residual,{},error\n", names.join(","));
    for p in points {
        match &p.outcome {
            Ok((params, logdet, kkt)) => {
                let values: Vec<String> = params.iter().map(|v| format!("{v}")).collect();
                out += &format!("{},{logdet},{kkt},{},\n", p.value, values.join(","));
            }
            Err(e) => out += &format!("{},,,{},{e}\n", p.value, vec![""; names.len()].join(",")),
        }
    }
    out
}

fn sweep_section(
    dir: &Path,
    spec: &DesignSpec,
    sweep: &Sweep,
    points: &[SweepPoint],
) -> Result<Vec<Block>, ReproduceError> {
    write_atomically(&dir.join(SWEEP_CSV), &sweep_csv(&spec.names, points))?;
    let front: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|p| p.outcome.as_ref().ok().map(|o| (p.value, o.1)))
        .collect();
    let panel = XyPanel {
        title: format!("best confidence against the budget {} b", sweep.label),
        x_label: format!("b in {} b", sweep.label),
        y_label: "best ln|Π^U|".into(),
        dots: vec![Series::new("optimum", Colour(0, 114, 178), front.clone())],
        lines: vec![Series::new("", Colour(0, 114, 178), front)],
        log_y: false,
        legend: Legend::LowerRight,
        headroom: 0.1,
    };
    let svg = plot::save(&dir.join(SWEEP_SVG), &[Panel::Xy(panel)], (640, 420))?;
    let infeasible = points.iter().filter(|p| p.outcome.is_err()).count();
    Ok(vec![
        Block::Heading(2, "Trade-off".into()),
        Block::p(format!(
            "The design re-solved with `{} b` for {} values of b ({} infeasible): how much confidence \
             each unit of budget buys (`{SWEEP_CSV}`).",
            sweep.label,
            points.len(),
            infeasible
        )),
        Block::Figure { file: SWEEP_SVG.into(), caption: "Best ln|Π^U| against the swept budget.".into(), svg },
    ])
}

/// The 3-D view of the design's episode beside the simulated random tool with the largest ∫F
/// (on a model without a URDF flange, the line saying why there is none).
fn arm_view(input: &ReportInput) -> Vec<Block> {
    let simulated =
        |c: &&toolconf::design::verify::ToolCheck| c.simulated.as_ref().ok().map(|s| s.free_energy);
    let design = input.result.checks.first();
    let worst = input
        .result
        .checks
        .iter()
        .skip(1)
        .filter(|c| simulated(c).is_some())
        .max_by(|a, b| {
            simulated(a)
                .partial_cmp(&simulated(b))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
    let picked: Vec<(String, AnyTool)> = design
        .into_iter()
        .chain(worst)
        .filter_map(|c| {
            Some((
                c.label.clone(),
                AnyTool::new(input.model_kind, &c.params).ok()?,
            ))
        })
        .collect();
    let traces: Vec<_> = picked
        .iter()
        .map(|(_, tool)| input.tasks.trace(tool).ok())
        .collect();
    let shown: Vec<view3d::Shown> = picked
        .iter()
        .zip(&traces)
        .filter_map(|((label, tool), trace)| {
            Some(view3d::Shown {
                label: label.clone(),
                tool,
                trace: trace.as_ref()?,
            })
        })
        .collect();
    view3d::section(view3d::tip_goal(input.tasks.kind, &shown), &shown)
}
