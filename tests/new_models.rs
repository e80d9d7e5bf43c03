//! The models added only as description files (derive/models/arm2_payload.toml and msd.toml),
//! against forms derived independently here: the textbook double pendulum with a point mass at
//! the tip, energy conservation, the mass-spring-damper's analytic step response, and its
//! control confidence in closed form.

mod common;

use nalgebra::{Matrix2, SMatrix, SVector, Vector1, Vector2};
use proptest::prelude::*;
use toolconf_generated::{arm2_exact, arm2_payload, msd};
use toolconf_integrators::{solve_grid, uniform_grid, Options};

const G: f64 = 9.81;

/// Two uniform rods (absolute angles from the horizontal) with a point mass mp at the tip:
/// the rods' textbook terms plus mp·|v_tip|²/2 and mp·g·y_tip, worked out by hand.
fn textbook_with_payload(
    x: &SVector<f64, 4>,
    u: &Vector2<f64>,
    p: &SVector<f64, 5>,
) -> Vector2<f64> {
    let (t1, t2, w1, w2) = (x[0], x[1], x[2], x[3]);
    let (m1, m2, l1, l2, mp) = (p[0], p[1], p[2], p[3], p[4]);
    let d = t1 - t2;
    let coupling = (m2 / 2.0 + mp) * l1 * l2;
    let mass = Matrix2::new(
        (m1 / 3.0 + m2 + mp) * l1 * l1,
        coupling * d.cos(),
        coupling * d.cos(),
        (m2 / 3.0 + mp) * l2 * l2,
    );
    let coriolis = Vector2::new(coupling * d.sin() * w2 * w2, -coupling * d.sin() * w1 * w1);
    let gravity = Vector2::new(
        (m1 / 2.0 + m2 + mp) * G * l1 * t1.cos(),
        (m2 / 2.0 + mp) * G * l2 * t2.cos(),
    );
    let forces = Vector2::new(u[0] - u[1], u[1]);
    mass.try_inverse().unwrap() * (forces - coriolis - gravity)
}

proptest! {
    #[test]
    fn payload_arm_matches_the_textbook(
        t1 in -3.2..3.2f64, t2 in -3.2..3.2f64, w1 in -3.0..3.0f64, w2 in -3.0..3.0f64,
        u1 in -2.0..2.0f64, u2 in -2.0..2.0f64,
        m1 in 0.1..0.6f64, m2 in 0.1..0.6f64, l1 in 0.1..0.6f64, l2 in 0.1..0.6f64, mp in 0.0..2.0f64,
    ) {
        let x = SVector::<f64, 4>::new(t1, t2, w1, w2);
        let u = Vector2::new(u1, u2);
        let p = SVector::<f64, 5>::from([m1, m2, l1, l2, mp]);
        let got = arm2_payload::dynamics(&x, &u, &p);
        common::accelerations_match_the_textbook(&got, &textbook_with_payload(&x, &u, &p))?;
    }
}

#[test]
fn a_vanishing_payload_is_the_exact_two_link_arm() {
    let x = SVector::<f64, 4>::new(0.4, -1.1, 0.7, -2.0);
    let u = Vector2::new(0.3, -0.2);
    let arm = SVector::<f64, 4>::new(0.3, 0.4, 0.5, 0.2);
    let with = SVector::<f64, 5>::new(0.3, 0.4, 0.5, 0.2, 1e-300);
    let diff = arm2_payload::dynamics(&x, &u, &with) - arm2_exact::dynamics(&x, &u, &arm);
    assert!(diff.amax() < 1e-12, "{diff}");
}

