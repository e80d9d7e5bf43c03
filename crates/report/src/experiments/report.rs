//! The report: a small document model (headings, paragraphs, tables, figures, verdicts) that each
//! experiment fills, rendered once as Markdown (`report.md`, figures linked) and once as HTML
//! (`report.html`, figures inline).
//!
//! Text may use two inline marks, `` `code` `` and `**bold**`; everything else is plain text.

use std::fmt::Write as _;
use std::time::Duration;

use super::{Plan, Timing};
use toolconf_model::closed_loop::EpisodeOptions;

/// A verdict on a claim.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    Holds,
    DoesNotHold,
    Partly,
    /// The statistics could not be computed (the reason is in the evidence).
    NotJudged,
    /// The opposite of the claim, significantly (`reproduce --model`'s three-way rule).
    Reversed,
    /// Neither the claim nor its opposite (`reproduce --model`'s three-way rule).
    NoRelation,
}

impl Outcome {
    pub fn words(self) -> &'static str {
        match self {
            Outcome::Holds => "holds",
            Outcome::DoesNotHold => "does not hold",
            Outcome::Partly => "partly holds",
            Outcome::NotJudged => "cannot be judged",
            Outcome::Reversed => "reversed",
            Outcome::NoRelation => "no relation",
        }
    }

    /// The HTML class of a verdict's paragraph (the style's colours: green, red, amber, grey).
    pub fn css_class(self) -> &'static str {
        match self {
            Outcome::Holds => "holds",
            Outcome::DoesNotHold | Outcome::Reversed => "does-not-hold",
            Outcome::Partly => "partly-holds",
            Outcome::NotJudged | Outcome::NoRelation => "cannot-be-judged",
        }
    }
}

/// A claim of the paper, what was measured, and the verdict with its rule.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Short label, e.g. "C1, task 1 (position)".
    pub claim: String,
    /// The claim in the paper's words (or a close paraphrase).
    pub statement: String,
    pub outcome: Outcome,
    /// The statistics the verdict rests on.
    pub evidence: String,
    /// The rule that turns the statistics into the verdict.
    pub rule: String,
}

/// One block of the document.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    Heading(u8, String),
    Paragraph(String),
    Bullets(Vec<String>),
    Table {
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    /// An SVG written next to the report (`file`) with its text (`svg`) for inlining.
    Figure {
        file: String,
        caption: String,
        svg: String,
    },
    Verdict(Verdict),
    /// A part of the HTML report alone (an interactive view, trusted markup made by this crate),
    /// with the paragraph the Markdown report shows in its place.
    Html {
        markdown: String,
        html: String,
    },
}

impl Block {
    pub fn p(text: impl Into<String>) -> Self {
        Block::Paragraph(text.into())
    }

    pub fn table(header: &[&str], rows: Vec<Vec<String>>) -> Self {
        Block::Table {
            header: header.iter().map(|h| h.to_string()).collect(),
            rows,
        }
    }
}

/// One experiment's part of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    pub id: &'static str,
    pub title: String,
    pub blocks: Vec<Block>,
    /// Episodes simulated and their right-hand-side evaluations.
    pub episodes: u64,
    pub rhs_evals: u64,
}

impl Section {
    pub fn verdicts(&self) -> impl Iterator<Item = &Verdict> {
        self.blocks.iter().filter_map(|b| match b {
            Block::Verdict(v) => Some(v),
            _ => None,
        })
    }
}

/// Facts about the run for the report's header.
pub struct RunInfo<'a> {
    pub command: &'a str,
    pub seed: u64,
    pub plan: &'a Plan,
    pub timings: &'a [Timing],
    pub wall: Duration,
    pub threads: usize,
    /// The unperturbed episode settings every experiment starts from.
    pub episode: &'a EpisodeOptions,
}

fn join<'a>(v: impl Iterator<Item = &'a f64>) -> String {
    v.map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(" ")
}

/// The whole report: header, verdict summary, timing, then every section.
pub fn document(info: &RunInfo, sections: &[Section]) -> Vec<Block> {
    let mut doc = header(info);
    doc.push(Block::Heading(2, "Verdicts".into()));
    let mut rows = Vec::new();
    for s in sections {
        for v in s.verdicts() {
            rows.push(vec![
                v.claim.clone(),
                s.title.clone(),
                format!("**{}**", v.outcome.words()),
            ]);
        }
    }
    doc.push(Block::table(&["claim", "figure", "verdict"], rows));
    doc.push(Block::Heading(2, "Run time".into()));
    doc.extend(run_time(info));
    for s in sections {
        doc.push(Block::Heading(2, s.title.clone()));
        doc.extend(s.blocks.iter().cloned());
    }
    doc
}

