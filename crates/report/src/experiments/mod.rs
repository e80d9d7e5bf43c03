//! `toolconf reproduce`: every experiment of the paper's "Results" section, each written as a CSV
//! of raw data, an SVG figure and a report section with the claim, the statistics and a verdict.
//!
//! # Plan, seeds and independence
//!
//! [`Plan::paper`] holds the paper's counts (300 tools for Fig. 2, 100 for Fig. 4, 25 trials of 5
//! tools for Fig. 6, 50 trials of 10 tools for Fig. 7, ...); [`Plan::quick`] smaller ones for tests.
//! One master seed names a whole run. Every random stream is derived from it and a label with
//! [`derive_seed`] (`"fig2/tools"`, `"fig6/trial/3"`, `"fig4/bootstrap/position"`, ...), so each
//! experiment is independent of the others and of the order they run in, and each trial of a
//! decision experiment is independent of how many trials there are (the quick run's trials are
//! the first trials of the full run).
//!
//! # Determinism and interruption
//!
//! Tools are drawn before any parallel work; episodes run on rayon in ordered chunks
//! ([`batch::map_ordered`]) and each chunk's rows are appended in input order, one `write_all`
//! per row ([`csv::CsvWriter`]), into a temporary file renamed over the CSV when the experiment
//! has finished it. The files are therefore byte-identical whatever the thread count, and an
//! interrupted run keeps the file that was there. Figures and the report are written whole
//! (`.X.*.partial`, then renamed: [`toolconf_files::file`]).
//!
//! # Extending
//!
//! A new figure is a type implementing [`Experiment`] plus one line in [`experiments`]; a new
//! decision rule (for instance an MPC baseline J*) is one more entry of
//! [`objectives::decision_rules`], which the selection experiments (Figs. 6 and 7) iterate over.

pub mod batch;
mod exact_plant;
mod fig2_confidence_vs_error;
mod fig3_trajectories;
mod fig4_perturbation_change;
mod fig5_perturbation_sweep;
mod fig6_selection_grid;
mod fig7_benchmark;
pub(crate) mod figure_parts;
mod mpc_comparison;
pub mod objectives;
pub mod plot;
pub mod report;
pub mod verdict;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use indicatif::ProgressBar;

pub use report::{Block, Outcome, Section, Verdict};
use toolconf_files::csv::CsvWriter;
use toolconf_model::closed_loop::{EpisodeOptions, Plant};

/// How many tools, trials and resamples each experiment uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// `true` for the reduced counts of [`Plan::quick`].
    pub quick: bool,
    /// Fig. 2: random tools, each run on all three tasks (paper: 300).
    pub fig2_tools: usize,
    /// Fig. 3: the sample the highest- and lowest-confidence tools are picked from (task 1).
    pub fig3_sample: usize,
    /// Fig. 4: random tools, tasks 1 and 2 (paper: 100).
    pub fig4_tools: usize,
    /// Fig. 5: random tools for the perturbation sweep (velocity task; the paper gives no count).
    pub fig5_tools: usize,
    /// Fig. 5: the constant perturbations ΔT [N m] (paper: −1.0 … 1.0 in steps of 0.2).
    pub fig5_perturbations: Vec<f64>,
    /// Fig. 6: trials and tools per trial (paper: 25 × 5).
    pub fig6_trials: usize,
    pub fig6_tools: usize,
    /// Fig. 7: trials and tools per trial (paper: 50 × 10).
    pub fig7_trials: usize,
    pub fig7_tools: usize,
    /// The perturbation of Figs. 3, 4 and 7 [N m] (paper: −0.8).
    pub perturbation: f64,
    /// Bootstrap resamples per Spearman interval.
    pub bootstrap_resamples: usize,
    /// Confidence level of the bootstrap intervals.
    pub level: f64,
    /// Significance level of the paired tests.
    pub alpha: f64,
    /// Also run the MPC baseline: its J* ranking in Fig. 7 and the AIC-against-MPC section.
    pub mpc: bool,
    /// Tools of the AIC-against-MPC comparison (each on 3 tasks, 2 perturbations, 2 controllers).
    pub mpc_tools: usize,
}

