//! The n-link models derived by Lagrangian mechanics, against forms derived independently:
//! the textbook compound double pendulum (uniform rods) and conservation of energy.

mod common;

use nalgebra::{Matrix2, SVector, Vector2};
use proptest::prelude::*;
use toolconf_generated::{arm2_exact, arm3};
use toolconf_integrators::{solve_grid, uniform_grid, Options};

const G: f64 = 9.81;

/// The compound double pendulum of two uniform rods with absolute angles θ measured from the
/// horizontal (textbook form, e.g. Goldstein-style Lagrangian with I = m l²/12 about the centre):
/// M(θ)θ̈ + c(θ, θ̇) + G(θ) = Q, Q = [T1 − T2, T2].
fn textbook(x: &SVector<f64, 4>, u: &Vector2<f64>, p: &SVector<f64, 4>) -> Vector2<f64> {
    let (t1, t2, w1, w2) = (x[0], x[1], x[2], x[3]);
    let (m1, m2, l1, l2) = (p[0], p[1], p[2], p[3]);
    let d = t1 - t2;
    let mass = Matrix2::new(
        (m1 / 3.0 + m2) * l1 * l1,
        0.5 * m2 * l1 * l2 * d.cos(),
        0.5 * m2 * l1 * l2 * d.cos(),
        m2 * l2 * l2 / 3.0,
    );
    let coriolis = Vector2::new(
        0.5 * m2 * l1 * l2 * d.sin() * w2 * w2,
        -0.5 * m2 * l1 * l2 * d.sin() * w1 * w1,
    );
    let gravity = Vector2::new(
        (m1 / 2.0 + m2) * G * l1 * t1.cos(),
        0.5 * m2 * G * l2 * t2.cos(),
    );
    let forces = Vector2::new(u[0] - u[1], u[1]);
    mass.try_inverse().unwrap() * (forces - coriolis - gravity)
}

/// Kinetic plus potential energy of a chain of uniform rods, from the rods' centres directly.
fn energy<const N: usize>(q: &[f64], q_dot: &[f64], masses: &[f64], lengths: &[f64]) -> f64 {
    let (mut x_dot, mut y_dot, mut y) = (0.0, 0.0, 0.0);
    let mut e = 0.0;
    for i in 0..N {
        let (s, c) = q[i].sin_cos();
        let half = lengths[i] / 2.0;
        let (vx, vy) = (x_dot - half * s * q_dot[i], y_dot + half * c * q_dot[i]);
        e += 0.5 * masses[i] * (vx * vx + vy * vy)
            + 0.5 * (masses[i] * lengths[i] * lengths[i] / 12.0) * q_dot[i] * q_dot[i];
        e += masses[i] * G * (y + half * s);
        x_dot -= lengths[i] * s * q_dot[i];
        y_dot += lengths[i] * c * q_dot[i];
        y += lengths[i] * s;
    }
    e
}

proptest! {
    #[test]
    fn exact_two_link_matches_the_textbook_double_pendulum(
        t1 in -3.2..3.2f64, t2 in -3.2..3.2f64, w1 in -3.0..3.0f64, w2 in -3.0..3.0f64,
        u1 in -2.0..2.0f64, u2 in -2.0..2.0f64,
        m1 in 0.1..0.6f64, m2 in 0.1..0.6f64, l1 in 0.1..0.6f64, l2 in 0.1..0.6f64,
    ) {
        let x = SVector::<f64, 4>::new(t1, t2, w1, w2);
        let u = Vector2::new(u1, u2);
        let p = SVector::<f64, 4>::new(m1, m2, l1, l2);
        let got = arm2_exact::dynamics(&x, &u, &p);
        common::accelerations_match_the_textbook(&got, &textbook(&x, &u, &p))?;
    }
}

