//! `toolconf reproduce --quick` end to end through the real binary: the files, their exact CSV
//! headers and column counts, a verdict per claim in the report, no NaN anywhere, and the same
//! bytes whatever the number of threads.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh directory under cargo's per-test temporary directory.
fn fresh_dir(name: &str) -> PathBuf {
    common::fresh_dir(&format!("reproduce-{name}"))
}

fn reproduce(out: &Path, threads: usize, extra: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(["reproduce", "--quick", "--out"])
        .arg(out)
        .args(extra)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run toolconf")
}

fn finish(child: std::process::Child) -> Output {
    let out = child.wait_with_output().unwrap();
    common::assert_ok_with(&out, "toolconf reproduce failed:\n");
    out
}

/// Splits one CSV line into cells (RFC 4180 quotes).
fn cells(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(String::new()),
            (c, _) => out.last_mut().unwrap().push(c),
        }
    }
    out
}

/// The files of a folder by name, with their bytes.
type Files = BTreeMap<String, Vec<u8>>;

fn files(dir: &Path) -> Files {
    common::folder_files(dir)
}

const ARM: &str = "m1,m2,l1,l2";

/// Experiments rerun on the exact Lagrangian plant write the same files with this prefix.
const EXACT_RERUNS: [&str; 3] = ["fig2_", "fig4_", "fig7_"];

fn with_exact_reruns(names: Vec<String>) -> Vec<String> {
    let exact: Vec<String> = names
        .iter()
        .filter(|n| EXACT_RERUNS.iter().any(|p| n.starts_with(p)))
        .map(|n| format!("exact_plant_{n}"))
        .collect();
    names.into_iter().chain(exact).collect()
}

/// Every CSV of the quick run: header and number of data rows (quick counts).
fn expected_csvs() -> Vec<(String, String, usize)> {
    let paper = paper_csvs();
    let exact: Vec<(String, String, usize)> = paper
        .iter()
        .filter(|(n, _, _)| EXACT_RERUNS.iter().any(|p| n.starts_with(p)))
        .map(|(n, h, r)| (format!("exact_plant_{n}"), h.clone(), *r))
        .collect();
    paper.into_iter().chain(exact).collect()
}

fn paper_csvs() -> Vec<(String, String, usize)> {
    let rules = "chosen_by_free_energy,chosen_by_cost_j,chosen_by_confidence";
    let list: Vec<(&str, String, usize)> = vec![
        (
            "fig2_confidence_vs_error.csv",
            format!("task,tool,{ARM},logdet,task_error,free_energy,cost_j,rhs_evals,error"),
            3 * 8,
        ),
        ("fig3_tools.csv", format!("tool,{ARM},logdet,role"), 6),
        (
            "fig3_trajectories.csv",
            "role,tool,logdet,perturbation,t,theta1,theta2,theta1_dot,theta2_dot,u1,u2,error"
                .to_string(),
            4 * 101,
        ),
        (
            "fig4_perturbation_change.csv",
            format!("task,tool,{ARM},logdet,task_error,task_error_perturbed,abs_change,error"),
            2 * 10,
        ),
        (
            "fig5_perturbation_sweep.csv",
            format!(
                "tool,{ARM},logdet,perturbation,task_error,task_error_unperturbed,abs_change,error"
            ),
            6 * 11,
        ),
        (
            "fig6_selection_grid.csv",
            format!("trial,tool,{ARM},logdet,task_error,free_energy,cost_j,{rules},error"),
            4 * 3,
        ),
        (
            "fig7_benchmark.csv",
            format!(
                "trial,tool,{ARM},logdet,task_error,free_energy,cost_j,task_error_perturbed,\
                 abs_change,{rules},error"
            ),
            6 * 4,
        ),
        (
            "fig7_choices.csv",
            "trial,rule,tool,logdet,task_error,abs_change".to_string(),
            6 * 3,
        ),
    ];
    list.into_iter()
        .map(|(n, h, r)| (n.to_string(), h, r))
        .collect()
}

const SVGS: [&str; 6] = [
    "fig2_confidence_vs_error.svg",
    "fig3_trajectories.svg",
    "fig4_perturbation_change.svg",
    "fig5_perturbation_sweep.svg",
    "fig6_selection_grid.svg",
    "fig7_benchmark.svg",
];