/// The report's title and what the run was: its command, seed, counts, settings and streams.
fn header(info: &RunInfo) -> Vec<Block> {
    vec![
        Block::Heading(
            1,
            "Reproduction of the Results of \"Confidence-Aware Decision-Making and Control for \
             Tool Selection\""
                .into(),
        ),
        Block::p(format!(
            "Command: `{}`. Master seed {}; {} counts{}. toolconf {}.",
            info.command,
            info.seed,
            if info.plan.quick {
                "quick (reduced)"
            } else {
                "the paper's"
            },
            if info.plan.quick {
                ": the statistics below are for testing the pipeline, not for judging the paper"
            } else {
                ""
            },
            env!("CARGO_PKG_VERSION")
        )),
        Block::p(
            "Each section states a claim of the paper's Results section, the data measured here \
             (CSV files next to this report, one row per tool or time step; a failed episode is \
             a row with its error message and empty numbers), the statistics, and a verdict \
             with the rule it follows. Control confidence is ln|Π^U| (the log-determinant of \
             the control precision); task error is the paper's weighted sum over the grid \
             points of an episode. Arm parameters are uniform on [0.1, 0.6).",
        ),
        Block::p(format!(
            "Episode settings (the paper's \"Implementation details\"): t_end = {} s, output \
             step dt = {} s, X0 = [{}], U0 = [{}], learning rate γ = {}; integrator `{:?}` \
             (method {}).",
            info.episode.t_end,
            info.episode.dt,
            join(info.episode.x0.iter()),
            join(info.episode.u0.iter()),
            info.episode.learning_rate,
            info.episode.integrator,
            info.episode.integrator.method.describe()
        )),
        Block::p(
            "Random streams: each experiment draws from its own sub-seeds, \
             `derive_seed(master, label)` = SplitMix64 finaliser of (master XOR FNV-1a-64(label)), \
             with labels `<experiment>/tools` (Figs. 2–5), `<experiment>/trial/<k>` (Figs. 6–7, \
             one stream per trial) and `<experiment>/bootstrap/<task or ΔT>`; tools come from \
             the documented ChaCha8 stream of `toolconf::select::draw_tools`. Experiments are \
             therefore independent of each other and of their order, and the CSVs and figures \
             are byte-identical whatever the thread count.",
        ),
    ]
}

/// The run's wall time and throughput, overall and per experiment.
fn run_time(info: &RunInfo) -> [Block; 2] {
    let episodes: u64 = info.timings.iter().map(|t| t.episodes).sum();
    let secs = info.wall.as_secs_f64();
    let overall = Block::p(format!(
        "Wall time {:.2} s on {} rayon thread{}; {} episodes, {:.0} episodes/s overall.",
        secs,
        info.threads,
        if info.threads == 1 { "" } else { "s" },
        episodes,
        if secs > 0.0 {
            episodes as f64 / secs
        } else {
            0.0
        }
    ));
    let rows = info
        .timings
        .iter()
        .map(|t| {
            let s = t.wall.as_secs_f64();
            vec![
                t.id.to_string(),
                format!("{s:.2}"),
                t.episodes.to_string(),
                if s > 0.0 {
                    format!("{:.0}", t.episodes as f64 / s)
                } else {
                    "-".into()
                },
                t.rhs_evals.to_string(),
            ]
        })
        .collect();
    let table = Block::table(
        &[
            "experiment",
            "wall time [s]",
            "episodes",
            "episodes/s",
            "RHS evaluations",
        ],
        rows,
    );
    [overall, table]
}

fn verdict_line(v: &Verdict) -> String {
    format!(
        "**Verdict ({}): {}.** {}",
        v.claim,
        v.outcome.words(),
        v.evidence
    )
}