impl Plan {
    /// The paper's counts.
    pub fn paper() -> Self {
        Self {
            quick: false,
            fig2_tools: 300,
            fig3_sample: 20,
            fig4_tools: 100,
            fig5_tools: 100,
            fig5_perturbations: (-5..=5).map(|k| f64::from(k) / 5.0).collect(),
            fig6_trials: 25,
            fig6_tools: 5,
            fig7_trials: 50,
            fig7_tools: 10,
            perturbation: -0.8,
            bootstrap_resamples: 2000,
            level: 0.95,
            alpha: 0.05,
            mpc: false,
            mpc_tools: 20,
        }
    }

    /// Small counts for tests: every experiment and every code path, in a few seconds.
    pub fn quick() -> Self {
        Self {
            quick: true,
            fig2_tools: 8,
            fig3_sample: 6,
            fig4_tools: 10,
            fig5_tools: 6,
            fig6_trials: 4,
            fig6_tools: 3,
            fig7_trials: 6,
            fig7_tools: 4,
            bootstrap_resamples: 200,
            mpc_tools: 1,
            ..Self::paper()
        }
    }
}

/// The sub-seed of `label` under `master` (the evaluation's, so that both name a stream alike).
pub use toolconf::evaluation::derive_seed;

/// Why a reproduction stopped (failed episodes and statistics do not stop it).
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot draw {path}: {reason}")]
    Plot { path: PathBuf, reason: String },
    #[error("experiment {id} cannot run: {reason}")]
    Experiment { id: &'static str, reason: String },
    #[error("unknown experiment {0:?}; known: {known}", known = experiment_ids().join(", "))]
    UnknownExperiment(String),
}

impl From<toolconf_files::WriteError> for ReproduceError {
    fn from(e: toolconf_files::WriteError) -> Self {
        ReproduceError::Io {
            path: e.path,
            source: e.source,
        }
    }
}

impl ReproduceError {
    pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReproduceError + '_ {
        move |source| ReproduceError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What an experiment gets to run with.
pub struct Context<'a> {
    pub out_dir: &'a Path,
    pub seed: u64,
    pub plan: &'a Plan,
    /// The paper's episode settings (ode45 tolerances, 5 s, dt 0.05, ΔT = 0).
    pub options: EpisodeOptions,
    /// The equations of motion the tools are simulated on (the paper's, or the exact ones).
    pub plant: Plant,
    pub progress: &'a ProgressBar,
    /// Prefix of every file the experiment writes (empty, or e.g. `exact_plant_`).
    pub file_prefix: &'a str,
}

impl Context<'_> {
    /// The sub-seed of `"<experiment id>/<stream>"`, see [`derive_seed`].
    pub fn seed_for(&self, experiment: &dyn Experiment, stream: &str) -> u64 {
        derive_seed(self.seed, &format!("{}/{stream}", experiment.id()))
    }

    pub fn path(&self, file: &str) -> PathBuf {
        self.out_dir.join(format!("{}{file}", self.file_prefix))
    }

    /// A CSV writer for `file` of the output folder ([`Context::path`]), its columns `header`.
    pub fn csv<S: AsRef<str>>(
        &self,
        file: &str,
        header: &[S],
    ) -> Result<CsvWriter, ReproduceError> {
        let header: Vec<&str> = header.iter().map(AsRef::as_ref).collect();
        Ok(CsvWriter::create(&self.path(file), &header)?)
    }

    /// The paper's options with a constant perturbation ΔT.
    pub fn perturbed(&self, perturbation: f64) -> EpisodeOptions {
        EpisodeOptions {
            perturbation,
            ..self.options
        }
    }
}

/// One figure of the Results section.
pub trait Experiment: Sync {
    /// Short id, the prefix of its files and seed labels (`"fig2"`).
    fn id(&self) -> &'static str;
    /// Section title in the report.
    fn title(&self) -> &'static str;
    /// The files it writes (removed before it runs, so none is left from an older run).
    fn outputs(&self) -> Vec<String>;
    /// Episodes it will simulate under `plan` (the progress bar's share).
    fn planned_episodes(&self, plan: &Plan) -> u64;
    /// Runs it: writes its files and returns its report section.
    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError>;
    /// Whether it runs only with the MPC baseline switched on ([`Plan::mpc`]).
    fn needs_mpc(&self) -> bool {
        false
    }
}

