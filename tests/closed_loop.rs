//! The closed loop as a whole: analytic identities of the metrics, agreement with a
//! tight-tolerance run, the trajectory's shape, pinned metrics for fixed tools, and
//! determinism of selection across thread counts.

use proptest::prelude::*;
use toolconf::select::{draw_tools, evaluate, Objective};
use toolconf_model::closed_loop::{simulate, EpisodeOptions, Metrics, Plant};
use toolconf_model::model::{Arm2, ArmModel};
use toolconf_model::Term;
use toolconf_model::{Arm, Task, TaskKind, Vector2};

const ARMS: [[f64; 4]; 3] = [
    [0.3, 0.4, 0.5, 0.2],
    [0.1, 0.1, 0.1, 0.1],
    [0.6, 0.6, 0.6, 0.6],
];

fn arm(p: [f64; 4]) -> Arm {
    Arm::new([p[0], p[1], p[2], p[3]]).unwrap()
}

fn run(arm: &Arm, kind: TaskKind, options: &EpisodeOptions) -> Metrics {
    simulate(arm, &Task::paper(kind), options).unwrap().metrics
}

fn tight() -> EpisodeOptions {
    let mut o = EpisodeOptions::default();
    o.integrator.rtol = 1e-10;
    o.integrator.atol = 1e-10;
    o
}

#[test]
fn free_energy_minus_cost_is_the_confidence_term() {
    // F = J − ½ ln|Π^U| with Π^U constant, so ∫F − ∫J = −½ T ln|Π^U| exactly (trapezoid of a constant).
    for p in ARMS {
        for kind in [TaskKind::Position, TaskKind::Velocity] {
            let m = run(&arm(p), kind, &EpisodeOptions::default());
            let expected = -0.5 * 5.0 * m.logdet;
            let got = m.free_energy - m.cost_j;
            assert!(
                (got - expected).abs() <= 1e-9 * m.cost_j.abs().max(1.0),
                "{p:?} {kind}: {got} vs {expected}"
            );
        }
    }
}

#[test]
fn default_tolerances_agree_with_a_tight_reference() {
    // ode45's rtol = 1e-3 bounds the local error; the integrated metrics stay within that.
    for p in ARMS {
        for kind in [TaskKind::Position, TaskKind::Velocity] {
            let a = run(&arm(p), kind, &EpisodeOptions::default());
            let b = run(&arm(p), kind, &tight());
            for (name, x, y) in [
                ("task error", a.task_error, b.task_error),
                ("int F", a.free_energy, b.free_energy),
                ("int J", a.cost_j, b.cost_j),
            ] {
                let rel = (x - y).abs() / y.abs();
                assert!(
                    rel < 1e-3,
                    "{p:?} {kind} {name}: {x} vs tight {y} (rel {rel:e})"
                );
            }
            assert!(b.rhs_evals > a.rhs_evals);
        }
    }
}

#[test]
fn trajectory_is_on_the_paper_grid_and_starts_at_the_initial_conditions() {
    let options = EpisodeOptions {
        record_trajectory: true,
        ..EpisodeOptions::default()
    };
    let episode = simulate(&arm(ARMS[0]), &Task::paper(TaskKind::Position), &options).unwrap();
    let tr = episode.trajectory.unwrap();
    assert_eq!(tr.t.len(), 101);
    assert_eq!(tr.t[0], 0.0);
    assert_eq!(tr.t[100], 5.0);
    assert!((tr.t[1] - 0.05).abs() < 1e-15);
    assert_eq!(
        tr.of(Term::Theta)[0],
        Arm2::equilibrium_state().fixed_rows::<2>(0).into_owned()
    );
    assert_eq!(tr.of(Term::U)[0], Vector2::new(0.1, 0.1));
    // The recorded task error is the sum of the per-sample errors on this trajectory.
    let task = Task::paper(TaskKind::Position);
    let sum: f64 = tr
        .of(Term::Theta)
        .iter()
        .map(|th| {
            (th - task.goal[Term::Theta.index()])
                .dot(&(task.precision[Term::Theta.index()] * (th - task.goal[Term::Theta.index()])))
        })
        .sum();
    assert!((sum - episode.metrics.task_error).abs() <= 1e-12 * sum);
    // θ2 approaches its goal π/6 under task 1.
    assert!(
        (tr.of(Term::Theta)[100][1] - std::f64::consts::FRAC_PI_6).abs()
            < (tr.of(Term::Theta)[0][1] - std::f64::consts::FRAC_PI_6).abs()
    );
}

