//! `Method::Fast` (the default of select, rank and reproduce) on a population of random
//! tools against a tight reference (DP5 at rtol 1e-10, atol 1e-12) and against `ode45`
//! (`Method::Explicit`) at the same default tolerances: every tool's task error within 1e-4
//! relative and the same ranking by it; ∫F and ∫J no further from the reference than `ode45`'s
//! own, beyond 1e-4 of ∫J (`ode45` itself is off by up to ≈ 1e-3 at rtol 1e-3, see
//! docs/explanation/performance-population.md); identical results whatever the number of threads.
//!
//! The full 2000-tool check (`draw_tools(2000, 1)`) is `benches/population.sh`
//! (`benches/timing/population.rs`); here 60 tools per task keep the debug build to seconds.

mod common;

use toolconf::select::{draw_tools, evaluate};
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{simulate, EpisodeOptions, Metrics, Plant};
use toolconf_model::{Arm, Task, TaskKind};

const TOOLS: usize = 60;

fn run(arm: &Arm, kind: TaskKind, method: Method, rtol: f64, atol: f64) -> Metrics {
    let mut o = EpisodeOptions::default();
    o.integrator.method = method;
    o.integrator.rtol = rtol;
    o.integrator.atol = atol;
    simulate(arm, &Task::paper(kind), &o)
        .unwrap_or_else(|e| panic!("{method:?} {arm:?}: {e}"))
        .metrics
}

fn relative(value: f64, reference: f64) -> f64 {
    ((value - reference) / reference).abs()
}

/// Pairs the candidate orders the other way round from the reference although the reference
/// values differ by more than `tol` relative (a swap not explained by a tie).
fn unexplained_swaps(reference: &[f64], candidate: &[f64], tol: f64) -> Vec<(usize, usize)> {
    let mut swaps = Vec::new();
    for a in 0..reference.len() {
        for b in 0..reference.len() {
            let gap = reference[b] - reference[a];
            if gap > tol * reference[a].abs().max(reference[b].abs()) && candidate[a] > candidate[b]
            {
                swaps.push((a, b));
            }
        }
    }
    swaps
}

fn check_task(kind: TaskKind, seed: u64) {
    let tools = draw_tools(TOOLS, seed);
    let mut switched = 0;
    let (mut ref_error, mut fast_error) = (Vec::new(), Vec::new());
    for arm in &tools {
        let reference = run(arm, kind, Method::Explicit, 1e-10, 1e-12);
        let ode45 = run(arm, kind, Method::Explicit, 1e-3, 1e-6);
        let fast = run(arm, kind, Method::Fast, 1e-3, 1e-6);
        if fast.jacobian_evals > 0 {
            switched += 1;
        } else {
            // Never found stiff: ode45's steps, bit for bit.
            assert_eq!(fast, ode45, "{kind:?} {arm:?}");
        }
        let e = relative(fast.task_error, reference.task_error);
        assert!(e <= 1e-4, "{kind:?} {arm:?}: task error off by {e:e}");
        for (name, f, o, r) in [
            (
                "∫F",
                fast.free_energy,
                ode45.free_energy,
                reference.free_energy,
            ),
            ("∫J", fast.cost_j, ode45.cost_j, reference.cost_j),
        ] {
            // ∫F = ∫J − ½ ln|Π^U|·t_end, the last term exact: its error is ∫J's, on ∫J's scale
            // (∫F itself can be near zero).
            let scale = r.abs().max(reference.cost_j);
            let (e_fast, e_ode45) = ((f - r).abs(), (o - r).abs());
            assert!(
                e_fast <= e_ode45 + 1e-4 * scale,
                "{kind:?} {arm:?}: {name} off by {e_fast:e}, ode45's by {e_ode45:e} (reference {r})"
            );
        }
        ref_error.push(reference.task_error);
        fast_error.push(fast.task_error);
    }
    let swaps = unexplained_swaps(&ref_error, &fast_error, 1e-4);
    assert!(
        swaps.is_empty(),
        "{kind:?}: ranking by task error swaps {swaps:?}"
    );
    // The population has stiff tools: the switch to Rodas5P is exercised.
    assert!(
        switched > TOOLS / 10,
        "{kind:?}: only {switched} tools switched"
    );
}

#[test]
fn fast_matches_the_tight_reference_on_task_1() {
    check_task(TaskKind::Position, 1);
}

#[test]
fn fast_matches_the_tight_reference_on_task_2() {
    check_task(TaskKind::Velocity, 2);
}

#[test]
fn fast_matches_the_tight_reference_on_task_3() {
    // Task 3's reference by DP5 is stability-limited (≈ 300k evaluations on light arms), so
    // fewer tools here; Rodas5P at rtol 1e-10 is the other method's check.
    for arm in draw_tools(12, 3) {
        let kind = TaskKind::Acceleration;
        let reference = run(&arm, kind, Method::Stiff, 1e-10, 1e-12);
        let fast = run(&arm, kind, Method::Fast, 1e-3, 1e-6);
        let e = relative(fast.task_error, reference.task_error);
        assert!(e <= 1e-4, "{arm:?}: task error off by {e:e}");
        assert!(fast.jacobian_evals > 0, "{arm:?}: task 3 is stiff");
    }
}

#[test]
fn fast_results_do_not_depend_on_the_number_of_threads() {
    let tools = draw_tools(24, 5);
    let task = Task::paper(TaskKind::Position);
    let mut options = EpisodeOptions::default();
    options.integrator.method = Method::Fast;
    let metrics = |threads: usize| -> Vec<Metrics> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| evaluate(&tools, &task, &options, Plant::Paper))
            .into_iter()
            .map(|r| r.episode.unwrap())
            .collect()
    };
    assert_eq!(metrics(1), metrics(3));
}

fn select_json(extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "select", "--task", "position", "--tools", "8", "--seed", "1", "--json",
    ];
    args.extend_from_slice(extra);
    common::toolconf_json(&args)
}

/// `select` runs `Method::Fast` unless told otherwise, says so, and `--method explicit` gives
/// `ode45`'s numbers (the library's task-1 default) exactly.
#[test]
fn the_command_line_defaults_to_fast_and_names_the_method() {
    let tools = draw_tools(8, 1);
    let task = Task::paper(TaskKind::Position);
    for (extra, method) in [
        (&[][..], Method::Fast),
        (&["--method", "explicit"][..], Method::Explicit),
    ] {
        let v = select_json(extra);
        assert_eq!(v["method"], method.describe());
        for (t, arm) in v["tools"].as_array().unwrap().iter().zip(&tools) {
            let m = run(arm, TaskKind::Position, method, 1e-3, 1e-6);
            assert_eq!(
                t["task_error"].as_f64(),
                Some(m.task_error),
                "{method:?} {arm:?}"
            );
            assert_eq!(
                t["free_energy"].as_f64(),
                Some(m.free_energy),
                "{method:?} {arm:?}"
            );
        }
    }
    let explicit = EpisodeOptions::default();
    let m = simulate(&tools[0], &task, &explicit).unwrap().metrics;
    assert_eq!(
        select_json(&["--method", "explicit"])["tools"][0]["cost_j"].as_f64(),
        Some(m.cost_j)
    );
    let out = common::toolconf(&[
        "select", "--task", "position", "--tools", "2", "--method", "rk4",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("rk4"), "{stderr}");
}
