//! Identities that hold analytically, checked on the generated code with values computed
//! independently of it (finite differences, nalgebra inverses, the paper's formulas by hand).

mod common;

use nalgebra::{SMatrix, SVector};
use proptest::prelude::*;
use toolconf_model::model::{self, Arm2, ArmModel};
use toolconf_model::Term;
use toolconf_model::{control_confidence, Arm, Error, Matrix2, Task, TaskKind, Vector2};

fn arm_strategy() -> impl Strategy<Value = Arm> {
    (0.1..0.6f64, 0.1..0.6f64, 0.1..0.6f64, 0.1..0.6f64)
        .prop_map(|(a, b, c, d)| Arm::new([a, b, c, d]).unwrap())
}

fn rel(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / scale.max(f64::MIN_POSITIVE)
}

/// A = ∂f/∂X and B = ∂f/∂U by central differences of the generated dynamics at the equilibrium.
fn finite_difference_linearisation(arm: &Arm) -> (SMatrix<f64, 4, 4>, SMatrix<f64, 4, 2>) {
    let xe = Arm2::equilibrium_state();
    let ue = Vector2::zeros();
    let h = 1e-6;
    let mut a = SMatrix::<f64, 4, 4>::zeros();
    let mut b = SMatrix::<f64, 4, 2>::zeros();
    for j in 0..4 {
        let mut dx = SVector::<f64, 4>::zeros();
        dx[j] = h;
        a.set_column(
            j,
            &((arm.dynamics(&(xe + dx), &ue) - arm.dynamics(&(xe - dx), &ue)) / (2.0 * h)),
        );
    }
    for j in 0..2 {
        let mut du = Vector2::zeros();
        du[j] = h;
        b.set_column(
            j,
            &((arm.dynamics(&xe, &(ue + du)) - arm.dynamics(&xe, &(ue - du))) / (2.0 * h)),
        );
    }
    (a, b)
}

proptest! {
    #[test]
    fn equilibrium_is_a_rest_point(arm in arm_strategy()) {
        let f = arm.dynamics(&Arm2::equilibrium_state(), &Vector2::zeros());
        prop_assert!(f.amax() < 1e-12, "f(X^e, U^e) = {f}");
    }

    #[test]
    fn a_and_b_match_finite_differences_of_the_dynamics(arm in arm_strategy()) {
        let (a_fd, b_fd) = finite_difference_linearisation(&arm);
        let (a, b) = (arm.state_matrix(), arm.input_matrix());
        prop_assert!((a - a_fd).amax() <= 1e-6 * a.amax(), "A {a} vs {a_fd}");
        prop_assert!((b - b_fd).amax() <= 1e-6 * b.amax(), "B {b} vs {b_fd}");
    }

    #[test]
    fn task3_acceleration_sensitivity_is_the_identity(arm in arm_strategy()) {
        // [I O](A² A⁻¹(E − B) + AB) = [I O] A E = I for every arm: task 3's confidence is the
        // same for every tool, as the paper finds.
        let s = arm.sensitivities(TaskKind::Acceleration).of(Term::ThetaDdot).expect("task 3 uses θ̈");
        prop_assert_eq!(s, Matrix2::identity());
        let task = Task::paper(TaskKind::Acceleration);
        let c = control_confidence(&arm, &task).unwrap();
        prop_assert_eq!(c.pi_u, task.precision[Term::ThetaDdot.index()] + task.precision[Term::U.index()]);
    }

    #[test]
    fn task1_sensitivities_match_a_hand_inverse(arm in arm_strategy()) {
        // ∂X/∂U = A⁻¹([I; I] − B), by nalgebra's general 4×4 inverse.
        let a_inv = arm.state_matrix().try_inverse().expect("A invertible");
        let e = SMatrix::<f64, 4, 2>::from_row_slice(&[1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0]);
        let dx_du = a_inv * (e - arm.input_matrix());
        let s = arm.sensitivities(TaskKind::Position);
        let d_theta = s.of(Term::Theta).unwrap();
        let scale = d_theta.amax();
        for i in 0..2 {
            for j in 0..2 {
                prop_assert!(rel(d_theta[(i, j)], dx_du[(i, j)], scale) < 1e-12);
            }
        }
        prop_assert_eq!(s.of(Term::ThetaDot).unwrap(), Matrix2::identity());
        prop_assert!((dx_du.fixed_view::<2, 2>(2, 0) - Matrix2::identity()).amax() < 1e-12);
    }

    #[test]
    fn task2_velocity_sensitivity_is_the_position_block(arm in arm_strategy()) {
        let a_inv_b = arm.state_matrix().try_inverse().unwrap() * arm.input_matrix();
        let s = arm.sensitivities(TaskKind::Velocity).of(Term::ThetaDot).unwrap();
        let expected = -a_inv_b.fixed_view::<2, 2>(0, 0).into_owned();
        prop_assert!((s - expected).amax() <= 1e-12 * expected.amax());
        // The strict velocity block [O I]A⁻¹B vanishes: why the paper uses the position block.
        prop_assert!(a_inv_b.fixed_view::<2, 2>(2, 0).amax() <= 1e-12 * a_inv_b.amax());
    }

    #[test]
    fn confidence_is_symmetric_positive_definite(arm in arm_strategy(), k in 0usize..3) {
        let kind = TaskKind::ALL[k];
        let c = control_confidence(&arm, &Task::paper(kind)).unwrap();
        prop_assert_eq!(c.pi_u, c.pi_u.transpose());
        let eig = c.pi_u.symmetric_eigenvalues();
        prop_assert!(eig.min() > 0.0, "eigenvalues {eig}");
        prop_assert!(rel(c.logdet, c.pi_u.determinant().ln(), c.logdet.abs().max(1.0)) < 1e-12);
    }
}

