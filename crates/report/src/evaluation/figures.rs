//! The figures of an evaluation, each the paper's figure for the model's task: a figure whose
//! data are missing is not drawn (the report says why), so no panel is ever empty.

use std::path::Path;

use toolconf::evaluation::trials::{MEASURES, RULES};
use toolconf::evaluation::{Evaluation, HighlightRun, ToolRecord};

use crate::experiments::figure_parts::mean_lines;
use crate::experiments::plot::{
    self, diverging, BoxPanel, Colour, GridPanel, Legend, Panel, Series, XyPanel,
};
use crate::experiments::ReproduceError;

/// A drawn figure: its file and SVG text.
pub struct Figure {
    pub file: &'static str,
    pub svg: String,
}

/// A log y axis when the positive values span more than a factor 30 (and none is ≤ 0).
fn wants_log(values: &[f64]) -> bool {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    lo > 0.0 && hi.is_finite() && hi / lo > 30.0
}

fn save(
    dir: &Path,
    file: &'static str,
    panels: &[Panel],
    size: (u32, u32),
) -> Result<Figure, ReproduceError> {
    Ok(Figure {
        file,
        svg: plot::save(&dir.join(file), panels, size)?,
    })
}

/// ln|Π^U| against `y` for every tool with both.
fn scatter(
    e: &Evaluation,
    y: impl Fn(&toolconf::evaluation::ToolRecord) -> Option<f64>,
) -> Vec<(f64, f64)> {
    e.records
        .iter()
        .filter_map(|r| Some((r.logdet()?, y(r)?)))
        .collect()
}

/// `file`, one panel of `points` against confidence; none where there are no points.
fn scatter_figure(
    dir: &Path,
    file: &'static str,
    title: String,
    y_label: &str,
    points: Vec<(f64, f64)>,
    colour: Colour,
) -> Result<Option<Figure>, ReproduceError> {
    if points.is_empty() {
        return Ok(None);
    }
    let ys: Vec<f64> = points.iter().map(|p| p.1).collect();
    let panel = Panel::Xy(XyPanel {
        title,
        x_label: "control confidence ln|Π^U|".into(),
        y_label: y_label.into(),
        dots: vec![Series::new("", colour, points)],
        lines: vec![],
        log_y: wants_log(&ys),
        legend: Legend::UpperRight,
        headroom: 0.0,
    });
    save(dir, file, &[panel], (640, 460)).map(Some)
}

/// Fig. 2: task error against confidence.
pub fn fig2(dir: &Path, e: &Evaluation) -> Result<Option<Figure>, ReproduceError> {
    let title = format!(
        "{}: {}",
        e.task_title(),
        e.statistics.task_error.describe_short()
    );
    let points = scatter(e, |r| r.task_error());
    let file = "fig2_confidence_vs_error.svg";
    scatter_figure(dir, file, title, "task error", points, Colour(0, 114, 178))
}

/// Fig. 4: |Δ task error| under ΔT against confidence.
pub fn fig4(dir: &Path, e: &Evaluation) -> Result<Option<Figure>, ReproduceError> {
    let title = format!(
        "|Δ task error| under ΔT: {}",
        e.statistics.reliability.describe_short()
    );
    let points = scatter(e, |r| r.abs_change());
    let y_label = "|task error(ΔT) − task error(0)|";
    let file = "fig4_perturbation_change.svg";
    scatter_figure(dir, file, title, y_label, points, Colour(213, 94, 0))
}

