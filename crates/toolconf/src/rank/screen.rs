//! The cheap stage: every tool of a file read, checked against the task and given its control
//! confidence (and, when the screen is by prediction, its predicted cost), the [`Screen`]
//! keeping what will be simulated.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use std::path::Path;

use rayon::prelude::*;

use super::{ModelTasks, ScreenBy};
use toolconf_model::inputs::tools_file::{read_tools, ToolFileError, ToolRow};
use toolconf_model::prediction::{Prediction, PredictionError};
use toolconf_model::Error;

/// A tool that passed the cheap stage, with its confidence and, when the screen is by
/// prediction ([`ScreenBy::Predicted`]), its predicted cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    pub row: ToolRow,
    pub logdet: Result<f64, Error>,
    pub prediction: Option<Result<Prediction, PredictionError>>,
}

/// A candidate in the validation sample's heap (ordered by its key and row alone).
struct SampledCandidate(Candidate);

impl PartialEq for SampledCandidate {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Eq for SampledCandidate {}

impl PartialOrd for SampledCandidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for SampledCandidate {
    fn cmp(&self, _: &Self) -> Ordering {
        Ordering::Equal
    }
}

/// A candidate in the screen's heap, ordered by its key ([`ScreenBy::key`]); on a tie the later
/// row is less.
struct Screened {
    key: f64,
    candidate: Candidate,
}

impl Ord for Screened {
    fn cmp(&self, other: &Self) -> Ordering {
        self.key
            .total_cmp(&other.key)
            .then(other.candidate.row.row.cmp(&self.candidate.row.row))
    }
}

impl PartialOrd for Screened {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Screened {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Screened {}

/// The cheap stage over a stream of tools: keeps every tool, or only the `k` best by its
/// criterion ([`ScreenBy`]: by default the largest ln|Π^U|; the earlier row on ties) in O(k)
/// memory. A tool without a confidence is never kept by a screen.
pub struct Screen {
    limit: Option<usize>,
    by: ScreenBy,
    heap: BinaryHeap<Reverse<Screened>>,
    all: Vec<Candidate>,
    /// The validation sample's size ([`Screen::with_validation`]) and its tools, by key.
    validation: usize,
    sample: BinaryHeap<(u64, usize, SampledCandidate)>,
    /// Tools seen.
    pub read: usize,
    /// Tools whose Π^U is not positive definite (never kept by a screen), and the first reason.
    pub without_confidence: usize,
    pub first_confidence_error: Option<String>,
    /// Tools with a confidence but no prediction (a screen by prediction ranks them last), and
    /// the first reason.
    pub without_prediction: usize,
    pub first_prediction_error: Option<String>,
}

impl Screen {
    /// `limit`: keep only this many (the `--screen K`), or every tool.
    pub fn new(limit: Option<usize>) -> Self {
        Self {
            limit,
            by: ScreenBy::Confidence,
            heap: BinaryHeap::new(),
            all: Vec::new(),
            validation: 0,
            sample: BinaryHeap::new(),
            read: 0,
            without_confidence: 0,
            first_confidence_error: None,
            without_prediction: 0,
            first_prediction_error: None,
        }
    }

    /// A screen keeping the `limit` best tools by `by`.
    pub fn by(limit: Option<usize>, by: ScreenBy) -> Self {
        Self {
            by,
            ..Self::new(limit)
        }
    }

    /// The screen's criterion.
    pub fn criterion(&self) -> ScreenBy {
        self.by
    }

    /// A screen that also keeps a uniform sample of `validation` tools with a confidence, the
    /// rows whose [`sample_key`](crate::evaluation::check::sample_key) is smallest: what `rank
    /// --screen` simulates alongside to check that confidence predicts the task error.
    pub fn with_validation(limit: Option<usize>, validation: usize) -> Self {
        Self {
            validation,
            ..Self::new(limit)
        }
    }

    /// The validation sample, in row order.
    pub fn validation_sample(&self) -> Vec<Candidate> {
        let mut sample: Vec<Candidate> = self.sample.iter().map(|s| s.2 .0.clone()).collect();
        sample.sort_by_key(|c| c.row.row);
        sample
    }

    fn offer_to_sample(&mut self, candidate: &Candidate) {
        if self.validation == 0 || candidate.logdet.is_err() {
            return;
        }
        let row = candidate.row.row;
        let entry = (
            crate::evaluation::check::sample_key(row),
            row,
            SampledCandidate(candidate.clone()),
        );
        if self.sample.len() < self.validation {
            self.sample.push(entry);
        } else if self
            .sample
            .peek()
            .is_some_and(|worst| (entry.0, entry.1) < (worst.0, worst.1))
        {
            self.sample.pop();
            self.sample.push(entry);
        }
    }

