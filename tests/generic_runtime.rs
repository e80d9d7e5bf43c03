//! The model-generic runtime (`toolconf_model::model`): the paper's arm's plant choice runs it on the
//! chosen model; arm3 runs; bad input gives typed errors; mixed tool sets draw and rank
//! deterministically.

mod common;

use toolconf_model::Term;

use common::toolconf;
use nalgebra::SMatrix;
use proptest::prelude::*;
use serde_json::Value;
use toolconf::select::mixed::{draw_mixed_tools, evaluate_mixed, MixedObjective, MixedResult};
use toolconf::select::{draw_tools, PARAMETER_RANGE};
use toolconf_model::closed_loop::{self, EpisodeOptions, Metrics, Plant};
use toolconf_model::model::{
    self, control_confidence, simulate, simulate_on, Arm2, Arm2Exact, Arm2Tool, Arm3, Arm3Tool,
    ArmModel, EpisodeOptionsN,
};
use toolconf_model::registry::{AnyTool, ModelKind};
use toolconf_model::{Arm, Error, Task, TaskKind};

/// Every field of the metrics as bits, so that "equal" means bit-identical (and NaN-safe).
fn bits(m: &Metrics) -> [u64; 10] {
    [
        m.task_error.to_bits(),
        m.free_energy.to_bits(),
        m.cost_j.to_bits(),
        m.logdet.to_bits(),
        m.control_effort.to_bits(),
        m.rhs_evals as u64,
        m.steps as u64,
        m.rejected_steps as u64,
        m.jacobian_evals as u64,
        m.factorisations as u64,
    ]
}

fn arms() -> Vec<Arm> {
    let mut arms = vec![
        Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap(),
        Arm::new([0.5, 0.5, 0.5, 0.5]).unwrap(),
        Arm::new([0.1, 0.6, 0.2, 0.35]).unwrap(),
        Arm::new([0.55, 0.12, 0.45, 0.15]).unwrap(),
    ];
    arms.extend(draw_tools(3, 11));
    arms
}

#[test]
fn the_plant_choice_runs_the_generic_episode_on_that_model() {
    let mut compared = 0;
    for arm in arms() {
        for kind in TaskKind::ALL {
            let task = Task::paper(kind);
            for perturbation in [0.0, -0.8] {
                let options = EpisodeOptions {
                    perturbation,
                    ..EpisodeOptions::default()
                };
                let paper = Plant::Paper.simulate(&arm, &task, &options);
                let exact = Plant::Exact.simulate(&arm, &task, &options);
                let on_arm2 = simulate_on::<Arm2, Arm2, 2, 4, 4, 6>(&arm, &task, &options);
                let on_exact = simulate_on::<Arm2, Arm2Exact, 2, 4, 4, 6>(&arm, &task, &options);
                for (chosen, generic) in [(&paper, on_arm2), (&exact, on_exact)] {
                    match (chosen, generic) {
                        (Ok(c), Ok(g)) => {
                            assert_eq!(
                                bits(&c.metrics),
                                bits(&g),
                                "{arm} {kind} dT={perturbation}"
                            );
                            compared += 1;
                        }
                        (Err(c), Err(g)) => assert_eq!(c.time(), g.time()),
                        (c, g) => panic!("{arm} {kind} dT={perturbation}: {c:?} vs {g:?}"),
                    }
                }
                // The exact plant is another world: the same controller does differently in it.
                if let (Ok(p), Ok(e)) = (&paper, &exact) {
                    assert_ne!(p.metrics.task_error, e.metrics.task_error, "{arm} {kind}");
                }
            }
        }
    }
    assert!(compared >= 70, "only {compared} episodes compared");
}

#[test]
fn the_paper_arms_failures_name_the_arm_and_the_generic_ones_the_model() {
    let arm = Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let task = Task::paper(TaskKind::Position);
    let mut options = EpisodeOptions::default();
    options.integrator.max_steps = 3;
    let paper = closed_loop::simulate(&arm, &task, &options)
        .unwrap_err()
        .to_string();
    assert!(
        paper.starts_with("simulation of arm m1=0.3 m2=0.4 l1=0.5 l2=0.2 failed"),
        "{paper}"
    );
    let generic = simulate(&arm, &task, &options).unwrap_err().to_string();
    assert!(
        generic.starts_with("simulation of arm2(m1=0.3 m2=0.4 l1=0.5 l2=0.2) failed"),
        "{generic}"
    );
    assert_eq!(
        paper.split_once(" failed").unwrap().1,
        generic.split_once(" failed").unwrap().1
    );
}

