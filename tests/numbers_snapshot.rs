//! A numeric table of A, B, the task sensitivities and Π^U for a fixed list of tools, per task,
//! pinned by an insta snapshot: a change in the derivation that moves any number is a reviewed diff.

use std::fmt::Write;
use toolconf_model::Term;

use toolconf_model::{control_confidence, Arm, Task, TaskKind};

/// Tools spanning the paper's parameter domain [0.1, 0.6], corners and the CLI example.
const TOOLS: [[f64; 4]; 5] = [
    [0.3, 0.4, 0.5, 0.2],
    [0.1, 0.1, 0.1, 0.1],
    [0.6, 0.6, 0.6, 0.6],
    [0.1, 0.6, 0.6, 0.1],
    [0.55, 0.15, 0.25, 0.45],
];

fn row(name: &str, values: impl IntoIterator<Item = f64>) -> String {
    let cells: Vec<String> = values.into_iter().map(|v| format!("{v:.12e}")).collect();
    format!("  {name:<16} {}\n", cells.join(" "))
}

#[test]
fn linearisation_sensitivities_and_confidence_table() {
    let mut out = String::new();
    for [m1, m2, l1, l2] in TOOLS {
        let arm = Arm::new([m1, m2, l1, l2]).unwrap();
        writeln!(out, "arm {arm}").unwrap();
        let a = arm.state_matrix();
        let b = arm.input_matrix();
        out += &row("A[3,:]", a.row(2).iter().copied());
        out += &row("A[4,:]", a.row(3).iter().copied());
        out += &row("B[3,:]", b.row(2).iter().copied());
        out += &row("B[4,:]", b.row(3).iter().copied());
        for kind in TaskKind::ALL {
            let s = arm.sensitivities(kind);
            let c = control_confidence(&arm, &Task::paper(kind)).unwrap();
            writeln!(out, " task {kind}").unwrap();
            for (name, m) in [
                ("dtheta/dU", s.of(Term::Theta)),
                ("dthetadot/dU", s.of(Term::ThetaDot)),
                ("dthetaddot/dU", s.of(Term::ThetaDdot)),
            ] {
                if let Some(m) = m {
                    out += &row(name, m.transpose().iter().copied());
                }
            }
            out += &row("Pi^U", c.pi_u.transpose().iter().copied());
            out += &row("ln|Pi^U|", [c.logdet]);
        }
    }
    insta::assert_snapshot!(out);
}

/// The Lagrangian models' linearisation and Π^U for the paper's default precisions, per task.
#[test]
fn lagrangian_models_table() {
    use nalgebra::{SMatrix, SVector};
    use toolconf_generated::{arm2_exact, arm3};

    fn rows<const R: usize, const C: usize>(name: &str, m: &SMatrix<f64, R, C>) -> String {
        (0..R)
            .map(|i| row(&format!("{name}[{}]", i + 1), m.row(i).iter().copied()))
            .collect()
    }

    let mut out = String::new();
    // A model's A, B and Π^U rows at each parameter vector: the generated module, its joint
    // count and its parameter count.
    macro_rules! model_rows {
        ($model:ident, $n:literal, $np:literal, $params:expr) => {
            for p in $params {
                let p = SVector::<f64, $np>::from(p);
                writeln!(out, "{} {:?}", stringify!($model), p.as_slice()).unwrap();
                out += &rows("A", &$model::state_matrix(&p));
                out += &rows("B", &$model::input_matrix(&p));
                let eye = SMatrix::<f64, $n, $n>::identity();
                out += &rows(
                    "Pi^U position",
                    &$model::position_control_confidence(
                        &p,
                        &(100.0 * eye),
                        &(50.0 * eye),
                        &eye,
                        &eye,
                    ),
                );
                out += &rows(
                    "Pi^U velocity",
                    &$model::velocity_control_confidence(&p, &(50.0 * eye), &eye, &eye),
                );
            }
        };
    }
    model_rows!(
        arm2_exact,
        2,
        4,
        [[0.3, 0.4, 0.5, 0.2], [0.1, 0.6, 0.6, 0.1]]
    );
    model_rows!(
        arm3,
        3,
        6,
        [
            [0.3, 0.4, 0.2, 0.5, 0.2, 0.35],
            [0.6, 0.1, 0.3, 0.1, 0.6, 0.2],
        ]
    );
    insta::assert_snapshot!(out);
}
