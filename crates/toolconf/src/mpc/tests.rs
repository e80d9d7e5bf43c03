//! Unit tests of the MPC controller: the QP against LQR and closed forms, bounds, memory,
//! determinism, bad options.

use super::qp::StageCost;
use super::*;
use toolconf_generated::arm2;
use toolconf_model::model::{Arm2, ArmModel};
use toolconf_model::{Arm, State, Task, TaskKind, Vector2};

fn arms() -> [Arm; 3] {
    [
        Arm::new([0.3, 0.3, 0.3, 0.3]).unwrap(),
        Arm::new([0.1, 0.6, 0.5, 0.2]).unwrap(),
        Arm::new([0.6, 0.1, 0.1, 0.6]).unwrap(),
    ]
}

fn states() -> [State; 3] {
    let xe = Arm2::equilibrium_state();
    [
        xe,
        xe + State::new(0.3, -0.2, 0.5, -1.0),
        State::new(1.0, 0.5, 0.0, 2.0),
    ]
}

/// The equilibrium model without observer and without the bound: the linear-quadratic
/// problem the Riccati reference solves.
fn unconstrained() -> MpcOptions {
    MpcOptions {
        torque_limit: f64::INFINITY,
        ..MpcOptions::original_linear()
    }
}

#[test]
fn unconstrained_mpc_equals_finite_horizon_lqr() {
    let options = unconstrained();
    for arm in arms() {
        let (a, b, xe) = (
            arm.state_matrix(),
            arm.input_matrix(),
            Arm2::equilibrium_state(),
        );
        let model = discretise(&a, &b, &(-a * xe), options.period);
        for kind in crate::mpc::tasks() {
            let task = Task::paper(kind);
            let cost = StageCost::new(&a, &b, &(-a * xe), &task, options.period);
            let mut mpc = Mpc::new(&arm, &task, &options).unwrap();
            assert_eq!(mpc.horizon_steps(), 20);
            for x in states() {
                let u0 = mpc.control(&x).unwrap();
                let reference = lqr::plan(&model, &cost, mpc.horizon_steps(), &x);
                let scale = reference.iter().map(|u| u.amax()).fold(1.0, f64::max);
                assert_eq!(mpc.last_solve().status, "Solved");
                assert_eq!(mpc.last_plan().len(), reference.len());
                assert_eq!(u0, mpc.last_plan()[0]);
                for (k, (got, want)) in mpc.last_plan().iter().zip(&reference).enumerate() {
                    let error = (got - want).amax();
                    assert!(
                        error < 1e-6 * scale,
                        "{arm} {kind} x={x:?} k={k}: {got:?} vs LQR {want:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn torque_bound_holds_and_is_active_far_from_goal() {
    for arm in arms() {
        for kind in crate::mpc::tasks() {
            let mut mpc = Mpc::new(&arm, &Task::paper(kind), &MpcOptions::default()).unwrap();
            for x in states() {
                mpc.control(&x).unwrap();
                assert_eq!(mpc.last_plan().len(), 20);
                for u in mpc.last_plan() {
                    assert!(u.amax() <= 5.0 + 1e-7, "{arm} {kind}: {u:?} exceeds 5 Nm");
                }
            }
        }
    }
    // θ = [3, 2] is 2 and 1.5 rad past θ^g of task 1: the unconstrained optimum asks for
    // more than 5 Nm on these arms, so the bounded one must saturate.
    let task = Task::paper(TaskKind::Position);
    let x = State::new(3.0, 2.0, 0.0, 0.0);
    for arm in [Arm::new([0.6, 0.6, 0.6, 0.6]).unwrap(), arms()[1]] {
        let free = Mpc::new(&arm, &task, &unconstrained())
            .unwrap()
            .control(&x)
            .unwrap();
        assert!(
            free.amax() > 5.0,
            "{arm}: unconstrained u0 {free:?} would not test the bound"
        );
        let bounded = Mpc::new(&arm, &task, &MpcOptions::default())
            .unwrap()
            .control(&x)
            .unwrap();
        assert!(
            (bounded.amax() - 5.0).abs() < 1e-6,
            "{arm}: u0 {bounded:?} not at the bound"
        );
    }
}

#[test]
fn same_inputs_give_bitwise_identical_controls() {
    // The original linear MPC is memoryless: a call depends on its state only.
    let arm = arms()[1];
    let task = Task::paper(TaskKind::Velocity);
    let [x1, x2, _] = states();
    let options = MpcOptions::original_linear();
    let mut first = Mpc::new(&arm, &task, &options).unwrap();
    let mut second = Mpc::new(&arm, &task, &options).unwrap();
    let u = first.control(&x1).unwrap();
    let plan = first.last_plan().to_vec();
    assert_eq!(
        second.control(&x1).unwrap().map(f64::to_bits),
        u.map(f64::to_bits)
    );
    // The in-place update leaves no trace: re-solving x1 after x2 is the same computation.
    first.control(&x2).unwrap();
    assert_eq!(
        first.control(&x1).unwrap().map(f64::to_bits),
        u.map(f64::to_bits)
    );
    let bits = |p: &[Vector2]| {
        p.iter()
            .flat_map(|u| u.iter().map(|v| v.to_bits()))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(first.last_plan()), bits(&plan));
}

#[test]
fn invalid_options_name_the_value() {
    let arm = arms()[0];
    let task = Task::paper(TaskKind::Position);
    let d = MpcOptions::default();
    let cases = [
        (MpcOptions { period: 0.0, ..d }, "period = 0"),
        (MpcOptions { period: -0.05, ..d }, "period = -0.05"),
        (
            MpcOptions {
                period: f64::NAN,
                ..d
            },
            "period = NaN",
        ),
        (MpcOptions { horizon: 0.01, ..d }, "horizon = 0.01"),
        (
            MpcOptions {
                horizon: f64::NAN,
                ..d
            },
            "horizon = NaN",
        ),
        (
            MpcOptions {
                horizon: f64::INFINITY,
                ..d
            },
            "horizon = inf",
        ),
        (
            MpcOptions {
                torque_limit: f64::NAN,
                ..d
            },
            "torque_limit = NaN",
        ),
        (
            MpcOptions {
                torque_limit: 0.0,
                ..d
            },
            "torque_limit = 0",
        ),
        (MpcOptions { horizon: 1e6, ..d }, "horizon / period = 1e6"),
        (
            MpcOptions {
                observer_gain: 0.0,
                ..d
            },
            "observer_gain = 0",
        ),
        (
            MpcOptions {
                observer_gain: 1.5,
                ..d
            },
            "observer_gain = 1.5",
        ),
        (
            MpcOptions {
                observer_gain: f64::NAN,
                ..d
            },
            "observer_gain = NaN",
        ),
    ];
    for (options, named) in cases {
        match Mpc::new(&arm, &task, &options) {
            Err(MpcError::InvalidOptions { reason }) => {
                assert!(reason.contains(named), "{reason:?} lacks {named:?}")
            }
            other => panic!(
                "{options:?}: expected InvalidOptions, got {:?}",
                other.map(|_| ())
            ),
        }
    }
}

#[test]
fn non_finite_state_is_a_solve_error_with_its_step() {
    let mut mpc = Mpc::new(
        &arms()[0],
        &Task::paper(TaskKind::Position),
        &MpcOptions::default(),
    )
    .unwrap();
    mpc.control(&Arm2::equilibrium_state()).unwrap();
    let err = mpc
        .control(&State::new(f64::NAN, 0.0, 0.0, 0.0))
        .unwrap_err();
    assert!(matches!(err, MpcError::Solve { step: 1, .. }), "{err:?}");
    assert!(mpc.last_plan().is_empty());
}

#[test]
fn local_model_at_the_equilibrium_is_the_equilibrium_model() {
    let xe = Arm2::equilibrium_state();
    for arm in arms() {
        // The generated Jacobian at (X^e, 0) is the paper's A, B, and f(X^e, 0) = 0.
        let (a, b) = arm2::dynamics_jacobian(&xe, &Vector2::zeros(), &arm.params());
        assert!((a - arm.state_matrix()).amax() < 1e-12 * arm.state_matrix().amax());
        assert!((b - arm.input_matrix()).amax() < 1e-12 * arm.input_matrix().amax());
        assert!(arm.dynamics(&xe, &Vector2::zeros()).amax() < 1e-12);
        for kind in crate::mpc::tasks() {
            let task = Task::paper(kind);
            let mut reference = Mpc::new(&arm, &task, &MpcOptions::original_linear()).unwrap();
            let want = reference.control(&xe).unwrap();
            let scale = want.amax().max(1.0);
            for observer in [false, true] {
                let options = MpcOptions {
                    model: MpcModel::Local,
                    disturbance_observer: observer,
                    ..MpcOptions::default()
                };
                // First call: u_prev = 0, d̂ = 0, so the QP is re-linearised at (X^e, 0).
                let mut local = Mpc::new(&arm, &task, &options).unwrap();
                let got = local.control(&xe).unwrap();
                assert!(
                    (got - want).amax() < 1e-9 * scale,
                    "{arm} {kind} observer={observer}: {got:?} vs {want:?}"
                );
                for (g, w) in local.last_plan().iter().zip(reference.last_plan()) {
                    assert!((g - w).amax() < 1e-9 * scale, "{arm} {kind}: plan differs");
                }
            }
        }
    }
}

#[test]
fn observer_recovers_a_constant_disturbance_on_the_linear_model() {
    // Plant = the equilibrium model with ΔT added at its input: with L = 1 the first
    // update is exact (the model's one-step prediction error is Bd·ΔT), with L = ½ the
    // error halves every step.
    let arm = arms()[1];
    let task = Task::paper(TaskKind::Position);
    let (a, b, xe) = (
        arm.state_matrix(),
        arm.input_matrix(),
        Arm2::equilibrium_state(),
    );
    let plant = discretise(&a, &b, &(-a * xe), 0.05);
    let disturbance = Vector2::new(-0.3, 0.7);
    for gain in [1.0, 0.5] {
        let options = MpcOptions {
            observer_gain: gain,
            ..MpcOptions::original_linear()
        };
        let options = MpcOptions {
            disturbance_observer: true,
            ..options
        };
        let mut mpc = Mpc::new(&arm, &task, &options).unwrap();
        let mut x = xe;
        for step in 1..=40 {
            let u = mpc.control(&x).unwrap();
            x = plant.ad * x + plant.bd * (u + disturbance) + plant.cd;
            let expected = (1.0 - (1.0 - gain).powi(step - 1)) * disturbance;
            let got = mpc.disturbance_estimate();
            assert!(
                (got - expected).amax() < 1e-9,
                "L={gain}, step {step}: {got:?} vs {expected:?}"
            );
        }
        mpc.control(&x).unwrap();
        assert!((mpc.disturbance_estimate() - disturbance).amax() < 1e-9);
        mpc.reset();
        assert_eq!(mpc.disturbance_estimate(), Vector2::zeros());
    }
}

#[test]
fn local_mpc_is_reproducible_after_reset() {
    let arm = arms()[2];
    let task = Task::paper(TaskKind::Velocity);
    let mut mpc = Mpc::new(&arm, &task, &MpcOptions::default()).unwrap();
    let [_, x1, x2] = states();
    let first = [mpc.control(&x1).unwrap(), mpc.control(&x2).unwrap()];
    assert_ne!(mpc.disturbance_estimate(), Vector2::zeros());
    mpc.reset();
    let again = [mpc.control(&x1).unwrap(), mpc.control(&x2).unwrap()];
    assert_eq!(
        first.map(|u| u.map(f64::to_bits)),
        again.map(|u| u.map(f64::to_bits))
    );
}

#[test]
fn mpc_can_move_to_worker_threads() {
    // Experiments run one controller per arm on rayon's pool.
    fn send_and_sync<T: Send + Sync>() {}
    send_and_sync::<Mpc>();
}