    pub fn push(&mut self, candidate: Candidate) {
        self.offer_to_sample(&candidate);
        self.read += 1;
        if let Err(e) = &candidate.logdet {
            self.without_confidence += 1;
            self.first_confidence_error
                .get_or_insert_with(|| e.to_string());
        }
        if let Some(Err(e)) = &candidate.prediction {
            self.without_prediction += 1;
            self.first_prediction_error
                .get_or_insert_with(|| e.reason());
        }
        self.keep(candidate);
    }

    /// Takes in what screening another block of the same rows found, as if its rows had been
    /// pushed here: the kept tools are the most confident of both (ties: the earlier row) and
    /// the counts add up. Blocks screened apart (toolconf.dask's partitions) are absorbed in
    /// row order, so that the first reason a tool has no confidence (or no prediction) stays the
    /// first row's. The blocks' candidates carry their predictions when the screen is by
    /// prediction: the key they were kept by is the key they are kept by here.
    pub fn absorb(&mut self, block: ScreenedBlock) {
        self.read += block.read;
        self.without_confidence += block.without_confidence;
        if self.first_confidence_error.is_none() {
            self.first_confidence_error = block.first_confidence_error;
        }
        self.without_prediction += block.without_prediction;
        if self.first_prediction_error.is_none() {
            self.first_prediction_error = block.first_prediction_error;
        }
        for candidate in block.kept {
            self.keep(candidate);
        }
    }

    /// The kept tools and the counts, for a block screened apart.
    pub fn into_block(mut self) -> ScreenedBlock {
        let (read, without_confidence) = (self.read, self.without_confidence);
        let first_confidence_error = self.first_confidence_error.take();
        let without_prediction = self.without_prediction;
        let first_prediction_error = self.first_prediction_error.take();
        ScreenedBlock {
            kept: self.finish(),
            read,
            without_confidence,
            first_confidence_error,
            without_prediction,
            first_prediction_error,
        }
    }

    /// What the output says of the tools without a prediction when the screen is by prediction
    /// and some have none (`rank`'s `note:` line, the Python package's warning); else `None`.
    pub fn unpredicted_note(&self) -> Option<String> {
        unpredicted_note(
            self.by,
            self.without_prediction,
            self.first_prediction_error.as_deref(),
        )
    }

    fn keep(&mut self, candidate: Candidate) {
        let Some(k) = self.limit else {
            self.all.push(candidate);
            return;
        };
        let Ok(logdet) = candidate.logdet else {
            return;
        };
        let key = self.by.key(logdet, candidate.prediction.as_ref());
        let entry = Screened { key, candidate };
        if self.heap.len() < k {
            self.heap.push(Reverse(entry));
        } else if self
            .heap
            .peek()
            .is_some_and(|Reverse(worst)| entry > *worst)
        {
            self.heap.pop();
            self.heap.push(Reverse(entry));
        }
    }