/// The report as Markdown.
pub fn to_markdown(doc: &[Block]) -> String {
    let mut out = String::new();
    for block in doc {
        match block {
            Block::Heading(level, text) => {
                let _ = writeln!(out, "{} {text}\n", "#".repeat(usize::from(*level)));
            }
            Block::Paragraph(text) => {
                let _ = writeln!(out, "{text}\n");
            }
            Block::Bullets(items) => {
                for item in items {
                    let _ = writeln!(out, "- {item}");
                }
                out.push('\n');
            }
            Block::Table { header, rows } => {
                let cell = |s: &String| s.replace('|', "\\|");
                let line = |cells: &[String]| {
                    format!(
                        "| {} |\n",
                        cells.iter().map(cell).collect::<Vec<_>>().join(" | ")
                    )
                };
                out.push_str(&line(header));
                out.push_str(&format!("|{}\n", "---|".repeat(header.len())));
                for row in rows {
                    out.push_str(&line(row));
                }
                out.push('\n');
            }
            Block::Figure { file, caption, .. } => {
                let _ = writeln!(out, "![{file}]({file})\n\n*{caption}*\n");
            }
            Block::Verdict(v) => {
                let _ = writeln!(out, "> **Claim ({}).** {}\n", v.claim, v.statement);
                let _ = writeln!(out, "{}\n", verdict_line(v));
                let _ = writeln!(out, "Rule: {}\n", v.rule);
            }
            Block::Html { markdown, .. } => {
                let _ = writeln!(out, "{markdown}\n");
            }
        }
    }
    out
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Escapes `s` and turns the paired inline marks `` ` `` and `**` into `<code>` and `<strong>`.
fn inline(s: &str) -> String {
    let mut out = escape(s);
    for (mark, tag) in [("`", "code"), ("**", "strong")] {
        if out.matches(mark).count() % 2 != 0 {
            continue;
        }
        let parts: Vec<&str> = out.split(mark).collect();
        let mut joined = String::new();
        for (i, part) in parts.iter().enumerate() {
            if i > 0 {
                joined.push_str(
                    if i % 2 == 1 {
                        format!("<{tag}>")
                    } else {
                        format!("</{tag}>")
                    }
                    .as_str(),
                );
            }
            joined.push_str(part);
        }
        out = joined;
    }
    out
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1500px;margin:2em auto;padding:0 1em;\
line-height:1.45;color:#222}table{border-collapse:collapse;margin:0.5em 0 1em}\
td,th{border:1px solid #bbb;padding:0.2em 0.6em;text-align:left}th{background:#eee}\
blockquote{border-left:4px solid #ccc;margin:1em 0;padding:0.2em 1em;color:#444}\
figure{margin:1em 0}figcaption{font-style:italic;max-width:60em}\
.verdict{padding:0.4em 0.8em;border-radius:4px;background:#f4f4f4}\
.holds{border-left:6px solid #2a7}.does-not-hold{border-left:6px solid #c33}\
.partly-holds{border-left:6px solid #d90}.cannot-be-judged{border-left:6px solid #888}\
code{background:#f0f0f0;padding:0 0.2em}";

/// The report as one self-contained HTML page with the figures inline.
pub fn to_html(doc: &[Block]) -> String {
    let title = doc
        .iter()
        .find_map(|b| match b {
            Block::Heading(_, t) => Some(t.as_str()),
            _ => None,
        })
        .unwrap_or("toolconf reproduction");
    let mut out = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n\
         <style>{STYLE}</style>\n</head>\n<body>\n",
        escape(title)
    );
    for block in doc {
        match block {
            Block::Heading(level, text) => {
                let _ = writeln!(out, "<h{level}>{}</h{level}>", inline(text));
            }
            Block::Paragraph(text) => {
                let _ = writeln!(out, "<p>{}</p>", inline(text));
            }
            Block::Bullets(items) => {
                out.push_str("<ul>\n");
                for item in items {
                    let _ = writeln!(out, "<li>{}</li>", inline(item));
                }
                out.push_str("</ul>\n");
            }
            Block::Table { header, rows } => {
                out.push_str("<table>\n<tr>");
                for h in header {
                    let _ = write!(out, "<th>{}</th>", inline(h));
                }
                out.push_str("</tr>\n");
                for row in rows {
                    out.push_str("<tr>");
                    for c in row {
                        let _ = write!(out, "<td>{}</td>", inline(c));
                    }
                    out.push_str("</tr>\n");
                }
                out.push_str("</table>\n");
            }
            Block::Figure { file, caption, svg } => {
                let _ = writeln!(
                    out,
                    "<figure id=\"{}\">\n{}\n<figcaption>{} (<a href=\"{}\">{}</a>)</figcaption>\n</figure>",
                    escape(file),
                    svg.trim(),
                    inline(caption),
                    escape(file),
                    escape(file)
                );
            }
            Block::Verdict(v) => {
                let _ = writeln!(
                    out,
                    "<blockquote><strong>Claim ({}).</strong> {}</blockquote>",
                    inline(&v.claim),
                    inline(&v.statement)
                );
                let _ = writeln!(
                    out,
                    "<p class=\"verdict {}\">{}</p>\n<p>Rule: {}</p>",
                    v.outcome.css_class(),
                    inline(&verdict_line(v)),
                    inline(&v.rule)
                );
            }
            Block::Html { html, .. } => {
                let _ = writeln!(out, "{}", html.trim());
            }
        }
    }
    out.push_str("</body>\n</html>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inline_marks_become_tags_and_text_is_escaped() {
        assert_eq!(
            inline("a `x<y` and **b & c**"),
            "a <code>x&lt;y</code> and <strong>b &amp; c</strong>"
        );
        assert_eq!(inline("lone ` tick"), "lone ` tick");
    }

    #[test]
    fn both_renderings_carry_every_verdict() {
        let v = Verdict {
            claim: "C9, test".into(),
            statement: "something".into(),
            outcome: Outcome::Partly,
            evidence: "ρ = −0.2".into(),
            rule: "a rule".into(),
        };
        let doc = vec![
            Block::Heading(1, "T".into()),
            Block::table(&["a|b"], vec![vec!["1".into()]]),
            Block::Verdict(v),
        ];
        let md = to_markdown(&doc);
        assert!(md.contains("**Verdict (C9, test): partly holds.** ρ = −0.2"));
        assert!(md.contains("| a\\|b |"));
        let html = to_html(&doc);
        assert!(html.contains("<strong>Verdict (C9, test): partly holds.</strong>"));
        assert!(html.contains("class=\"verdict partly-holds\""));
    }
}