#[test]
fn the_default_options_are_the_papers_implementation_details() {
    let o = EpisodeOptions::default();
    assert_eq!(
        (o.t_end, o.dt, o.learning_rate, o.perturbation),
        (5.0, 0.05, 1.0, 0.0)
    );
    let half_pi = -std::f64::consts::FRAC_PI_2;
    assert_eq!(o.x0.as_slice(), &[half_pi, half_pi, 0.0, 0.0]);
    assert_eq!(o.u0.as_slice(), &[0.1, 0.1]);
    assert_eq!((o.integrator.rtol, o.integrator.atol), (1e-3, 1e-6));
    assert_eq!(o.integrator.method, toolconf_integrators::Method::Auto);
    assert_eq!(o.joint_perturbation, nalgebra::Vector2::zeros());
    assert!(!o.record_trajectory);
    assert_eq!(
        o,
        EpisodeOptionsN::paper::<Arm2Exact, 4, 6>(),
        "the exact arm hangs alike"
    );
}

#[test]
fn arm3_runs_every_task_with_finite_metrics() {
    let tool = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    for kind in TaskKind::ALL {
        let task = Arm3::paper_task(kind);
        for perturbation in [0.0, -0.8] {
            let options = EpisodeOptionsN {
                perturbation,
                ..EpisodeOptionsN::paper::<Arm3, 6, 9>()
            };
            let result = simulate(&tool, &task, &options);
            if kind == TaskKind::TipAcceleration && perturbation != 0.0 {
                // arm3 hangs straight at q^e, a kinematic singularity: J(q^e)'s radial row is
                // zero, so the tip acceleration task controls the tip's x alone, and ΔT swings
                // the joints it does not see until J(q) and J(q^e) disagree in sign (measured:
                // from t ≈ 1.5 s; it diverges by t = 3.43 s, DP5 and Rodas5P alike). That is an
                // error naming the divergence, never a metric of NaN.
                let e = result.unwrap_err().to_string();
                assert!(e.contains("the state left the joints' range"), "{e}");
                continue;
            }
            let m = result.unwrap();
            for v in [
                m.task_error,
                m.free_energy,
                m.cost_j,
                m.logdet,
                m.control_effort,
            ] {
                assert!(v.is_finite(), "{kind} dT={perturbation}: {m:?}");
            }
            assert!(m.rhs_evals > 0);
            let c = control_confidence(&tool, &task).unwrap();
            assert_eq!(m.logdet.to_bits(), c.logdet.to_bits());
            assert!(
                (m.free_energy - (m.cost_j - 0.5 * m.logdet * 5.0)).abs()
                    < 1e-9 * m.free_energy.abs().max(1.0)
            );
        }
    }
    // Task 3: Π^U = P^θ̈ + P^U exactly (∂θ̈/∂U = I), whatever the tool.
    let task = Arm3::paper_task(TaskKind::Acceleration);
    let c = control_confidence(&tool, &task).unwrap();
    assert_eq!(
        c.pi_u,
        task.precision[Term::ThetaDdot.index()] + task.precision[Term::U.index()]
    );
    assert_eq!(c.pi_u, SMatrix::<f64, 3, 3>::identity() * 10.0);
    assert!((c.logdet - 3.0 * 10f64.ln()).abs() < 1e-14);
    assert!((c.logdet_per_joint() - 10f64.ln()).abs() < 1e-15);
}

#[test]
fn arm3_goals_extend_the_two_link_ones() {
    let two = Arm2::paper_task(TaskKind::Position);
    let three = Arm3::paper_task(TaskKind::Position);
    assert_eq!(
        three.goal[Term::Theta.index()][2],
        two.goal[Term::Theta.index()][1]
    );
    assert_eq!(
        three.goal[Term::Theta.index()][0],
        two.goal[Term::Theta.index()][0]
    );
    let v = Arm3::paper_task(TaskKind::Velocity);
    assert_eq!(v.goal[Term::ThetaDot.index()].as_slice(), &[0.0, 0.0, 2.0]);
    let a = Arm3::paper_task(TaskKind::Acceleration);
    assert_eq!(a.goal[Term::ThetaDdot.index()].as_slice(), &[0.0, 0.0, 0.1]);
    assert_eq!(Arm3::name(), "arm3");
    assert_eq!(
        *Arm3::parameter_names(),
        ["m1", "m2", "m3", "l1", "l2", "l3"]
    );
}