#[test]
fn perturbation_changes_the_episode_and_zero_is_the_default() {
    let a = arm(ARMS[0]);
    let base = run(&a, TaskKind::Velocity, &EpisodeOptions::default());
    let zero = run(
        &a,
        TaskKind::Velocity,
        &EpisodeOptions {
            perturbation: 0.0,
            ..EpisodeOptions::default()
        },
    );
    assert_eq!(base, zero);
    let pushed = run(
        &a,
        TaskKind::Velocity,
        &EpisodeOptions {
            perturbation: -0.8,
            ..EpisodeOptions::default()
        },
    );
    assert_ne!(base.task_error, pushed.task_error);
    assert_eq!(base.logdet, pushed.logdet);
}

#[test]
fn closed_loop_metrics_for_fixed_tools() {
    let mut out = String::new();
    for p in ARMS {
        for kind in [TaskKind::Position, TaskKind::Velocity] {
            for perturbation in [0.0, -0.8] {
                let m = run(
                    &arm(p),
                    kind,
                    &EpisodeOptions {
                        perturbation,
                        ..EpisodeOptions::default()
                    },
                );
                out += &format!(
                    "{p:?} {kind:<8} dT={perturbation:<4} task_error={:.10e} int_F={:.10e} int_J={:.10e} logdet={:.10e} rhs_evals={}\n",
                    m.task_error, m.free_energy, m.cost_j, m.logdet, m.rhs_evals
                );
            }
        }
    }
    insta::assert_snapshot!(out);
}

#[test]
fn selection_is_identical_for_any_thread_count() {
    let tools = draw_tools(24, 11);
    let task = Task::paper(TaskKind::Velocity);
    let options = EpisodeOptions::default();
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| evaluate(&tools, &task, &options, Plant::Paper))
    };
    let one = with(1);
    let two = with(2);
    assert_eq!(one.len(), 24);
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a.index, b.index);
        assert_eq!(a.arm, b.arm);
        assert_eq!(a.logdet, b.logdet);
        assert_eq!(a.episode.as_ref().unwrap(), b.episode.as_ref().unwrap());
    }
    for o in Objective::ALL {
        assert_eq!(o.choose(&one), o.choose(&two));
        assert!(o.choose(&one).is_some());
    }
}

#[test]
fn tools_are_drawn_from_the_documented_stream() {
    let a = draw_tools(50, 3);
    assert_eq!(a, draw_tools(50, 3));
    assert_ne!(a, draw_tools(50, 4));
    for t in &a {
        for &v in t.params().iter() {
            assert!((0.1..0.6).contains(&v));
        }
    }
    // The first tool of a longer draw is the same tool: the stream does not depend on n.
    assert_eq!(draw_tools(1, 3)[0], a[0]);
}

#[test]
fn choices_follow_their_objectives() {
    let tools = draw_tools(10, 5);
    let results = evaluate(
        &tools,
        &Task::paper(TaskKind::Velocity),
        &EpisodeOptions::default(),
        Plant::Paper,
    );
    let f = Objective::FreeEnergy.choose(&results).unwrap();
    let j = Objective::CostJ.choose(&results).unwrap();
    let c = Objective::Confidence.choose(&results).unwrap();
    for r in &results {
        let m = r.episode.as_ref().unwrap();
        assert!(results[f].episode.as_ref().unwrap().free_energy <= m.free_energy);
        assert!(results[j].episode.as_ref().unwrap().cost_j <= m.cost_j);
        assert!(results[c].logdet.as_ref().unwrap() >= r.logdet.as_ref().unwrap());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn valid_arms_never_panic(m1 in 0.05..1.0f64, m2 in 0.05..1.0f64, l1 in 0.05..1.0f64, l2 in 0.05..1.0f64, k in 0usize..2, dt in -1.0..1.0f64) {
        let arm = Arm::new([m1, m2, l1, l2]).unwrap();
        let options = EpisodeOptions { perturbation: dt, ..EpisodeOptions::default() };
        // Either a finite result or a typed error: never a panic, never a NaN.
        if let Ok(e) = simulate(&arm, &Task::paper(TaskKind::ALL[k]), &options) {
            prop_assert!(e.metrics.task_error.is_finite() && e.metrics.free_energy.is_finite() && e.metrics.cost_j.is_finite());
        }
    }
}

#[test]
fn the_exact_plant_changes_the_world_not_the_agent() {
    for p in ARMS {
        let paper = run(&arm(p), TaskKind::Position, &EpisodeOptions::default());
        let exact = Plant::Exact
            .simulate(
                &arm(p),
                &Task::paper(TaskKind::Position),
                &EpisodeOptions::default(),
            )
            .unwrap()
            .metrics;
        assert_eq!(paper.logdet, exact.logdet);
        assert_ne!(paper.task_error, exact.task_error);
        let identity = exact.free_energy - exact.cost_j + 2.5 * exact.logdet;
        assert!(identity.abs() <= 1e-9 * exact.cost_j.abs().max(1.0));
    }
}