/// An experiment's [`Experiment::id`], [`Experiment::title`] and [`Experiment::outputs`],
/// inside its `impl Experiment`: `described!("fig2", "Fig. 2: ...", [CSV, SVG]);`.
macro_rules! described {
    ($id:literal, $title:literal, [$($file:expr),* $(,)?]) => {
        fn id(&self) -> &'static str {
            $id
        }

        fn title(&self) -> &'static str {
            $title
        }

        fn outputs(&self) -> Vec<String> {
            vec![$($file.into()),*]
        }
    };
}
pub(crate) use described;

/// The registry: every experiment, in report order.
pub fn experiments() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(fig2_confidence_vs_error::Fig2),
        Box::new(fig3_trajectories::Fig3),
        Box::new(fig4_perturbation_change::Fig4),
        Box::new(fig5_perturbation_sweep::Fig5),
        Box::new(fig6_selection_grid::Fig6),
        Box::new(fig7_benchmark::Fig7 { with_mpc: true }),
        Box::new(exact_plant::OnExactPlant {
            inner: Box::new(fig2_confidence_vs_error::Fig2),
            id: "fig2_exact",
            title: "Exact plant: Fig. 2, confidence and task error (C1)",
        }),
        Box::new(exact_plant::OnExactPlant {
            inner: Box::new(fig4_perturbation_change::Fig4),
            id: "fig4_exact",
            title: "Exact plant: Fig. 4, confidence and sensitivity to a perturbation (C2)",
        }),
        Box::new(exact_plant::OnExactPlant {
            inner: Box::new(fig7_benchmark::Fig7 { with_mpc: false }),
            id: "fig7_exact",
            title: "Exact plant: Fig. 7, benchmarking tool selection (C4)",
        }),
        Box::new(mpc_comparison::MpcComparison),
    ]
}

pub fn experiment_ids() -> Vec<&'static str> {
    experiments().iter().map(|e| e.id()).collect()
}

/// A reproduction to run.
#[derive(Debug, Clone)]
pub struct Config {
    pub out_dir: PathBuf,
    pub seed: u64,
    pub plan: Plan,
    /// Run only these experiment ids (all if `None`).
    pub only: Option<Vec<String>>,
    /// Draw a progress bar on stderr.
    pub progress: bool,
    /// The command line, quoted in the report.
    pub command: String,
    /// The integration method of every episode ([`toolconf_integrators::Method::Fast`] from the
    /// command line; [`toolconf_integrators::Method::Explicit`] is the paper's ode45).
    pub method: toolconf_integrators::Method,
}

/// Timing of one experiment.
#[derive(Debug, Clone)]
pub struct Timing {
    pub id: &'static str,
    pub wall: Duration,
    pub episodes: u64,
    pub rhs_evals: u64,
}

/// What a finished reproduction produced.
#[derive(Debug, Clone)]
pub struct Summary {
    pub report_md: PathBuf,
    pub report_html: PathBuf,
    pub sections: Vec<Section>,
    pub timings: Vec<Timing>,
    pub wall: Duration,
    pub threads: usize,
}

impl Summary {
    pub fn episodes(&self) -> u64 {
        self.timings.iter().map(|t| t.episodes).sum()
    }
}

/// The experiments `config` selects, in report order.
fn select<'a>(
    all: &'a [Box<dyn Experiment>],
    config: &Config,
) -> Result<Vec<&'a dyn Experiment>, ReproduceError> {
    Ok(match &config.only {
        None => all
            .iter()
            .filter(|e| config.plan.mpc || !e.needs_mpc())
            .map(|e| e.as_ref())
            .collect(),
        Some(ids) => {
            for id in ids {
                if !all.iter().any(|e| e.id() == id) {
                    return Err(ReproduceError::UnknownExperiment(id.clone()));
                }
            }
            all.iter()
                .filter(|e| ids.iter().any(|id| id == e.id()))
                .map(|e| e.as_ref())
                .collect()
        }
    })
}

