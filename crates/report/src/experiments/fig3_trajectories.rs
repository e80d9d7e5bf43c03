//! Fig. 3 (part of claim C2): the highest- and the lowest-confidence tool of a small random sample
//! on task 1, θ2 over time against the goal θ2^g = π/6, without and with a constant perturbation.
//!
//! Seed: the sample from `"fig3/tools"`. Confidence needs no simulation, so only the two chosen
//! tools are simulated (four episodes, trajectories recorded).

use toolconf::select::draw_tools;
use toolconf_model::closed_loop::{Metrics, Trajectory};
use toolconf_model::confidence::control_confidence;
use toolconf_model::{Arm, Task, TaskKind, Term};

use super::batch::map_ordered;
use super::figure_parts::{arm_cells, columns, dt_label, ARM_COLUMNS, TOOL_COLUMNS};
use super::plot::{self, Colour, Legend, Panel, Series, XyPanel};
use super::report::{Block, Outcome, Section, Verdict};
use super::verdict::num;
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf_files::csv::{Cell, CsvWriter};

pub struct Fig3;

const TOOLS_CSV: &str = "fig3_tools.csv";
const CSV: &str = "fig3_trajectories.csv";
const SVG: &str = "fig3_trajectories.svg";
pub const TOOLS_HEADER: [&str; 7] = columns(&[&TOOL_COLUMNS, &["role"]]);
pub const HEADER: [&str; 12] = [
    "role",
    "tool",
    "logdet",
    "perturbation",
    "t",
    "theta1",
    "theta2",
    "theta1_dot",
    "theta2_dot",
    "u1",
    "u2",
    "error",
];
/// θ2 counts as settled once it stays within this fraction of its initial distance to the goal.
const BAND: f64 = 0.05;

/// One of the four runs.
struct Run {
    role: &'static str,
    tool: usize,
    logdet: f64,
    perturbation: f64,
    result: Result<(Metrics, Trajectory), String>,
}

fn traj(r: &Run) -> Option<&Trajectory> {
    r.result.as_ref().ok().map(|x| &x.1)
}

/// Time from which |θ2 − goal| stays within the band for the rest of the episode.
fn settling_time(tr: &Trajectory, goal: f64) -> Option<f64> {
    let band = BAND * (tr.of(Term::Theta).first()?[1] - goal).abs();
    let last_outside = tr
        .of(Term::Theta)
        .iter()
        .rposition(|th| (th[1] - goal).abs() > band);
    match last_outside {
        None => tr.t.first().copied(),
        Some(k) if k + 1 < tr.t.len() => Some(tr.t[k + 1]),
        Some(_) => None,
    }
}

impl Experiment for Fig3 {
    described!(
        "fig3",
        "Fig. 3: high- and low-confidence tool under a perturbation (C2)",
        [TOOLS_CSV, CSV, SVG]
    );

    fn planned_episodes(&self, _plan: &Plan) -> u64 {
        4
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let task = Task::paper(TaskKind::Position);
        let goal = task.goal(Term::Theta)[1];
        let tools = draw_tools(plan.fig3_sample, ctx.seed_for(self, "tools"));
        let logdets: Vec<Option<f64>> = tools
            .iter()
            .map(|a| control_confidence(a, &task).ok().map(|c| c.logdet))
            .collect();
        let (Some(high), Some(low)) = (
            extreme(&logdets, |a, b| a > b),
            extreme(&logdets, |a, b| a < b),
        ) else {
            return Err(ReproduceError::Experiment {
                id: self.id(),
                reason: "no tool of the sample has a control confidence".into(),
            });
        };
        write_sample(ctx, &tools, &logdets, high.0, low.0)?;
        let runs = Runs {
            runs: simulate_pair(ctx, &tools, &task, high, low)?,
            goal,
            perturbation: plan.perturbation,
        };
        let svg = runs.figure(ctx, tools.len())?;
        let failed = runs.runs.iter().filter(|r| r.result.is_err()).count();
        let blocks = vec![
            Block::p(format!(
                "{} random tools on task 1 (position); the one with the highest ln|Π^U| (tool {}, \
                 {}) and the one with the lowest (tool {}, {}) are each simulated without \
                 perturbation and with a constant ΔT = {} N m on both joints. Settling time: the \
                 time from which |θ2 − π/6| stays within {}% of its initial distance 2π/3 (i.e. \
                 {} rad) until t = 5 s.",
                tools.len(),
                high.0,
                num(high.1),
                low.0,
                num(low.1),
                dt_label(plan.perturbation),
                BAND * 100.0,
                num(BAND * 2.0 * std::f64::consts::FRAC_PI_3),
            )),
            Block::p(format!(
                "Data: `{TOOLS_CSV}` (the sample, columns {}, logdet, role), `{CSV}` (the four \
                 trajectories on the 0.05 s grid; {failed} failed run(s)), `{SVG}`.",
                ARM_COLUMNS.join(", ")
            )),
            Block::table(&TABLE_HEADER, runs.table_rows()),
            Block::Figure {
                file: SVG.into(),
                caption: "θ2 over time for the highest-confidence tool (yellow: ΔT = 0, purple: \
                          perturbed) and the lowest-confidence tool (red: ΔT = 0, blue: \
                          perturbed); the goal π/6 dotted in black. Compare with the paper's \
                          Fig. 3."
                    .into(),
                svg,
            },
            Block::Verdict(runs.settling_verdict()),
            Block::Verdict(runs.variability_verdict()),
        ];
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes: runs.runs.len() as u64,
            rhs_evals: runs
                .runs
                .iter()
                .filter_map(|r| r.result.as_ref().ok())
                .map(|(m, _)| m.rhs_evals as u64)
                .sum(),
        })
    }
}

