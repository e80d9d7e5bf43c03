//! The MPC baseline in closed loop with the nonlinear plant.

use std::f64::consts::FRAC_PI_2;

use toolconf::closed_loop::EpisodeOptions;
use toolconf::mpc::{simulate_mpc, Mpc, MpcEpisodeError, MpcOptions};
use toolconf::{Arm, Task, TaskKind, Vector2};

fn arm() -> Arm {
    Arm::new(0.3, 0.4, 0.5, 0.2).unwrap()
}

/// A position task whose goal is near the hanging equilibrium, where the linearised model the
/// MPC plans with is accurate.
fn near_task() -> Task {
    let mut task = Task::paper(TaskKind::Position);
    task.goal_theta = Vector2::new(-FRAC_PI_2 + 0.2, -FRAC_PI_2 + 0.1);
    task
}

#[test]
fn mpc_reaches_a_goal_near_the_equilibrium_on_the_nonlinear_plant() {
    let options = EpisodeOptions {
        record_trajectory: true,
        ..EpisodeOptions::default()
    };
    let episode = simulate_mpc(&arm(), &near_task(), &options, &MpcOptions::default()).unwrap();
    let tr = episode.trajectory.unwrap();
    assert_eq!(tr.t.len(), 101);
    let goal = near_task().goal_theta;
    let start_error = (tr.theta[0] - goal).norm();
    let end_error = (tr.theta[100] - goal).norm();
    assert!(
        end_error < 0.2 * start_error,
        "θ(5) = {} vs goal {goal}",
        tr.theta[100]
    );
    assert!(
        tr.u.iter().all(|u| u.amax() <= 5.0 + 1e-6),
        "torque bound violated"
    );
    let m = episode.metrics;
    assert_eq!(m.qp_solves, 101);
    assert!(m.task_error.is_finite() && m.cost_j > 0.0 && m.control_effort > 0.0);
    assert!((m.free_energy - (m.cost_j - 2.5 * m.logdet)).abs() < 1e-9 * m.cost_j.abs().max(1.0));
}

#[test]
fn the_first_torque_is_the_controllers_answer_at_the_initial_state() {
    let options = EpisodeOptions {
        record_trajectory: true,
        ..EpisodeOptions::default()
    };
    let episode = simulate_mpc(&arm(), &near_task(), &options, &MpcOptions::default()).unwrap();
    let mut mpc = Mpc::new(&arm(), &near_task(), &MpcOptions::default()).unwrap();
    assert_eq!(
        episode.trajectory.unwrap().u[0],
        mpc.control(&options.x0).unwrap()
    );
}

#[test]
fn mpc_episodes_are_deterministic() {
    let options = EpisodeOptions {
        perturbation: 0.0,
        ..EpisodeOptions::default()
    };
    let a = simulate_mpc(&arm(), &near_task(), &options, &MpcOptions::default()).unwrap();
    let b = simulate_mpc(&arm(), &near_task(), &options, &MpcOptions::default()).unwrap();
    assert_eq!(a.metrics.task_error, b.metrics.task_error);
    assert_eq!(a.metrics.cost_j, b.metrics.cost_j);
    assert_eq!(a.metrics.qp_iterations, b.metrics.qp_iterations);
}

#[test]
fn grids_that_do_not_fit_the_control_period_are_rejected() {
    let options = EpisodeOptions {
        dt: 0.07,
        ..EpisodeOptions::default()
    };
    let err = simulate_mpc(&arm(), &near_task(), &options, &MpcOptions::default()).unwrap_err();
    assert!(matches!(err, MpcEpisodeError::Input(_)), "{err}");
    assert!(err.to_string().contains("output step dt"), "{err}");
}
