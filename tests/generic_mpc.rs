//! The MPC baseline over the model-generic runtime: with `Arm2` it is the 2-link
//! `simulate_mpc` bit for bit, and it runs the 3-link arm.

use toolconf::closed_loop::{EpisodeOptions, Plant};
use toolconf::model::{
    Arm2, Arm2Exact, Arm2Tool, Arm3, Arm3Tool, ArmModel, EpisodeOptionsN, TaskN,
};
use toolconf::mpc::{simulate_mpc, simulate_mpc_on, MpcOptions, MpcSimulationError};
use toolconf::{Arm, Task, TaskKind};

#[test]
fn arm2_mpc_is_the_two_link_mpc_bit_for_bit() {
    let arm = Arm::new(0.3, 0.4, 0.5, 0.2).unwrap();
    let tool = Arm2Tool::from(&arm);
    for kind in TaskKind::ALL {
        for plant in [Plant::Paper, Plant::Exact] {
            let options = EpisodeOptions {
                perturbation: -0.8,
                plant,
                record_trajectory: true,
                ..EpisodeOptions::default()
            };
            let task = Task::paper(kind);
            let reference = simulate_mpc(&arm, &task, &options, &MpcOptions::default()).unwrap();
            let generic_options = EpisodeOptionsN::from(&options);
            let task = TaskN::from(&task);
            let generic = match plant {
                Plant::Paper => simulate_mpc_on::<Arm2, Arm2, 2, 4, 4, 6>(
                    &tool,
                    &task,
                    &generic_options,
                    &MpcOptions::default(),
                ),
                Plant::Exact => simulate_mpc_on::<Arm2, Arm2Exact, 2, 4, 4, 6>(
                    &tool,
                    &task,
                    &generic_options,
                    &MpcOptions::default(),
                ),
            }
            .unwrap();
            let (r, g) = (&reference.metrics, &generic.metrics);
            for (a, b) in [
                (r.task_error, g.task_error),
                (r.cost_j, g.cost_j),
                (r.free_energy, g.free_energy),
                (r.control_effort, g.control_effort),
                (r.logdet, g.logdet),
            ] {
                assert_eq!(a.to_bits(), b.to_bits(), "{kind} {plant:?}");
            }
            assert_eq!(r.disturbance_estimate, g.disturbance_estimate);
            assert_eq!((r.rhs_evals, r.qp_solves), (g.rhs_evals, g.qp_solves));
            assert_eq!(reference.trajectory, generic.trajectory);
        }
    }
}

#[test]
fn arm3_mpc_runs_with_finite_metrics() {
    let tool = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    let options = EpisodeOptionsN {
        t_end: 1.0,
        ..EpisodeOptionsN::paper::<Arm3, 6, 9>()
    };
    for kind in TaskKind::ALL {
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