const TABLE_HEADER: [&str; 7] = [
    "run",
    "ln|Π^U|",
    "ΔT [N m]",
    "task error",
    "settling time",
    "final |θ2 − π/6| [rad]",
    "max |θ2 − θ2 (ΔT = 0)| [rad]",
];

/// (tool, ln|Π^U|) of the tool whose confidence is `better` than every other's (the first on ties).
fn extreme(logdets: &[Option<f64>], better: fn(f64, f64) -> bool) -> Option<(usize, f64)> {
    logdets
        .iter()
        .enumerate()
        .filter_map(|(i, l)| Some((i, (*l)?)))
        .fold(None, |best: Option<(usize, f64)>, (i, l)| match best {
            Some((_, b)) if !better(l, b) => best,
            _ => Some((i, l)),
        })
}

/// The sample with each tool's confidence and its role (high, low or none), to `TOOLS_CSV`.
fn write_sample(
    ctx: &Context,
    tools: &[Arm],
    logdets: &[Option<f64>],
    high: usize,
    low: usize,
) -> Result<(), ReproduceError> {
    let mut tools_csv = ctx.csv(TOOLS_CSV, &TOOLS_HEADER)?;
    for (i, arm) in tools.iter().enumerate() {
        let role = if i == high {
            "high"
        } else if i == low {
            "low"
        } else {
            ""
        };
        let mut row = vec![Cell::from(i)];
        row.extend(arm_cells(arm));
        row.extend([Cell::from(logdets[i]), Cell::from(role)]);
        tools_csv.row(row)?;
    }
    tools_csv.finish()?;
    Ok(())
}

