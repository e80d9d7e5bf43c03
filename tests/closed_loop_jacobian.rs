//! `ClosedLoop::jacobian` (from the generated ∂f/∂X, ∂f/∂U and the controller's gains) against
//! central differences of `ClosedLoop::rhs`, on random arms, tasks, learning rates,
//! perturbations and states far from the equilibrium.

mod common;

use proptest::prelude::*;
use toolconf_model::closed_loop::{ClosedLoop, JointJacobian, JointState};
use toolconf_model::{Arm, Task, TaskKind};

/// ∂Ż/∂Z by central differences (tests/common).
fn central_differences(system: &ClosedLoop, z: &JointState) -> JointJacobian {
    common::central_differences(|z| system.rhs(z), z)
}

fn arm_strategy() -> impl Strategy<Value = Arm> {
    (0.1..0.6f64, 0.1..0.6f64, 0.1..0.6f64, 0.1..0.6f64)
        .prop_map(|(a, b, c, d)| Arm::new([a, b, c, d]).unwrap())
}

fn state_strategy() -> impl Strategy<Value = JointState> {
    (
        prop::array::uniform2(-3.2..3.2f64),
        prop::array::uniform2(-10.0..10.0f64),
        prop::array::uniform2(-20.0..20.0f64),
    )
        .prop_map(|(theta, theta_dot, u)| {
            JointState::from_column_slice(&[
                theta[0],
                theta[1],
                theta_dot[0],
                theta_dot[1],
                u[0],
                u[1],
            ])
        })
}

/// Largest entry-wise error, relative to the largest entry of its row (rows differ by orders
/// of magnitude: the U̇ rows carry the gains).
fn row_relative_error(analytic: &JointJacobian, numeric: &JointJacobian) -> f64 {
    (0..6)
        .map(|r| {
            let scale = analytic.row(r).amax().max(1.0);
            (analytic.row(r) - numeric.row(r)).amax() / scale
        })
        .fold(0.0, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn jacobian_matches_central_differences(
        arm in arm_strategy(),
        k in 0usize..3,
        learning_rate in 0.1..10.0f64,
        perturbation in -2.0..2.0f64,
        z in state_strategy(),
    ) {
        let task = Task::paper(TaskKind::ALL[k]);
        let system = ClosedLoop::new(&arm, &task, learning_rate, perturbation).unwrap();
        let analytic = system.jacobian(&z);
        let numeric = central_differences(&system, &z);
        let error = row_relative_error(&analytic, &numeric);
        prop_assert!(
            error < 1e-6,
            "{arm} {:?} γ={learning_rate} ΔT={perturbation} z={z}: error {error:e}\nanalytic {analytic}numeric {numeric}",
            task.kind
        );
    }
}

#[test]
fn jacobian_at_the_paper_initial_state_for_the_paper_arms() {
    // X0 = [−π/2 −π/2 0 0], U0 = [0.1 0.1]: the state every episode starts from.
    let z0 = JointState::from_column_slice(&[
        -std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
        0.0,
        0.0,
        0.1,
        0.1,
    ]);
    for p in [
        [0.3, 0.4, 0.5, 0.2],
        [0.1, 0.1, 0.1, 0.1],
        [0.6, 0.6, 0.6, 0.6],
    ] {
        let arm = Arm::new([p[0], p[1], p[2], p[3]]).unwrap();
        for kind in TaskKind::ALL {
            let system = ClosedLoop::new(&arm, &Task::paper(kind), 1.0, 0.0).unwrap();
            let analytic = system.jacobian(&z0);
            let error = row_relative_error(&analytic, &central_differences(&system, &z0));
            assert!(error < 1e-7, "{p:?} {kind}: error {error:e}");
            // The kinematic rows are exact: θ̇ is a state.
            for r in 0..2 {
                for c in 0..6 {
                    let expected = if c == r + 2 { 1.0 } else { 0.0 };
                    assert_eq!(analytic[(r, c)], expected, "{p:?} {kind} ({r}, {c})");
                }
            }
        }
    }
}