/// The files [`reproduce`] writes into its folder under `config`: every selected experiment's,
/// and the report (checked against each other before any work:
/// [`toolconf_files::run_files`]).
pub fn output_files(config: &Config) -> Result<Vec<String>, ReproduceError> {
    let all = experiments();
    let mut files: Vec<String> = select(&all, config)?
        .iter()
        .flat_map(|e| e.outputs())
        .collect();
    files.extend(["report.md".into(), "report.html".into()]);
    Ok(files)
}

/// Runs the selected experiments one after the other (each in parallel inside), then writes
/// `report.md` and `report.html`.
pub fn reproduce(config: &Config) -> Result<Summary, ReproduceError> {
    let all = experiments();
    let selected = select(&all, config)?;
    let out = config.out_dir.as_path();
    toolconf_files::file::create_folder(out).map_err(ReproduceError::io(out))?;
    let report_md = out.join("report.md");
    let report_html = out.join("report.html");
    // A report left from an older run would describe other data than an interrupted run leaves.
    for stale in [&report_md, &report_html] {
        remove_if_present(stale)?;
    }

    let total: u64 = selected
        .iter()
        .map(|e| e.planned_episodes(&config.plan))
        .sum();
    let progress = crate::progress::episodes(config.progress, total);
    let ctx = Context {
        out_dir: out,
        seed: config.seed,
        plan: &config.plan,
        options: {
            let mut o = EpisodeOptions::default();
            o.integrator.method = config.method;
            o
        },
        plant: Plant::Paper,
        progress: &progress,
        file_prefix: "",
    };
    let start = Instant::now();
    let mut sections = Vec::new();
    let mut timings = Vec::new();
    for experiment in selected {
        for file in experiment.outputs() {
            remove_if_present(&out.join(file))?;
        }
        progress.set_message(experiment.id());
        let t0 = Instant::now();
        let section = experiment.run(&ctx)?;
        timings.push(Timing {
            id: experiment.id(),
            wall: t0.elapsed(),
            episodes: section.episodes,
            rhs_evals: section.rhs_evals,
        });
        sections.push(section);
    }
    progress.finish_and_clear();
    let summary = Summary {
        report_md,
        report_html,
        sections,
        timings,
        wall: start.elapsed(),
        threads: rayon::current_num_threads(),
    };
    let meta = report::RunInfo {
        command: &config.command,
        seed: config.seed,
        plan: &config.plan,
        timings: &summary.timings,
        wall: summary.wall,
        threads: summary.threads,
        episode: &ctx.options,
    };
    let doc = report::document(&meta, &summary.sections);
    write_atomically(&summary.report_md, &report::to_markdown(&doc))?;
    write_atomically(&summary.report_html, &report::to_html(&doc))?;
    Ok(summary)
}

/// Removes an earlier run's regular file at `path`; a link, a device or a FIFO is the user's, and
/// stays (it is written through, or in place, by the output rule).
pub(crate) fn remove_if_present(path: &Path) -> Result<(), ReproduceError> {
    if !std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file()) {
        return Ok(());
    }
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(ReproduceError::io(path)(e)),
        _ => Ok(()),
    }
}

/// Writes a whole file or nothing (the runtime's [`toolconf_files::write_atomically`]).
pub fn write_atomically(path: &Path, contents: &str) -> Result<(), ReproduceError> {
    Ok(toolconf_files::write_atomically(path, contents)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_seeds_differ_by_label_and_master() {
        let a = derive_seed(0, "fig2/tools");
        assert_eq!(a, derive_seed(0, "fig2/tools"));
        assert_ne!(a, derive_seed(1, "fig2/tools"));
        assert_ne!(a, derive_seed(0, "fig4/tools"));
        assert_ne!(
            derive_seed(0, "fig6/trial/1"),
            derive_seed(0, "fig6/trial/2")
        );
    }

    #[test]
    fn paper_sweep_is_minus_one_to_one_in_fifths() {
        let p = Plan::paper().fig5_perturbations;
        assert_eq!(p.len(), 11);
        assert_eq!((p[0], p[5], p[10]), (-1.0, 0.0, 1.0));
        assert_eq!(p[1], -0.8);
    }

    #[test]
    fn registry_ids_are_unique() {
        let mut ids = experiment_ids();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), experiments().len());
    }
}