#[test]
fn payload_arm_conserves_energy_without_torques() {
    let (m1, m2, l1, l2, mp) = (0.3, 0.4, 0.5, 0.2, 0.8);
    let p = SVector::<f64, 5>::from([m1, m2, l1, l2, mp]);
    let energy = |x: &SVector<f64, 4>| {
        let (t1, t2, w1, w2) = (x[0], x[1], x[2], x[3]);
        let (s1, c1, s2, c2) = (t1.sin(), t1.cos(), t2.sin(), t2.cos());
        let rod2 = Vector2::new(
            -l1 * s1 * w1 - l2 / 2.0 * s2 * w2,
            l1 * c1 * w1 + l2 / 2.0 * c2 * w2,
        );
        let tip = Vector2::new(-l1 * s1 * w1 - l2 * s2 * w2, l1 * c1 * w1 + l2 * c2 * w2);
        let kinetic = 0.5 * (m1 * l1 * l1 / 3.0) * w1 * w1
            + 0.5 * m2 * rod2.norm_squared()
            + 0.5 * (m2 * l2 * l2 / 12.0) * w2 * w2
            + 0.5 * mp * tip.norm_squared();
        let potential =
            G * (m1 * l1 / 2.0 * s1 + m2 * (l1 * s1 + l2 / 2.0 * s2) + mp * (l1 * s1 + l2 * s2));
        kinetic + potential
    };
    let x0 = SVector::<f64, 4>::new(-0.3, 1.2, 0.5, -1.0);
    let e0 = energy(&x0);
    let mut worst: f64 = 0.0;
    // The heavy tip makes the motion faster than the bare chains': integrate tighter than
    // tests/lagrangian.rs so that the integrator's error stays well below the bound.
    let options = Options {
        rtol: 1e-12,
        atol: 1e-12,
        ..Options::default()
    };
    solve_grid(
        |_, x: &SVector<f64, 4>| arm2_payload::dynamics(x, &Vector2::zeros(), &p),
        &x0,
        &uniform_grid(0.0, 5.0, 0.05),
        &options,
        |_, _, x| worst = worst.max((energy(x) - e0).abs()),
    )
    .unwrap();
    assert!(worst / e0.abs().max(1.0) < 1e-8, "energy drift {worst:e}");
}

#[test]
fn mass_spring_damper_step_response_is_the_textbook_one() {
    // m z'' + c z' + k z = F from rest: underdamped, z = F/k (1 − e^{−ζω t}(cos ω_d t + ζ/√(1−ζ²) sin ω_d t)).
    let (m, k, c, force) = (0.4, 2.5, 0.3, 0.7);
    let p = SVector::<f64, 3>::new(m, k, c);
    let omega = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let omega_d = omega * (1.0 - zeta * zeta).sqrt();
    let analytic = |t: f64| {
        force / k
            * (1.0
                - (-zeta * omega * t).exp()
                    * ((omega_d * t).cos()
                        + zeta / (1.0 - zeta * zeta).sqrt() * (omega_d * t).sin()))
    };
    let options = Options {
        rtol: 1e-11,
        atol: 1e-12,
        ..Options::default()
    };
    let mut worst: f64 = 0.0;
    solve_grid(
        |_, x: &SVector<f64, 2>| msd::dynamics(x, &Vector1::new(force), &p),
        &SVector::<f64, 2>::zeros(),
        &uniform_grid(0.0, 10.0, 0.05),
        &options,
        |_, t, x| worst = worst.max((x[0] - analytic(t)).abs()),
    )
    .unwrap();
    assert!(worst < 1e-8 * force / k, "max |z − analytic| = {worst:e}");
}

#[test]
fn mass_spring_damper_confidence_in_closed_form() {
    // A = [[0, 1], [−k/m, −c/m]], B = [0; 1/m]. Task 2 (the paper's choice): ∂ż/∂U = −[I O]A⁻¹B
    // = 1/k and ∂z̈/∂U = 1, so Π^U = P_ż/k² + P_z̈ + P_u. Task 1: ∂z/∂U = [I O]A⁻¹(E − B) with
    // E = [1; 1], i.e. (1 − m − c)/k, ∂ż/∂U = 1 and ∂z̈/∂U = 1.
    let (m, k, c) = (0.4, 2.5, 0.3);
    let p = SVector::<f64, 3>::new(m, k, c);
    let one = |v: f64| SMatrix::<f64, 1, 1>::new(v);
    let (pd, pdd, pu) = (50.0, 1.0, 1.0);
    let velocity = msd::velocity_control_confidence(&p, &one(pd), &one(pdd), &one(pu))[(0, 0)];
    let want = pd / (k * k) + pdd + pu;
    assert!(
        (velocity - want).abs() <= 1e-14 * want,
        "{velocity} vs {want}"
    );

    let pt = 80.0;
    let position =
        msd::position_control_confidence(&p, &one(pt), &one(pd), &one(pdd), &one(pu))[(0, 0)];
    let s = (1.0 - m - c) / k;
    let want = pt * s * s + pd + pdd + pu;
    assert!(
        (position - want).abs() <= 1e-13 * want,
        "{position} vs {want}"
    );
    assert_eq!(msd::acceleration_sensitivity(&p), one(1.0));
}