/// Π^U for the CLI example computed by hand from the paper's formulas: A and B typed in from
/// appendix "Generative model" (with the derived A[3,1], see generated/arm2.md), task 2's
/// Π^U = ([I O]A⁻¹B)ᵀ P^θ̇ ([I O]A⁻¹B) + P^θ̈ + P^U, and A⁻¹ by block inversion:
/// A = [[O, I], [A21, O]] ⇒ [I O]A⁻¹B = A21⁻¹ B2.
#[test]
fn velocity_confidence_matches_the_paper_formula_by_hand() {
    let (m1, m2, l1, l2, g) = (0.3_f64, 0.4_f64, 0.5_f64, 0.2_f64, 9.81_f64);
    let d = m1 + 3.0 * m2;
    let a21 = Matrix2::new(
        -3.0 * (m1 + 2.0 * m2) * g / (2.0 * l1 * d),
        9.0 * m2 * g / (4.0 * l1 * d),
        0.0,
        -3.0 * g / (2.0 * l2),
    );
    let b2 = Matrix2::new(
        3.0 / (l1 * l1 * d),
        -3.0 * (3.0 * l1 + 2.0 * l2) / (2.0 * l1 * l1 * l2 * d),
        0.0,
        3.0 / (m2 * l2 * l2),
    );
    // 2×2 inverse by the adjugate.
    let det = a21[(0, 0)] * a21[(1, 1)] - a21[(0, 1)] * a21[(1, 0)];
    let a21_inv = Matrix2::new(a21[(1, 1)], -a21[(0, 1)], -a21[(1, 0)], a21[(0, 0)]) / det;
    let s = a21_inv * b2;
    let by_hand = s.transpose() * (50.0 * Matrix2::identity()) * s
        + Matrix2::identity()
        + Matrix2::identity();

    let arm = Arm::new([m1, m2, l1, l2]).unwrap();
    let c = control_confidence(&arm, &Task::paper(TaskKind::Velocity)).unwrap();
    assert!(
        (c.pi_u - by_hand).amax() <= 1e-12 * by_hand.amax(),
        "{} vs {by_hand}",
        c.pi_u
    );
    let logdet = (by_hand[(0, 0)] * by_hand[(1, 1)] - by_hand[(0, 1)] * by_hand[(1, 0)]).ln();
    assert!((c.logdet - logdet).abs() < 1e-12);
}

