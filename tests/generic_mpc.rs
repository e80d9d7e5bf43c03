//! The MPC baseline over the model-generic runtime: the paper's arm's plant choice runs it on the
//! chosen model, and it runs the 3-link arm.

use toolconf::mpc::{simulate_mpc, simulate_mpc_on, MpcOptions, MpcSimulationError, SimulateMpc};
use toolconf_model::closed_loop::{EpisodeOptions, Plant};
use toolconf_model::model::{Arm2, Arm2Exact, Arm3, Arm3Tool, ArmModel, EpisodeOptionsN};
use toolconf_model::{Arm, Task, TaskKind};

#[test]
fn the_plant_choice_runs_the_generic_mpc_episode_on_that_model() {
    let arm = Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let mpc = MpcOptions::default();
    for kind in toolconf::mpc::tasks() {
        let options = EpisodeOptions {
            perturbation: -0.8,
            record_trajectory: true,
            ..EpisodeOptions::default()
        };
        let task = Task::paper(kind);
        let paper = Plant::Paper
            .simulate_mpc(&arm, &task, &options, &mpc)
            .unwrap();
        let exact = Plant::Exact
            .simulate_mpc(&arm, &task, &options, &mpc)
            .unwrap();
        let default_plant = simulate_mpc(&arm, &task, &options, &mpc).unwrap();
        assert_eq!(
            paper.trajectory, default_plant.trajectory,
            "{kind}: the paper's plant by default"
        );
        let on_arm2 = simulate_mpc_on::<Arm2, Arm2, 2, 4, 4, 6>(&arm, &task, &options, &mpc);
        let on_exact = simulate_mpc_on::<Arm2, Arm2Exact, 2, 4, 4, 6>(&arm, &task, &options, &mpc);
        for (chosen, generic) in [(&paper, on_arm2.unwrap()), (&exact, on_exact.unwrap())] {
            let (r, g) = (&chosen.metrics, &generic.metrics);
            for (a, b) in [
                (r.task_error, g.task_error),
                (r.cost_j, g.cost_j),
                (r.free_energy, g.free_energy),
                (r.control_effort, g.control_effort),
                (r.logdet, g.logdet),
            ] {
                assert_eq!(a.to_bits(), b.to_bits(), "{kind}");
            }
            assert_eq!(r.disturbance_estimate, g.disturbance_estimate);
            assert_eq!((r.rhs_evals, r.qp_solves), (g.rhs_evals, g.qp_solves));
            assert_eq!(chosen.trajectory, generic.trajectory);
        }
        assert_ne!(
            paper.metrics.task_error, exact.metrics.task_error,
            "{kind}: the plants differ"
        );
    }
}

#[test]
fn arm3_mpc_runs_with_finite_metrics() {
    let tool = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    let options = EpisodeOptionsN {
        t_end: 1.0,
        ..EpisodeOptionsN::paper::<Arm3, 6, 9>()
    };
    for kind in toolconf::mpc::tasks() {
        let task = Arm3::paper_task(kind);
        let episode = simulate_mpc_on::<Arm3, Arm3, 3, 6, 6, 9>(
            &tool,
            &task,
            &options,
            &MpcOptions::default(),
        )
        .unwrap();
        let m = &episode.metrics;
        assert_eq!(m.qp_solves, 21, "{kind}");
        for v in [
            m.task_error,
            m.cost_j,
            m.free_energy,
            m.control_effort,
            m.logdet,
        ] {
            assert!(v.is_finite(), "{kind}: {m:?}");
        }
        assert!(m.disturbance_estimate.iter().all(|d| d.is_finite()));
    }
    // Errors name the model and the tool.
    let bad = MpcOptions {
        horizon: 0.0,
        ..MpcOptions::default()
    };
    let err = simulate_mpc_on::<Arm3, Arm3, 3, 6, 6, 9>(
        &tool,
        &Arm3::paper_task(TaskKind::Position),
        &options,
        &bad,
    )
    .unwrap_err();
    assert!(matches!(err, MpcSimulationError::Setup { .. }), "{err:?}");
    assert!(err.to_string().starts_with("MPC for arm3(m1=0.3 "), "{err}");
}