/// Fig. 3: the distance to the goal over time of the two tools without and with ΔT, and on a tip
/// task the tip's path seen from above and from the side.
pub fn fig3(dir: &Path, e: &Evaluation) -> Result<Option<Figure>, ReproduceError> {
    let runs: Vec<&HighlightRun> = e
        .highlight
        .runs
        .iter()
        .filter(|r| r.trace.is_ok())
        .collect();
    if runs.is_empty() {
        return Ok(None);
    }
    let colour = |r: &HighlightRun| match (r.role, r.perturbed) {
        ("high", false) => Colour(230, 159, 0),
        ("high", true) => Colour(120, 60, 160),
        (_, false) => Colour(200, 30, 30),
        (_, true) => Colour(30, 80, 200),
    };
    let label = |r: &HighlightRun| {
        format!(
            "{} confidence (tool {}){}",
            r.role,
            r.tool,
            if r.perturbed { ", ΔT" } else { ", ΔT = 0" }
        )
    };
    let series = |r: &HighlightRun, points: Vec<(f64, f64)>| {
        let s = Series::new(label(r), colour(r), points);
        if r.perturbed {
            s.dashed()
        } else {
            s
        }
    };
    let lines: Vec<Series> = runs
        .iter()
        .filter_map(|r| Some(series(r, r.distance()?)))
        .collect();
    let mut panels = vec![Panel::Xy(XyPanel {
        title: format!("{}: distance to the goal", e.task_title()),
        x_label: "time t [s]".into(),
        y_label: format!("|{} − goal|", e.setup.spec.kind.error_term().symbol()),
        dots: vec![],
        lines,
        log_y: false,
        legend: Legend::UpperRight,
        headroom: 0.45,
    })];
    panels.extend(tip_paths(&runs, e, &series));
    save(dir, "fig3_trajectories.svg", &panels, (560, 460)).map(Some)
}

/// How a run's points become its drawn series (colour, dashes, label).
type SeriesOf<'a> = dyn Fn(&HighlightRun, Vec<(f64, f64)>) -> Series + 'a;

/// The tip's path in two projections (one for a planar arm), goals and starts marked.
fn tip_paths(runs: &[&HighlightRun], e: &Evaluation, series: &SeriesOf) -> Vec<Panel> {
    let paths: Vec<(&HighlightRun, &Vec<Vec<f64>>)> = runs
        .iter()
        .filter_map(|r| Some((*r, r.trace.as_ref().ok()?.tip_path.as_ref()?)))
        .filter(|(_, p)| p.len() >= 2)
        .collect();
    let Some(dims) = paths.iter().map(|p| p.1.len()).min() else {
        return Vec::new();
    };
    let point_goal = e.setup.spec.kind == toolconf_model::TaskKind::TipPosition;
    let projections: &[(usize, usize, &str)] = if dims >= 3 {
        &[
            (0, 1, "the tip seen from above (x–y)"),
            (0, 2, "the tip seen from the side (x–z)"),
        ]
    } else {
        &[(0, 1, "the tip in the arm's plane (x–y)")]
    };
    projections
        .iter()
        .map(|&(a, b, title)| {
            let lines = paths
                .iter()
                .map(|(r, p)| series(r, p[a].iter().copied().zip(p[b].iter().copied()).collect()))
                .collect();
            let mut goals = Vec::new();
            let mut starts = Vec::new();
            for (r, p) in &paths {
                let tr = r.trace.as_ref().expect("filtered");
                if point_goal && tr.goal.len() > b {
                    goals.push((tr.goal[a], tr.goal[b]));
                }
                starts.push((p[a][0], p[b][0]));
            }
            let mut dots = vec![Series::new("start", Colour(190, 190, 190), starts)];
            if !goals.is_empty() {
                dots.push(Series::new("goal", plot::GOAL_GREY, goals));
            }
            plot::tip_path_panel(title, (a, b), dots, lines)
        })
        .collect()
}

/// Fig. 5: |Δ task error| against confidence at every level of the sweep, and its mean per level
/// for the least and the most confident third of the sweep's tools.
pub fn fig5(dir: &Path, e: &Evaluation) -> Result<Option<Figure>, ReproduceError> {
    let scales = &e.setup.scales;
    let swept: Vec<_> = e
        .records
        .iter()
        .filter(|r| !r.sweep.is_empty() && r.logdet().is_some())
        .collect();
    let largest = scales.iter().fold(0.0, |m: f64, s| m.max(s.abs()));
    let dots: Vec<Series> = (0..scales.len())
        .filter(|&k| scales[k] != 0.0)
        .map(|k| {
            let pts = swept
                .iter()
                .filter_map(|r| Some((r.logdet()?, r.sweep_change(k)?)))
                .collect();
            Series::new(
                format!("{:+.2}·ΔT", scales[k]).replace('-', "−"),
                diverging(-scales[k] / largest),
                pts,
            )
        })
        .filter(|s: &Series| !s.points.is_empty())
        .collect();
    if dots.is_empty() {
        return Ok(None);
    }
    let lines = fig5_mean_lines(scales, swept);
    let panels = [
        plot::scatter_panel(
            "|Δ task error| against confidence, by level",
            "control confidence ln|Π^U|",
            "|task error(s·ΔT) − task error(0)|",
            dots,
        ),
        plot::means_panel(
            "mean |Δ task error| per level",
            "scale s of ΔT",
            "mean |Δ task error|",
            lines,
        ),
    ];
    save(dir, "fig5_perturbation_sweep.svg", &panels, (620, 460)).map(Some)
}