/// The two tools without and with the perturbation, trajectories recorded and written to `CSV`
/// as each run finishes.
fn simulate_pair(
    ctx: &Context,
    tools: &[Arm],
    task: &Task,
    high: (usize, f64),
    low: (usize, f64),
) -> Result<Vec<Run>, ReproduceError> {
    let items: Vec<(&'static str, (usize, f64), f64)> = [("high", high), ("low", low)]
        .into_iter()
        .flat_map(|(role, tool)| [0.0, ctx.plan.perturbation].map(|dt| (role, tool, dt)))
        .collect();
    let mut csv = ctx.csv(CSV, &HEADER)?;
    let runs = map_ordered(
        &items,
        ctx.progress,
        1,
        |&(role, (tool, logdet), dt)| {
            let mut options = ctx.perturbed(dt);
            options.record_trajectory = true;
            let result = (ctx.plant)
                .simulate(&tools[tool], task, &options)
                .map(|e| (e.metrics, e.trajectory.expect("trajectory was requested")))
                .map_err(|e| e.to_string());
            Run {
                role,
                tool,
                logdet,
                perturbation: dt,
                result,
            }
        },
        |_, run| write_run(&mut csv, run),
    )?;
    csv.finish()?;
    Ok(runs)
}

/// One run's trajectory rows (or its error).
fn write_run(csv: &mut CsvWriter, run: &Run) -> Result<(), ReproduceError> {
    let lead = [
        Cell::from(run.role),
        Cell::from(run.tool),
        Cell::from(run.logdet),
        Cell::from(run.perturbation),
    ];
    match &run.result {
        Ok((_, tr)) => {
            for k in 0..tr.t.len() {
                let mut row = lead.to_vec();
                row.extend(
                    [
                        tr.t[k],
                        tr.of(Term::Theta)[k][0],
                        tr.of(Term::Theta)[k][1],
                        tr.of(Term::ThetaDot)[k][0],
                        tr.of(Term::ThetaDot)[k][1],
                        tr.of(Term::U)[k][0],
                        tr.of(Term::U)[k][1],
                    ]
                    .map(Cell::from),
                );
                row.push(Cell::Empty);
                csv.row(row)?;
            }
            Ok(())
        }
        Err(e) => {
            let mut row = lead.to_vec();
            row.extend(std::iter::repeat(Cell::Empty).take(7));
            row.push(Cell::from(e.as_str()));
            Ok(csv.row(row)?)
        }
    }
}

/// The four runs and what the report says of them.
struct Runs {
    runs: Vec<Run>,
    /// θ2^g.
    goal: f64,
    /// The perturbed runs' ΔT.
    perturbation: f64,
}

impl Runs {
    fn find(&self, role: &str, dt: f64) -> &Run {
        self.runs
            .iter()
            .find(|r| r.role == role && r.perturbation == dt)
            .expect("all four runs exist")
    }

    fn settle(&self, r: &Run) -> Option<f64> {
        traj(r).and_then(|tr| settling_time(tr, self.goal))
    }

    fn settle_text(&self, r: &Run) -> String {
        self.settle(r)
            .map_or("not within 5 s".into(), |t| format!("{t:.2} s"))
    }

    fn final_error(&self, r: &Run) -> Option<f64> {
        traj(r).and_then(|tr| {
            tr.of(Term::Theta)
                .last()
                .map(|th| (th[1] - self.goal).abs())
        })
    }

    /// The largest |θ2 − θ2 of the same tool without perturbation|.
    fn deviation(&self, r: &Run) -> Option<f64> {
        let base = traj(self.find(r.role, 0.0))?;
        let tr = traj(r)?;
        Some(
            tr.of(Term::Theta)
                .iter()
                .zip(base.of(Term::Theta))
                .map(|(a, b)| (a[1] - b[1]).abs())
                .fold(0.0, f64::max),
        )
    }

    /// |task error with ΔT − task error without| of one tool.
    fn change(&self, role: &str) -> Option<f64> {
        let error = |dt| Some(self.find(role, dt).result.as_ref().ok()?.0.task_error);
        Some((error(self.perturbation)? - error(0.0)?).abs())
    }

    fn table_rows(&self) -> Vec<Vec<String>> {
        self.runs
            .iter()
            .map(|r| {
                let mut row = vec![
                    format!("{} (tool {})", r.role, r.tool),
                    num(r.logdet),
                    dt_label(r.perturbation),
                ];
                match &r.result {
                    Ok((m, _)) => row.extend([
                        num(m.task_error),
                        self.settle(r)
                            .map_or("not within 5 s".into(), |t| format!("{t:.2}")),
                        self.final_error(r).map_or("-".into(), num),
                        if r.perturbation == 0.0 {
                            "-".into()
                        } else {
                            self.deviation(r).map_or("-".into(), num)
                        },
                    ]),
                    Err(e) => {
                        row.extend([format!("failed: {e}"), "-".into(), "-".into(), "-".into()])
                    }
                }
                row
            })
            .collect()
    }

    /// θ2 over time of the four runs, with the goal.
    fn figure(&self, ctx: &Context, sample: usize) -> Result<String, ReproduceError> {
        let colour = |role: &str, dt: f64| match (role, dt == 0.0) {
            ("high", true) => Colour(230, 159, 0),
            ("high", false) => Colour(120, 60, 160),
            (_, true) => Colour(200, 30, 30),
            (_, false) => Colour(30, 80, 200),
        };
        let mut lines: Vec<Series> = self
            .runs
            .iter()
            .filter_map(|r| {
                let tr = traj(r)?;
                let s = Series::new(
                    format!(
                        "{} confidence (ln|Π^U| = {}), ΔT = {}",
                        r.role,
                        num(r.logdet),
                        dt_label(r.perturbation)
                    ),
                    colour(r.role, r.perturbation),
                    tr.t.iter()
                        .zip(tr.of(Term::Theta))
                        .map(|(t, th)| (*t, th[1]))
                        .collect(),
                );
                Some(if r.perturbation == 0.0 { s } else { s.dashed() })
            })
            .collect();
        lines.push(
            Series::new(
                "goal θ2 = π/6",
                Colour(0, 0, 0),
                vec![(0.0, self.goal), (ctx.options.t_end, self.goal)],
            )
            .dashed(),
        );
        plot::save(
            &ctx.path(SVG),
            &[Panel::Xy(XyPanel {
                title: format!(
                    "Task 1: θ2 of the highest- and lowest-confidence of {sample} tools"
                ),
                x_label: "time t [s]".into(),
                y_label: "θ2 [rad]".into(),
                dots: vec![],
                lines,
                log_y: false,
                legend: Legend::LowerRight,
                headroom: 0.0,
            })],
            (860, 480),
        )
    }

    /// Whether the high-confidence tool settles first (`None` if either run failed).
    fn high_settles_first(&self, dt: f64) -> Option<bool> {
        let (h, l) = (self.find("high", dt), self.find("low", dt));
        h.result.as_ref().ok()?;
        l.result.as_ref().ok()?;
        match (self.settle(h), self.settle(l)) {
            (Some(a), Some(b)) => Some(a < b),
            (Some(_), None) => Some(true),
            (None, _) => Some(false),
        }
    }

    fn settling_verdict(&self) -> Verdict {
        let dt = self.perturbation;
        let outcome = match (self.high_settles_first(0.0), self.high_settles_first(dt)) {
            (Some(true), Some(true)) => Outcome::Holds,
            (Some(a), Some(b)) if a || b => Outcome::Partly,
            (Some(_), Some(_)) => Outcome::DoesNotHold,
            _ => Outcome::NotJudged,
        };
        Verdict {
            claim: "C2 (Fig. 3), settling".into(),
            statement: "\"High confident tool settles near the goal θ2^g faster than the low \
                        confident tool.\""
                .into(),
            outcome,
            evidence: format!(
                "settling time without perturbation: high {}, low {}; with ΔT = {}: high {}, \
                 low {}.",
                self.settle_text(self.find("high", 0.0)),
                self.settle_text(self.find("low", 0.0)),
                dt_label(dt),
                self.settle_text(self.find("high", dt)),
                self.settle_text(self.find("low", dt))
            ),
            rule: "holds if the high-confidence tool settles earlier both without and with \
                   the perturbation (a tool that never settles counts as slower), partly \
                   holds if in one of the two, does not hold if in neither. One pair of \
                   tools is an illustration, not a statistic; Fig. 4 tests the trend."
                .into(),
        }
    }

    fn variability_verdict(&self) -> Verdict {
        let (ch, cl) = (self.change("high"), self.change("low"));
        let dt = self.perturbation;
        let (dh, dl) = (
            self.deviation(self.find("high", dt)),
            self.deviation(self.find("low", dt)),
        );
        let outcome = match (ch.zip(cl), dh.zip(dl)) {
            (Some((a, b)), Some((c, d))) => match (b > a, d > c) {
                (true, true) => Outcome::Holds,
                (false, false) => Outcome::DoesNotHold,
                _ => Outcome::Partly,
            },
            _ => Outcome::NotJudged,
        };
        Verdict {
            claim: "C2 (Fig. 3), variability".into(),
            statement: "\"The low-confident tool shows more variability in performance than \
                        the high-confident tool under a constant control perturbation of \
                        ΔT = −0.8 N m.\""
                .into(),
            outcome,
            evidence: format!(
                "|change of task error| under the perturbation: high {}, low {}; largest \
                 deviation of θ2 from its unperturbed path: high {} rad, low {} rad.",
                ch.map_or("-".into(), num),
                cl.map_or("-".into(), num),
                dh.map_or("-".into(), num),
                dl.map_or("-".into(), num)
            ),
            rule: "holds if the low-confidence tool has both the larger |change of task \
                   error| and the larger largest deviation of θ2, partly holds if one of the \
                   two, does not hold if neither."
                .into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settling_time_is_when_the_band_is_entered_for_good() {
        let theta = |v: f64| toolconf_model::Vector2::new(0.0, v);
        let mut tr = Trajectory {
            t: vec![0.0, 1.0, 2.0, 3.0],
            ..Trajectory::default()
        };
        tr.terms[Term::Theta.index()] = vec![theta(-1.0), theta(0.01), theta(0.2), theta(0.02)];
        // Band: 5 % of 1.0 around 0.
        assert_eq!(settling_time(&tr, 0.0), Some(3.0));
        let mut never = Trajectory {
            t: vec![0.0, 1.0],
            ..Trajectory::default()
        };
        never.terms[Term::Theta.index()] = vec![theta(-1.0), theta(-0.5)];
        assert_eq!(settling_time(&never, 0.0), None);
    }
}