    /// The kept tools in file order.
    pub fn finish(self) -> Vec<Candidate> {
        if self.limit.is_none() {
            return self.all;
        }
        let mut kept: Vec<Candidate> = self
            .heap
            .into_iter()
            .map(|Reverse(s)| s.candidate)
            .collect();
        kept.sort_by_key(|c| c.row.row);
        kept
    }
}

/// What screening one block of rows found: the tools kept (in row order) and the counts
/// [`Screen::absorb`] adds up.
#[derive(Debug, Clone, PartialEq)]
pub struct ScreenedBlock {
    pub kept: Vec<Candidate>,
    pub read: usize,
    pub without_confidence: usize,
    pub first_confidence_error: Option<String>,
    /// Tools with a confidence but no prediction (a screen by prediction), and the first reason.
    pub without_prediction: usize,
    pub first_prediction_error: Option<String>,
}

/// [`Screen::unpredicted_note`] from its counts: `without` tools had a confidence but no
/// prediction, the first for the reason `first`.
pub fn unpredicted_note(by: ScreenBy, without: usize, first: Option<&str>) -> Option<String> {
    (by.needs_prediction() && without > 0).then(|| {
        format!(
            "{without} tools have no prediction ({}): the screen by prediction ranked them after \
             every tool with one, in file order",
            first.unwrap_or("")
        )
    })
}

/// Why a tools file gives nothing to simulate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScreenError {
    /// The file, or a row that is not skipped.
    #[error(transparent)]
    File(#[from] ToolFileError),
    /// A tool of a model the task does not cover, no valid row, or no tool with a confidence.
    #[error("{0}")]
    Input(String),
}

/// The cheap stage over the tools file `path`, as `toolconf rank` and the Python package run it:
/// every row checked against `tasks` and pushed with its ln|Π^U| into a [`Screen`] keeping
/// `limit` tools. A bad row stops the read unless `skip_bad_rows`, in which case `skipping`
/// hears of it. `task` names the task in the message when no tool has a confidence. Returns the
/// screen and the number of rows skipped.
pub fn screen_file(
    path: &Path,
    tasks: &ModelTasks,
    task: &str,
    limit: Option<usize>,
    skip_bad_rows: bool,
    skipping: impl FnMut(&ToolFileError),
) -> Result<(Screen, usize), ScreenError> {
    let source = toolconf_messages::ClipPath(&path.to_string_lossy()).to_string();
    let read = |each: &mut EachRow| read_tools(path, each);
    let (screen, skipped) = screen_rows(
        &source,
        read,
        tasks,
        (limit, ScreenBy::Confidence),
        skip_bad_rows,
        skipping,
    )?;
    check_screened(&screen, skipped, &source, task)?;
    Ok((screen, skipped))
}

/// Where a reader of tools hands each row ([`read_tools`]'s and
/// [`read_columns`](toolconf_model::inputs::tools_file::read_columns)'s callback); an `Err` it returns stops the
/// read.
pub type EachRow<'a> = dyn FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError> + 'a;

/// [`screen_file`] over the rows `read` gives (`tools_file` names them in errors), keeping
/// `limit` tools by `by`, without the checks of the whole input ([`check_screened`]): what one
/// block of a larger table runs.
pub fn screen_rows(
    tools_file: &str,
    read: impl FnOnce(&mut EachRow) -> Result<usize, ToolFileError>,
    tasks: &ModelTasks,
    (limit, by): (Option<usize>, ScreenBy),
    skip_bad_rows: bool,
    skipping: impl FnMut(&ToolFileError),
) -> Result<(Screen, usize), ScreenError> {
    let screen = Screen::by(limit, by);
    screen_rows_into(screen, tools_file, read, tasks, skip_bad_rows, skipping)
}

/// [`screen_file`] into a [`Screen::with_validation`] by `by`: the kept tools, and a sample of
/// `validation` tools of the whole file to check claim (a) (or the prediction) on.
pub fn screen_file_with_validation(
    path: &Path,
    tasks: &ModelTasks,
    task: &str,
    (limit, validation, by): (Option<usize>, usize, ScreenBy),
    skip_bad_rows: bool,
    skipping: impl FnMut(&ToolFileError),
) -> Result<(Screen, usize), ScreenError> {
    let source = toolconf_messages::ClipPath(&path.to_string_lossy()).to_string();
    let read = |each: &mut EachRow| read_tools(path, each);
    let screen = Screen {
        by,
        ..Screen::with_validation(limit, validation)
    };
    let (screen, skipped) =
        screen_rows_into(screen, &source, read, tasks, skip_bad_rows, skipping)?;
    check_screened(&screen, skipped, &source, task)?;
    Ok((screen, skipped))
}

/// How many tools are predicted in parallel before they are pushed, in row order.
const PREDICTION_CHUNK: usize = 256;

/// The rows `read` gives pushed into `screen`, each with its prediction when the screen needs
/// one (computed in parallel, a chunk at a time, and pushed in row order: the screen keeps the
/// same tools whatever the number of threads).
fn screen_rows_into(
    mut screen: Screen,
    tools_file: &str,
    read: impl FnOnce(&mut EachRow) -> Result<usize, ToolFileError>,
    tasks: &ModelTasks,
    skip_bad_rows: bool,
    mut skipping: impl FnMut(&ToolFileError),
) -> Result<(Screen, usize), ScreenError> {
    let mut skipped = 0;
    let mut misfit = None;
    let predict = screen.by.needs_prediction();
    let mut pending = Vec::new();
    let read = read(&mut |row| match row {
        Ok(row) => {
            if let Err(e) = tasks.check(row.tool.model()) {
                misfit = Some(format!(
                    "{e} (tool '{}' of {tools_file} is an {} tool)",
                    row.label(),
                    row.tool.model()
                ));
                return Err(ToolFileError {
                    file: tools_file.into(),
                    place: String::new(),
                    message: "stopped".into(),
                    row_level: false,
                });
            }
            let candidate = confidence_of(row, tasks, tools_file);
            match predict {
                true => {
                    pending.push(candidate);
                    if pending.len() == PREDICTION_CHUNK {
                        push_predicted(&mut screen, std::mem::take(&mut pending), tasks);
                    }
                }
                false => screen.push(candidate),
            }
            Ok(())
        }
        Err(bad) if skip_bad_rows && bad.row_level => {
            skipping(&bad);
            skipped += 1;
            Ok(())
        }
        Err(bad) => Err(bad),
    });
    if let Some(message) = misfit {
        return Err(ScreenError::Input(message));
    }
    read?;
    push_predicted(&mut screen, pending, tasks);
    Ok((screen, skipped))
}

/// `row` with its ln|Π^U|, or why it has none (a tip task's tool without its tip).
fn confidence_of(row: ToolRow, tasks: &ModelTasks, tools_file: &str) -> Candidate {
    let missing_tip = match toolconf_core::reads_tip(tasks.kind) {
        true => row.missing_tip(),
        false => Vec::new(),
    };
    let logdet = if missing_tip.is_empty() {
        tasks.logdet(&row.tool)
    } else {
        Err(Error::ToolWithoutTip {
            file: tools_file.into(),
            row: row.row,
            kind: tasks.kind,
            columns: missing_tip.join(", "),
        })
    };
    Candidate {
        row,
        logdet,
        prediction: None,
    }
}

/// `candidates` given their predictions (in parallel; a tool without a confidence is never
/// kept, so it is not predicted) and pushed in order.
fn push_predicted(screen: &mut Screen, mut candidates: Vec<Candidate>, tasks: &ModelTasks) {
    candidates
        .par_iter_mut()
        .filter(|c| c.logdet.is_ok())
        .for_each(|c| c.prediction = Some(tasks.predict(&c.row.tool)));
    for candidate in candidates {
        screen.push(candidate);
    }
}

/// The whole input's checks after the cheap stage: some row was valid (`skipped` rows were
/// not), and some tool has a control confidence (else the task's precisions are at fault).
pub fn check_screened(
    screen: &Screen,
    skipped: usize,
    source: &str,
    task: &str,
) -> Result<(), ScreenError> {
    if screen.read == 0 {
        return Err(ScreenError::Input(format!(
            "{source}: no valid tools (all {skipped} rows were bad)"
        )));
    }
    if screen.without_confidence == screen.read {
        // The task's precisions, not the tools, are at fault: say so before simulating.
        return Err(ScreenError::Input(format!(
            "task {task}: no tool of {source} has a control confidence: {}",
            screen.first_confidence_error.as_deref().unwrap_or("")
        )));
    }
    Ok(())
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use toolconf_model::registry::{AnyTool, ModelKind};

    pub(in crate::rank) fn candidate(row: usize, logdet: Result<f64, Error>) -> Candidate {
        Candidate {
            prediction: None,
            row: ToolRow {
                row,
                name: None,
                tool: AnyTool::new(ModelKind::Arm2, &[0.3, 0.3, 0.3, 0.3]).unwrap(),
                defaulted: Vec::new(),
            },
            logdet,
        }
    }

    #[test]
    fn the_screen_keeps_the_most_confident_and_the_earlier_on_ties() {
        let mut screen = Screen::new(Some(2));
        let bad = Err(Error::from(toolconf_core::Error::NotPositiveDefinite {
            determinant: 0.0,
        }));
        for (row, l) in [
            (1, Ok(1.0)),
            (2, Ok(3.0)),
            (3, bad),
            (4, Ok(2.0)),
            (5, Ok(3.0)),
            (6, Ok(0.5)),
        ] {
            screen.push(candidate(row, l));
        }
        assert_eq!((screen.read, screen.without_confidence), (6, 1));
        let rows: Vec<usize> = screen.finish().iter().map(|c| c.row.row).collect();
        assert_eq!(rows, [2, 5]);
        let mut screen = Screen::new(Some(1));
        for (row, l) in [(1, 2.0), (2, 2.0)] {
            screen.push(candidate(row, Ok(l)));
        }
        assert_eq!(screen.finish()[0].row.row, 1);
    }

    #[test]
    fn blocks_screened_apart_and_absorbed_in_order_keep_what_one_screen_keeps() {
        let bad = || Err(Error::Unsupported("no confidence".into()));
        let logdets = [
            Ok(2.0),
            bad(),
            Ok(3.0),
            Ok(3.0),
            Ok(1.0),
            Ok(3.0),
            bad(),
            Ok(2.0),
        ];
        for limit in [Some(1), Some(3), Some(20), None] {
            let mut whole = Screen::new(limit);
            for (i, l) in logdets.iter().enumerate() {
                whole.push(candidate(i + 1, l.clone()));
            }
            let mut merged = Screen::new(limit);
            for block in [0..3, 3..3, 3..7, 7..8] {
                let mut part = Screen::new(limit);
                for i in block {
                    part.push(candidate(i + 1, logdets[i].clone()));
                }
                merged.absorb(part.into_block());
            }
            assert_eq!(merged.into_block(), whole.into_block(), "{limit:?}");
        }
    }

    #[test]
    fn blocks_screened_by_prediction_apart_and_absorbed_keep_and_count_what_one_screen_does() {
        use crate::select::Objective;
        use toolconf_model::prediction::Prediction;
        let predicted = |free_energy: f64| {
            Some(Ok(Prediction {
                task_error: 0.0,
                free_energy,
                cost_j: free_energy,
                perturbation_effect: 0.0,
                abscissa: -1.0,
            }))
        };
        let unstable = |abscissa: f64| Some(Err(PredictionError::Unstable { abscissa }));
        let tools = [
            unstable(0.5),
            predicted(3.0),
            predicted(1.0),
            unstable(0.25),
            predicted(1.0),
            predicted(2.0),
            unstable(0.125),
        ];
        let by = ScreenBy::Predicted(Objective::FreeEnergy);
        let candidate_of = |i: usize| {
            let mut c = candidate(i + 1, Ok(i as f64));
            c.prediction = tools[i].clone();
            c
        };
        for limit in [Some(1), Some(2), Some(5), Some(20), None] {
            let mut whole = Screen::by(limit, by);
            for i in 0..tools.len() {
                whole.push(candidate_of(i));
            }
            let mut merged = Screen::by(limit, by);
            for block in [0..2, 2..2, 2..5, 5..7] {
                let mut part = Screen::by(limit, by);
                for i in block {
                    part.push(candidate_of(i));
                }
                merged.absorb(part.into_block());
            }
            assert_eq!(merged.unpredicted_note(), whole.unpredicted_note());
            let whole = whole.into_block();
            assert_eq!((whole.without_prediction, whole.read), (3, 7));
            // The first reason is the first row's (real part 0.5), whatever the blocks.
            assert!(whole
                .first_prediction_error
                .as_ref()
                .unwrap()
                .contains("5.000000e-1"));
            assert_eq!(merged.into_block(), whole, "{limit:?}");
        }
    }

    #[test]
    fn a_screen_by_prediction_keeps_the_cheapest_and_puts_tools_without_one_last() {
        use crate::select::Objective;
        use toolconf_model::prediction::Prediction;
        let predicted = |free_energy: f64| {
            Some(Ok(Prediction {
                task_error: 0.0,
                free_energy,
                cost_j: -free_energy,
                perturbation_effect: 0.0,
                abscissa: -1.0,
            }))
        };
        let unstable = || Some(Err(PredictionError::Unstable { abscissa: 0.5 }));
        let tools = [
            (1, unstable()),
            (2, predicted(3.0)),
            (3, predicted(1.0)),
            (4, unstable()),
            (5, predicted(2.0)),
            (6, predicted(1.0)),
        ];
        let kept = |by: ScreenBy, k: usize| -> (Vec<usize>, usize) {
            let mut screen = Screen::by(Some(k), by);
            for (row, p) in tools.clone() {
                // Confidence orders the rows the other way, so it cannot decide here.
                let mut c = candidate(row, Ok(row as f64));
                c.prediction = p;
                screen.push(c);
            }
            let without = screen.without_prediction;
            (screen.finish().iter().map(|c| c.row.row).collect(), without)
        };
        let by_f = ScreenBy::Predicted(Objective::FreeEnergy);
        assert_eq!(kept(by_f, 2), (vec![3, 6], 2));
        assert_eq!(kept(by_f, 3), (vec![3, 5, 6], 2));
        // Fewer tools with a prediction than K: those without come next, the earlier first.
        assert_eq!(kept(by_f, 5), (vec![1, 2, 3, 5, 6], 2));
        // Ranking by ∫J dt, the screen minimises predicted ∫J dt (here −∫F dt).
        assert_eq!(
            kept(ScreenBy::Predicted(Objective::CostJ), 2),
            (vec![2, 5], 2)
        );
        assert_eq!(kept(ScreenBy::Confidence, 2), (vec![5, 6], 2));
    }
}