/// Fig. 5's lines: the mean |Δ task error| per scale of all the swept tools, and (with six
/// tools or more) of the least and the most confident third.
fn fig5_mean_lines(scales: &[f64], ranked: Vec<&ToolRecord>) -> Vec<Series> {
    let m = mean_lines(ranked, |r| r.logdet(), scales, |r, k| r.sweep_change(k));
    let mut lines = vec![Series::new("all tools", Colour(60, 60, 60), m.all)];
    if let Some((_, least, most)) = m.thirds {
        lines.push(Series::new(
            "least confident third",
            Colour(200, 30, 30),
            least,
        ));
        lines.push(Series::new(
            "most confident third",
            Colour(30, 80, 200),
            most,
        ));
    }
    lines
}

/// Fig. 6: which tool of each trial ∫F and ∫J chose.
pub fn fig6(dir: &Path, e: &Evaluation) -> Result<Option<Figure>, ReproduceError> {
    let rows = e.grid.iter().map(|t| t.tools.len()).max().unwrap_or(0);
    if rows == 0 {
        return Ok(None);
    }
    let cells: Vec<Vec<usize>> = (0..rows)
        .map(|i| {
            e.grid
                .iter()
                .map(|t| {
                    usize::from(t.chosen[0] == Some(i)) + 2 * usize::from(t.chosen[1] == Some(i))
                })
                .collect()
        })
        .collect();
    let panel = Panel::Grid(GridPanel {
        title: format!(
            "Tool chosen by ∫F and ∫J in {} trials of {} tools",
            e.grid.len(),
            rows
        ),
        x_label: "trial".into(),
        y_label: "tool of the trial".into(),
        cells,
        categories: vec![
            ("not chosen".into(), Colour(255, 255, 255)),
            ("chosen by F".into(), Colour(205, 205, 205)),
            ("chosen by J".into(), Colour(105, 105, 105)),
            ("chosen by both".into(), Colour(0, 0, 0)),
        ],
    });
    save(dir, "fig6_selection_grid.svg", &[panel], (1000, 380)).map(Some)
}

/// Fig. 7: box plots of the chosen tools' confidence, task error and sensitivity, per rule.
pub fn fig7(dir: &Path, e: &Evaluation) -> Result<Option<Figure>, ReproduceError> {
    const COLOURS: [Colour; 3] = [Colour(0, 114, 178), Colour(213, 94, 0), Colour(0, 158, 115)];
    const SHORT: [&str; 3] = ["F", "J", "confidence"];
    let panels: Vec<Panel> = (0..MEASURES.len())
        .map(|m| {
            Panel::Boxes(BoxPanel {
                title: format!("{} of the chosen tool", MEASURES[m]),
                y_label: ["ln|Π^U|", "task error", "|Δ task error| under ΔT"][m].into(),
                groups: (0..RULES.len())
                    .map(|r| {
                        (
                            SHORT[r].to_string(),
                            COLOURS[r],
                            e.statistics.chosen[m][r]
                                .iter()
                                .flatten()
                                .copied()
                                .collect(),
                        )
                    })
                    .collect(),
            })
        })
        .collect();
    let empty = |p: &Panel| matches!(p, Panel::Boxes(b) if b.groups.iter().all(|g| g.2.is_empty()));
    if panels.iter().any(empty) {
        return Ok(None);
    }
    save(dir, "fig7_benchmark.svg", &panels, (440, 440)).map(Some)
}