#[test]
fn the_papers_model_shares_the_statics_but_not_the_dynamics() {
    // The paper's link 2 ignores its pivot's acceleration: the two models share the equilibrium
    // and the statics, not the dynamics.
    let p = SVector::<f64, 4>::new(0.3, 0.4, 0.5, 0.2);
    let xe = SVector::<f64, 4>::from(arm2_exact::EQUILIBRIUM_STATE);
    assert!(arm2_exact::dynamics(&xe, &Vector2::zeros(), &p).amax() < 1e-12);
    let exact = arm2_exact::velocity_sensitivity(&p).0;
    let paper = toolconf_generated::arm2::velocity_sensitivity(&p).0;
    // Statics: −[I O]A⁻¹B = (∂G/∂θ)⁻¹S does not involve the mass matrix, so task 2's sensitivity agrees.
    assert!((exact - paper).amax() < 1e-12 * paper.amax());
    assert!(
        (arm2_exact::state_matrix(&p) - toolconf_generated::arm2::state_matrix(&p)).amax() > 1.0
    );
}

fn energy_drift<const D: usize, const N: usize>(
    rhs: impl Fn(&SVector<f64, D>) -> SVector<f64, D>,
    x0: SVector<f64, D>,
    masses: &[f64],
    lengths: &[f64],
) -> f64 {
    let grid = uniform_grid(0.0, 5.0, 0.05);
    let options = Options {
        rtol: 1e-10,
        atol: 1e-10,
        ..Options::default()
    };
    let e0 = energy::<N>(&x0.as_slice()[..N], &x0.as_slice()[N..], masses, lengths);
    let mut worst: f64 = 0.0;
    solve_grid(
        |_, x: &SVector<f64, D>| rhs(x),
        &x0,
        &grid,
        &options,
        |_, _, x| {
            let e = energy::<N>(&x.as_slice()[..N], &x.as_slice()[N..], masses, lengths);
            worst = worst.max((e - e0).abs());
        },
    )
    .unwrap();
    worst / e0.abs().max(1.0)
}

#[test]
fn energy_is_conserved_without_torques() {
    let p2 = SVector::<f64, 4>::new(0.3, 0.4, 0.5, 0.2);
    let x2 = SVector::<f64, 4>::new(-0.3, 1.2, 0.5, -1.0);
    let drift2 = energy_drift::<4, 2>(
        |x| arm2_exact::dynamics(x, &Vector2::zeros(), &p2),
        x2,
        &[0.3, 0.4],
        &[0.5, 0.2],
    );
    assert!(drift2 < 1e-8, "2-link energy drift {drift2:e}");

    let p3 = SVector::<f64, 6>::new(0.3, 0.4, 0.2, 0.5, 0.2, 0.35);
    let x3 = SVector::<f64, 6>::new(-0.3, 1.2, 0.4, 0.5, -1.0, 2.0);
    let drift3 = energy_drift::<6, 3>(
        |x| arm3::dynamics(x, &SVector::<f64, 3>::zeros(), &p3),
        x3,
        &[0.3, 0.4, 0.2],
        &[0.5, 0.2, 0.35],
    );
    assert!(drift3 < 1e-8, "3-link energy drift {drift3:e}");

    // The paper's generative process is not a conservative mechanical system: its link-2
    // equation ignores the pivot's acceleration, so its "energy" drifts at the same tolerance.
    let paper = energy_drift::<4, 2>(
        |x| toolconf_generated::arm2::dynamics(x, &Vector2::zeros(), &p2),
        x2,
        &[0.3, 0.4],
        &[0.5, 0.2],
    );
    assert!(
        paper > 1e3 * drift2,
        "paper model drift {paper:e} vs exact {drift2:e}"
    );
}

#[test]
fn three_link_hangs_at_rest_and_its_task3_confidence_is_tool_independent() {
    let p = SVector::<f64, 6>::new(0.3, 0.4, 0.2, 0.5, 0.2, 0.35);
    let xe = SVector::<f64, 6>::from(arm3::EQUILIBRIUM_STATE);
    assert!(arm3::dynamics(&xe, &SVector::<f64, 3>::zeros(), &p).amax() < 1e-12);
    assert_eq!(
        arm3::acceleration_sensitivity(&p),
        nalgebra::Matrix3::identity()
    );
}