#[test]
fn invalid_arms_are_errors_naming_the_parameter() {
    for (arm, name) in [
        (Arm::new([0.0, 0.4, 0.5, 0.2]), "m1"),
        (Arm::new([0.3, -1.0, 0.5, 0.2]), "m2"),
        (Arm::new([0.3, 0.4, f64::NAN, 0.2]), "l1"),
        (Arm::new([0.3, 0.4, 0.5, f64::INFINITY]), "l2"),
    ] {
        match arm {
            Err(model::Error::InvalidParameter { name: got, .. }) => assert_eq!(got, name),
            other => panic!("expected an error for {name}, got {other:?}"),
        }
    }
    assert!(matches!(
        toolconf_model::arm::parse("0.3,0.4,x,0.2"),
        Err(Error::ArmSyntax { .. })
    ));
    assert!(matches!(
        toolconf_model::arm::parse("0.3,0.4,0.5"),
        Err(Error::ArmSyntax { .. })
    ));
    assert!(matches!(
        toolconf_model::arm::parse("0.3,0.4,-0.5,0.2"),
        Err(Error::Core(model::Error::InvalidParameter {
            name: "l1",
            ..
        }))
    ));
    assert_eq!(
        toolconf_model::arm::parse("0.3, 0.4,0.5 ,0.2").unwrap(),
        Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap()
    );
}

#[test]
fn invalid_tasks_are_errors() {
    let arm = Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let mut task = Task::paper(TaskKind::Position);
    task.precision[Term::Theta.index()][(0, 1)] = 3.0;
    assert!(matches!(
        control_confidence(&arm, &task),
        Err(model::Error::InvalidPrecision { .. })
    ));
    let mut task = Task::paper(TaskKind::Position);
    task.goal[Term::Theta.index()][1] = f64::NAN;
    assert!(matches!(
        control_confidence(&arm, &task),
        Err(model::Error::InvalidGoal { .. })
    ));
    // Precisions that leave Π^U singular for every tool are refused as such...
    let mut task = Task::paper(TaskKind::Acceleration);
    task.precision[Term::ThetaDdot.index()] = Matrix2::zeros();
    common::assert_rank_zero(control_confidence(&arm, &task), 2);
    // ...and a tool whose sensitivities leave a direction of U without precision gets
    // NotPositiveDefinite: with P^θ = e₁e₁ᵀ and P^U = e₂e₂ᵀ, Π^U = r rᵀ + e₂e₂ᵀ for r the first
    // row of ∂θ/∂U, whose first entry −(2/3)(l1²(m1 + 3m2) − 3)/(g l1 (m1 + 2m2)) vanishes at
    // l1 = 1, m1 + 3m2 = 3: r ∥ e₂ and Π^U is singular.
    let mut task = Task::paper(TaskKind::Position);
    task.precision[Term::Theta.index()] = Matrix2::new(1.0, 0.0, 0.0, 0.0);
    task.precision[Term::ThetaDot.index()] = Matrix2::zeros();
    task.precision[Term::ThetaDdot.index()] = Matrix2::zeros();
    task.precision[Term::U.index()] = Matrix2::new(0.0, 0.0, 0.0, 1.0);
    assert!(control_confidence(&arm, &task).is_ok());
    let singular = Arm::new([1.5, 0.5, 1.0, 0.3]).unwrap();
    assert!(matches!(
        control_confidence(&singular, &task),
        Err(model::Error::NotPositiveDefinite { .. })
    ));
    assert!(matches!(
        toolconf_model::task::parse_task("jump"),
        Err(Error::UnknownTask(ref t)) if t == "jump"
    ));
    assert_eq!("2".parse::<TaskKind>().unwrap(), TaskKind::Velocity);
}