#[test]
fn invalid_tool_parameters_give_typed_errors() {
    assert_eq!(
        Arm3Tool::new([0.3, -1.0, 0.2, 0.4, 0.35, 0.3]).unwrap_err(),
        model::Error::InvalidParameter {
            name: "m2",
            value: -1.0
        }
    );
    match Arm3Tool::new([0.3, 0.2, 0.2, 0.4, 0.35, f64::NAN]).unwrap_err() {
        model::Error::InvalidParameter { name, value } => {
            assert_eq!(name, "l3");
            assert!(value.is_nan());
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(
        Arm2Tool::new([0.3, 0.2, 0.0, 0.4]).unwrap_err(),
        model::Error::InvalidParameter {
            name: "l1",
            value: 0.0
        }
    );
    assert!(matches!(
        AnyTool::new(ModelKind::Arm3, &[0.3, 0.3, 0.3, 0.3]),
        Err(Error::ParameterCount {
            model: "arm3",
            expected: 6,
            found: 4,
            ..
        })
    ));
    assert!(matches!(
        AnyTool::new(ModelKind::Arm3, &[0.3, 0.3, 0.3, 0.3, 0.3, f64::INFINITY]),
        Err(Error::Core(model::Error::InvalidParameter {
            name: "l3",
            ..
        }))
    ));
}

#[test]
fn invalid_tasks_give_typed_errors() {
    let tool = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    // All-zero precisions: Π^U = 0 for every tool, refused as such.
    let mut task = Arm3::paper_task(TaskKind::Acceleration);
    task.precision[Term::ThetaDdot.index()] = SMatrix::zeros();
    common::assert_rank_zero(control_confidence(&tool, &task), 3);
    // Rank 2 of 3 in all is still singular for every tool.
    task.precision[Term::ThetaDdot.index()] =
        SMatrix::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, 0.0));
    assert!(matches!(
        control_confidence(&tool, &task),
        Err(model::Error::ConfidenceRank { rank: 2, .. })
    ));
    // Not positive semi-definite.
    let mut task = Arm3::paper_task(TaskKind::Velocity);
    task.precision[Term::ThetaDot.index()][(2, 2)] = -1.0;
    assert!(matches!(
        control_confidence(&tool, &task),
        Err(model::Error::InvalidPrecision {
            term: Term::ThetaDot,
            ..
        })
    ));
    // Not symmetric.
    let mut task = Arm3::paper_task(TaskKind::Position);
    task.precision[Term::Theta.index()][(0, 2)] = 3.0;
    assert!(matches!(
        control_confidence(&tool, &task),
        Err(model::Error::InvalidPrecision {
            term: Term::Theta,
            ..
        })
    ));
    // A non-finite goal.
    let mut task = Arm3::paper_task(TaskKind::Position);
    task.goal[Term::Theta.index()][1] = f64::NAN;
    assert!(matches!(
        control_confidence(&tool, &task),
        Err(model::Error::InvalidGoal { .. })
    ));
}