/// Claim labels the report must give a verdict for.
const CLAIMS: [&str; 14] = [
    "C1, task 1 (position)",
    "C1, task 2 (velocity)",
    "C1, task 3 (acceleration)",
    "C2 (Fig. 3), settling",
    "C2 (Fig. 3), variability",
    "C2, task 1 (position)",
    "C2, task 2 (velocity)",
    "C2 (Fig. 5), range of ΔT",
    "C2 (Fig. 5), sign of ΔT",
    "C3",
    "C4, confidence",
    "C4, sensitivity",
    "C4, task error",
    "C4, confidence-only selection",
];

#[test]
fn quick_reproduction_is_complete_clean_and_thread_independent() {
    let (one, two) = (fresh_dir("one-thread"), fresh_dir("two-threads"));
    let (a, b) = (reproduce(&one, 1, &[]), reproduce(&two, 2, &[]));
    let (out_one, _) = (finish(a), finish(b));
    let stdout = String::from_utf8_lossy(&out_one.stdout);
    assert!(stdout.contains("report: "), "{stdout}");
    assert!(
        out_one.stderr.is_empty(),
        "no progress bar when stderr is not a terminal: {}",
        String::from_utf8_lossy(&out_one.stderr)
    );

    let (first, second) = (files(&one), files(&two));
    let mut names: Vec<String> = expected_csvs().iter().map(|c| c.0.to_string()).collect();
    names.extend(with_exact_reruns(
        SVGS.iter().map(|s| s.to_string()).collect(),
    ));
    names.extend(["report.md".to_string(), "report.html".to_string()]);
    names.sort();
    assert_eq!(
        first.keys().cloned().collect::<Vec<_>>(),
        names,
        "exactly the expected files, no .partial left over"
    );

    csvs_and_figures_are_complete(&first);

    every_claim_has_its_verdict(&first);

    // Byte for byte the same data and figures with one and with two threads.
    for (name, bytes) in &first {
        if name.starts_with("report.") {
            continue; // they state the thread count and timings
        }
        assert!(
            bytes == &second[name],
            "{name} differs between 1 and 2 threads"
        );
    }
}

/// Each CSV with its header, its rows and only finite numbers; no NaN in any file; each SVG an
/// SVG.
fn csvs_and_figures_are_complete(first: &Files) {
    for (name, header, rows) in expected_csvs() {
        let text = std::str::from_utf8(&first[&name]).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], header, "{name} header");
        assert_eq!(lines.len() - 1, rows, "{name} rows");
        assert!(text.ends_with('\n'), "{name} ends with a complete row");
        let columns = header.split(',').count();
        for line in &lines[1..] {
            let row = cells(line);
            assert_eq!(row.len(), columns, "{name}: {line}");
            for cell in &row {
                if let Ok(v) = cell.parse::<f64>() {
                    assert!(v.is_finite(), "{name}: non-finite cell in {line}");
                }
            }
        }
    }

    for (name, bytes) in first {
        let text = String::from_utf8_lossy(bytes);
        assert!(!text.contains("NaN"), "{name} contains NaN");
        if name.ends_with(".svg") {
            assert!(text.starts_with("<svg"), "{name}");
        }
    }
}

/// The reports (Markdown and HTML) with a verdict and a rule for every claim, every figure,
/// and the run time.
fn every_claim_has_its_verdict(first: &Files) {
    let report = std::str::from_utf8(&first["report.md"]).unwrap();
    let exact_claims: Vec<String> = CLAIMS
        .iter()
        .filter(|c| c.starts_with("C1, ") || c.starts_with("C2, task") || c.starts_with("C4, "))
        .map(|c| format!("exact plant: {c}"))
        .collect();
    let claims: Vec<String> = CLAIMS
        .iter()
        .map(|c| c.to_string())
        .chain(exact_claims)
        .collect();
    for claim in &claims {
        let line = report
            .lines()
            .find(|l| l.starts_with(&format!("**Verdict ({claim}): ")))
            .unwrap_or_else(|| panic!("no verdict line for {claim}"));
        assert!(
            [
                "holds.",
                "does not hold.",
                "partly holds.",
                "cannot be judged."
            ]
            .iter()
            .any(|w| line.contains(&format!("): {w}**"))),
            "{line}"
        );
    }
    assert_eq!(report.matches("Rule: ").count(), claims.len());
    for svg in with_exact_reruns(SVGS.iter().map(|s| s.to_string()).collect()) {
        assert!(report.contains(&format!("]({svg})")), "report links {svg}");
    }
    for needle in ["Wall time", "rayon thread", "episodes/s"] {
        assert!(report.contains(needle), "report states {needle}");
    }
    let html = std::str::from_utf8(&first["report.html"]).unwrap();
    let figures = with_exact_reruns(SVGS.iter().map(|s| s.to_string()).collect()).len();
    assert_eq!(html.matches("<svg").count(), figures, "figures inline");
    assert_eq!(html.matches("Verdict (").count(), claims.len());
}

