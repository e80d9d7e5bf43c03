//! `toolconf reproduce --model`: the paper's evaluation ([`toolconf::evaluation`]) written as the
//! paper's reproduction is: a CSV per figure's data, an SVG per figure, and `report.md` and
//! `report.html` (figures inline), under the same file names.

mod document;
mod figures;

use std::path::{Path, PathBuf};
use std::time::Duration;

use toolconf::evaluation::tables::tables;
use toolconf::evaluation::Evaluation;
use toolconf_files::csv::CsvWriter;

use crate::experiments::{remove_if_present, report, write_atomically, ReproduceError};

/// Every file an evaluation writes into its folder.
pub const FILES: [&str; 16] = [
    "fig2_confidence_vs_error.csv",
    "fig2_confidence_vs_error.svg",
    "fig3_tools.csv",
    "fig3_trajectories.csv",
    "fig3_trajectories.svg",
    "fig4_perturbation_change.csv",
    "fig4_perturbation_change.svg",
    "fig5_perturbation_sweep.csv",
    "fig5_perturbation_sweep.svg",
    "fig6_selection_grid.csv",
    "fig6_selection_grid.svg",
    "fig7_benchmark.csv",
    "fig7_benchmark.svg",
    "fig7_choices.csv",
    "report.md",
    "report.html",
];

/// Facts about the run for the report.
pub struct RunInfo<'a> {
    pub command: &'a str,
    /// The integration method, as `--method` names it in words.
    pub method: &'a str,
    pub wall: Duration,
    pub threads: usize,
}

/// Writes the evaluation's CSVs, figures and report into `dir` (created if missing); returns the
/// paths of `report.md` and `report.html`. Files of an earlier run that this one does not write
/// (a figure without data) are removed first, so none describes other data.
pub fn write(dir: &Path, e: &Evaluation, info: &RunInfo) -> Result<[PathBuf; 2], ReproduceError> {
    toolconf_files::file::create_folder(dir).map_err(ReproduceError::io(dir))?;
    for file in FILES {
        remove_if_present(&dir.join(file))?;
    }
    for table in tables(e) {
        let header: Vec<&str> = table.header.iter().map(String::as_str).collect();
        let mut csv = CsvWriter::create(&dir.join(format!("{}.csv", table.name)), &header)?;
        for row in table.rows {
            csv.row(row)?;
        }
        csv.finish()?;
    }
    let figures = [
        figures::fig2(dir, e)?,
        figures::fig3(dir, e)?,
        figures::fig4(dir, e)?,
        figures::fig5(dir, e)?,
        figures::fig6(dir, e)?,
        figures::fig7(dir, e)?,
    ];
    let doc = document::document(e, info, &figures);
    let (md, html) = (dir.join("report.md"), dir.join("report.html"));
    write_atomically(&md, &report::to_markdown(&doc))?;
    write_atomically(&html, &report::to_html(&doc))?;
    Ok([md, html])
}