#[test]
fn invalid_episode_options_give_typed_errors() {
    let tool = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    // Options and learning rate.
    let task = Arm3::paper_task(TaskKind::Position);
    let bad = EpisodeOptionsN {
        dt: -0.1,
        ..EpisodeOptionsN::paper::<Arm3, 6, 9>()
    };
    assert!(matches!(
        simulate(&tool, &task, &bad),
        Err(model::ModelSimulationError::Input(Error::OutOfRange { .. }))
    ));
    let bad = EpisodeOptionsN {
        learning_rate: 0.0,
        ..EpisodeOptionsN::paper::<Arm3, 6, 9>()
    };
    assert!(matches!(
        simulate(&tool, &task, &bad),
        Err(model::ModelSimulationError::Input(Error::OutOfRange { .. }))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random valid arm3 tools never panic: confidence and a short episode give a value or a
    /// typed error, and an episode that succeeds has finite metrics.
    #[test]
    fn random_arm3_tools_never_panic(
        params in prop::array::uniform6(0.05f64..2.0),
        kind in prop::sample::select(TaskKind::ALL.to_vec()),
        perturbation in -1.0f64..1.0,
    ) {
        let tool = Arm3Tool::new(params).unwrap();
        let task = Arm3::paper_task(kind);
        let c = control_confidence(&tool, &task).unwrap();
        prop_assert!(c.logdet.is_finite());
        let options = EpisodeOptionsN {
            t_end: 1.0,
            perturbation,
            ..EpisodeOptionsN::paper::<Arm3, 6, 9>()
        };
        if let Ok(m) = simulate(&tool, &task, &options) {
            prop_assert!(m.task_error.is_finite() && m.free_energy.is_finite());
        }
    }
}

#[test]
fn a_set_of_only_arm2_is_the_two_link_stream() {
    let mixed = draw_mixed_tools(&[ModelKind::Arm2], 20, 5).unwrap();
    let plain = draw_tools(20, 5);
    for (m, p) in mixed.iter().zip(&plain) {
        assert_eq!(*m, AnyTool::from(*p));
    }
    assert!(draw_mixed_tools(&[], 3, 0).is_err());
}

#[test]
fn mixed_draws_are_seeded_and_in_range() {
    let models = [ModelKind::Arm2, ModelKind::Arm3];
    let a = draw_mixed_tools(&models, 40, 9).unwrap();
    assert_eq!(a, draw_mixed_tools(&models, 40, 9).unwrap());
    assert_ne!(a, draw_mixed_tools(&models, 40, 10).unwrap());
    let (lo, hi) = PARAMETER_RANGE;
    let mut seen = [0; 2];
    for t in &a {
        seen[usize::from(t.model() == ModelKind::Arm3)] += 1;
        for (_, v) in t.named_parameters() {
            assert!((lo..hi).contains(&v));
        }
    }
    assert!(seen[0] > 5 && seen[1] > 5, "{seen:?}");
}

fn argmin(results: &[MixedResult], key: impl Fn(&MixedResult) -> f64) -> usize {
    (0..results.len())
        .min_by(|&a, &b| key(&results[a]).total_cmp(&key(&results[b])))
        .unwrap()
}

#[test]
fn mixed_evaluation_matches_each_models_own_runtime_and_choices() {
    let models = [ModelKind::Arm2, ModelKind::Arm3];
    let tools = draw_mixed_tools(&models, 6, 7).unwrap();
    let options = EpisodeOptions::default();
    let results = evaluate_mixed(&tools, TaskKind::Velocity, &options, Plant::Paper);
    for r in &results {
        let (arm2, arm3) = (
            r.tool.downcast::<Arm2, 2, 4, 4, 6>(),
            r.tool.downcast::<Arm3, 3, 6, 6, 9>(),
        );
        match (arm2, arm3) {
            (Some(t), _) => {
                let p = t.params();
                let arm = Arm::new([p[0], p[1], p[2], p[3]]).unwrap();
                let reference =
                    closed_loop::simulate(&arm, &Task::paper(TaskKind::Velocity), &options)
                        .unwrap();
                assert_eq!(bits(&reference.metrics), bits(r.episode.as_ref().unwrap()));
            }
            (_, Some(t)) => {
                let task = Arm3::paper_task(TaskKind::Velocity);
                let m = simulate(&t, &task, &EpisodeOptionsN::paper::<Arm3, 6, 9>()).unwrap();
                assert_eq!(bits(&m), bits(r.episode.as_ref().unwrap()));
            }
            _ => unreachable!("{} was not drawn", r.tool),
        }
        let per_joint = r.logdet_per_joint().unwrap();
        assert_eq!(
            per_joint,
            r.logdet.clone().unwrap() / r.model().dof() as f64
        );
    }
    let ok = |r: &MixedResult| r.episode.clone().unwrap();
    assert_eq!(
        MixedObjective::FreeEnergy.choose(&results),
        Some(argmin(&results, |r| ok(r).free_energy))
    );
    assert_eq!(
        MixedObjective::CostJ.choose(&results),
        Some(argmin(&results, |r| ok(r).cost_j))
    );
    assert_eq!(
        MixedObjective::Confidence.choose(&results),
        Some(argmin(&results, |r| -r.logdet.clone().unwrap()))
    );
    assert_eq!(
        MixedObjective::NormalisedConfidence.choose(&results),
        Some(argmin(&results, |r| -r.logdet_per_joint().unwrap()))
    );
}

#[test]
fn mixed_selection_snapshot() {
    let models = [ModelKind::Arm2, ModelKind::Arm3, ModelKind::Arm2Exact];
    let tools = draw_mixed_tools(&models, 6, 2024).unwrap();
    let mut text = String::new();
    // The paper's three tasks (the tip tasks' episodes are pinned in tests/tip_tasks.rs).
    for kind in TaskKind::ALL.into_iter().filter(|k| !model::reads_tip(*k)) {
        let results = evaluate_mixed(&tools, kind, &EpisodeOptions::default(), Plant::Paper);
        text.push_str(&format!("task {kind}\n"));
        for r in &results {
            let params: Vec<String> = r
                .tool
                .named_parameters()
                .iter()
                .map(|(n, v)| format!("{n}={v:.6}"))
                .collect();
            let m = r.episode.as_ref().unwrap();
            text.push_str(&format!(
                "  {} {:<10} logdet={:.9} per_joint={:.9} task_error={:.9e} int_f={:.9e} int_j={:.9e} effort={:.9e} rhs={} | {}\n",
                r.index,
                r.model().name(),
                r.logdet.as_ref().unwrap(),
                r.logdet_per_joint().unwrap(),
                m.task_error,
                m.free_energy,
                m.cost_j,
                m.control_effort,
                m.rhs_evals,
                params.join(" ")
            ));
        }
        for o in MixedObjective::ALL {
            text.push_str(&format!(
                "  chosen by {}: {:?}\n",
                o.name(),
                o.choose(&results)
            ));
        }
    }
    insta::assert_snapshot!("mixed_selection", text);
}

#[test]
fn cli_default_models_keep_the_two_link_output() {
    for json in [false, true] {
        let mut base = vec![
            "select", "--task", "position", "--tools", "4", "--seed", "3",
        ];
        if json {
            base.push("--json");
        }
        let default = toolconf(&base);
        assert!(default.status.success());
        let mut explicit = base.clone();
        explicit.extend(["--models", "arm2"]);
        assert_eq!(default.stdout, toolconf(&explicit).stdout);
        if json {
            let v: Value = serde_json::from_slice(&default.stdout).unwrap();
            assert!(v["tools"][0].get("model").is_none());
            assert!(v["choice"].get("normalised_confidence").is_none());
        }
    }
}

#[test]
fn cli_mixed_selection_json_and_text() {
    let select = [
        "select",
        "--task",
        "velocity",
        "--tools",
        "5",
        "--seed",
        "1",
        "--models",
        "arm2,arm3",
    ];
    let out = toolconf(&[&select[..], &["--json"]].concat());
    let v: Value = common::json_ok(&out);
    let tools = v["tools"].as_array().unwrap();
    assert_eq!(tools.len(), 5);
    for t in tools {
        let model = t["model"].as_str().unwrap();
        let n = if model == "arm3" { 3.0 } else { 2.0 };
        let logdet = t["logdet"].as_f64().unwrap();
        assert_eq!(t["logdet_per_joint"].as_f64().unwrap(), logdet / n);
        assert_eq!(
            t["arm"].as_object().unwrap().len(),
            if model == "arm3" { 6 } else { 4 }
        );
    }
    for key in [
        "free_energy",
        "cost_j",
        "confidence",
        "normalised_confidence",
    ] {
        assert!(v["choice"][key].is_u64(), "{key}");
    }
    let text = toolconf(&select);
    let text = String::from_utf8(text.stdout).unwrap();
    assert!(text.contains("arm3"));
    assert!(text.contains("chosen by normalised_confidence"));
    let bad = toolconf(&["select", "--task", "velocity", "--models", "arm7"]);
    assert_eq!(bad.status.code(), Some(2));
}

/// The validate-once ranking path gives exactly `control_confidence` for every tool and task, and
/// refuses an invalid task up front with the same error.
#[test]
fn validated_task_gives_the_same_confidence_as_the_checked_api() {
    for kind in TaskKind::ALL {
        let task = Task::paper(kind);
        let validated = task.validated().unwrap();
        for arm in draw_tools(200, 9) {
            let checked = toolconf_model::control_confidence(&arm, &task).unwrap();
            let fast = validated.control_confidence(&arm).unwrap();
            assert_eq!(checked.logdet.to_bits(), fast.logdet.to_bits());
            assert_eq!(checked.pi_u, fast.pi_u);
        }
        let three = Arm3::paper_task(kind).validated().unwrap();
        let tool = Arm3Tool::new([0.3, 0.4, 0.2, 0.5, 0.2, 0.3]).unwrap();
        assert_eq!(
            three.control_confidence(&tool).unwrap(),
            control_confidence(&tool, three.task()).unwrap()
        );
    }
    let mut bad = Task::paper(TaskKind::Position);
    bad.precision[Term::U.index()][(0, 1)] = 5.0;
    let expected = bad.validate().unwrap_err().to_string();
    assert_eq!(bad.validated().unwrap_err().to_string(), expected);
}