#[test]
fn experiments_are_independent_of_each_other_and_follow_the_seed() {
    let (alone, other_seed) = (fresh_dir("only-fig6"), fresh_dir("only-fig6-seed1"));
    let (a, b) = (
        reproduce(&alone, 2, &["--only", "fig6"]),
        reproduce(&other_seed, 2, &["--only", "fig6", "--seed", "1"]),
    );
    finish(a);
    finish(b);
    let (alone, other_seed) = (files(&alone), files(&other_seed));
    let mut want = [
        "fig6_selection_grid.csv",
        "fig6_selection_grid.svg",
        "report.html",
        "report.md",
    ]
    .map(String::from)
    .to_vec();
    want.sort();
    assert_eq!(alone.keys().cloned().collect::<Vec<_>>(), want);
    assert_ne!(
        alone["fig6_selection_grid.csv"], other_seed["fig6_selection_grid.csv"],
        "another master seed draws other tools"
    );
    // The same experiment alone gives the same bytes as in a full run (seed 0, quick): fig6 only
    // depends on its own sub-seeds. Compare with a full run made here so this test stands alone.
    let full = fresh_dir("full-for-fig6");
    finish(reproduce(&full, 2, &["--only", "fig2,fig6"]));
    assert!(
        files(&full)["fig6_selection_grid.csv"] == alone["fig6_selection_grid.csv"],
        "fig6 does not depend on which experiments run before it"
    );
}

#[test]
fn an_unknown_experiment_is_bad_input() {
    let out = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(["reproduce", "--quick", "--only", "fig9", "--out"])
        .arg(fresh_dir("unknown"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("fig9"));
}

#[test]
fn the_mpc_comparison_runs_when_switched_on() {
    let dir = fresh_dir("mpc");
    finish(reproduce(&dir, 2, &["--only", "mpc", "--mpc"]));
    let out = files(&dir);
    let text = std::str::from_utf8(&out["mpc_comparison.csv"]).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        format!(
            "task,tool,{ARM},logdet,perturbation,controller,task_error,cost_j,control_effort,error"
        )
    );
    // quick: 1 tool × 3 tasks × 2 controllers × 2 perturbations
    assert_eq!(lines.len() - 1, 12);
    assert!(lines[1..].iter().all(|l| cells(l).len() == 13));
    let report = std::str::from_utf8(&out["report.md"]).unwrap();
    assert!(report.contains("Active inference against the MPC baseline"));
    assert!(report.contains("J* (MPC)"));
}

#[test]
fn mpc_cost_rule_picks_the_tool_with_the_lowest_mpc_cost() {
    use toolconf::mpc::{simulate_mpc, MpcOptions};
    use toolconf::select::{draw_tools, evaluate};
    use toolconf_model::closed_loop::EpisodeOptions;
    use toolconf_model::closed_loop::Plant;
    use toolconf_model::{Task, TaskKind};
    use toolconf_report::experiments::objectives::{DecisionRule, MpcCost, Trial};
    let tools = draw_tools(3, 21);
    let task = Task::paper(TaskKind::Velocity);
    let options = EpisodeOptions::default();
    let results = evaluate(&tools, &task, &options, Plant::Paper);
    let trial = Trial {
        task: &task,
        tools: &tools,
        results: &results,
        options: &options,
        plant: Plant::Paper,
    };
    let chosen = MpcCost(MpcOptions::default()).choose(&trial).unwrap();
    let costs: Vec<f64> = tools
        .iter()
        .map(|a| {
            simulate_mpc(a, &task, &options, &MpcOptions::default())
                .unwrap()
                .metrics
                .cost_j
        })
        .collect();
    assert!(
        costs.iter().all(|c| costs[chosen] <= *c),
        "chose {chosen} of {costs:?}"
    );
}
