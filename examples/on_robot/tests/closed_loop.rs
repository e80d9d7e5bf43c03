//! The on-robot controller closes the loop against the generated dynamics of the paper's arm,
//! the ticks at 1 kHz, the plant integrated between them (classical Runge–Kutta, four steps per
//! tick, the torque held), and agrees with `toolconf simulate --method explicit` within the
//! tolerance the crate docs derive (first order in the period, measured here by Richardson's
//! method, plus ode45's own error, recorded in `reference/`).

mod reference;

use reference::{Reference, REFERENCES};
use toolconf_core::{ActiveInferenceN, ArmModel, Error, TaskN, Term};
use toolconf_on_robot::{Arm2, Arm2Controller, Arm2Tool, Arm3Controller, Arm3Tool, TaskKind};

/// Runge–Kutta steps per tick for the plant.
const PLANT_STEPS: usize = 4;
/// The paper's episode: 5 s, the output grid every 0.05 s.
const T_END: f64 = 5.0;
const GRID: f64 = 0.05;

/// What an episode of ticks measures on the paper's grid.
#[derive(Debug, Clone, Copy)]
struct Run {
    task_error: f64,
    /// θ and θ̇ at t = 5 s.
    last: [f64; 4],
}

/// One episode of the paper's controller at `rate_hz` on the arm `p`, for `kind`: X0 = X^e,
/// U0 = 0.1, γ = 1, ΔT = 0, as `toolconf simulate` runs it.
fn episode(p: [f64; 4], kind: TaskKind, rate_hz: f64) -> Run {
    let tool = Arm2Tool::new(p).unwrap();
    let task = Arm2::paper_task(kind);
    let mut controller = Arm2Controller::new(&tool, &task, 1.0, [0.1; 2], rate_hz).unwrap();
    let plant = Arm2::dynamics_coefficients(&tool.params());
    let f =
        |x: &nalgebra::Vector4<f64>, u: &nalgebra::Vector2<f64>| Arm2::dynamics_with(x, u, &plant);
    let per_sample = (GRID * rate_hz).round() as usize;
    let ticks = (T_END * rate_hz).round() as usize;
    let h = 1.0 / rate_hz / PLANT_STEPS as f64;
    let mut x = Arm2::equilibrium_state();
    let mut task_error = 0.0;
    for i in 0..=ticks {
        if i % per_sample == 0 {
            task_error += weighted_error(&task, &x);
        }
        if i == ticks {
            break;
        }
        let u = nalgebra::Vector2::from(controller.tick(&x.into()).unwrap().torque);
        for _ in 0..PLANT_STEPS {
            let k1 = f(&x, &u);
            let k2 = f(&(x + k1 * (h / 2.0)), &u);
            let k3 = f(&(x + k2 * (h / 2.0)), &u);
            let k4 = f(&(x + k3 * h), &u);
            x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
    }
    Run {
        task_error,
        last: x.into(),
    }
}

/// (e − e^g)ᵀP(e − e^g) on the task's error term (θ for task 1, θ̇ for task 2).
fn weighted_error(task: &TaskN<2>, x: &nalgebra::Vector4<f64>) -> f64 {
    let (e, p) = match task.kind {
        TaskKind::Position => (
            x.fixed_rows::<2>(0) - task.goal[Term::Theta.index()],
            task.precision[Term::Theta.index()],
        ),
        TaskKind::Velocity => (
            x.fixed_rows::<2>(2) - task.goal[Term::ThetaDot.index()],
            task.precision[Term::ThetaDot.index()],
        ),
        other => panic!("{other} is not compared here"),
    };
    e.dot(&(p * e))
}

fn check(r: &Reference) {
    let kind: TaskKind = r.task.parse().unwrap();
    let [h1, h2, h4] = [1000.0, 2000.0, 4000.0].map(|rate| episode(r.arm, kind, rate));
    let quantities = |run: &Run| {
        [
            run.task_error,
            run.last[0],
            run.last[1],
            run.last[2],
            run.last[3],
        ]
    };
    let (q1, q2, q4) = (quantities(&h1), quantities(&h2), quantities(&h4));
    let ode45 = [r.task_error, r.last[0], r.last[1], r.last[2], r.last[3]];
    let tight = [
        r.tight_task_error,
        r.tight_last[0],
        r.tight_last[1],
        r.tight_last[2],
        r.tight_last[3],
    ];
    for k in 0..5 {
        let (d1, d2) = (q1[k] - q2[k], q2[k] - q4[k]);
        let ratio = d1 / d2;
        let tolerance = 2.6 * d1.abs() + (ode45[k] - tight[k]).abs();
        let off = (q1[k] - ode45[k]).abs();
        println!("{} {} #{k}: 1 kHz {:.10e}, ode45 {:.10e}, |diff| {off:.3e} <= {tolerance:.3e} (D1 {d1:.3e}, D1/D2 {ratio:.3})", r.task, arm_text(&r.arm), q1[k], ode45[k]);
        assert!(
            (1.7..=2.3).contains(&ratio),
            "{} #{k}: not first order: D1/D2 = {ratio}",
            r.task
        );
        assert!(
            off <= tolerance,
            "{} #{k}: |{} - {}| = {off:e} > {tolerance:e}",
            r.task,
            q1[k],
            ode45[k]
        );
    }
}

fn arm_text(p: &[f64; 4]) -> String {
    format!("m1={} m2={} l1={} l2={}", p[0], p[1], p[2], p[3])
}

#[test]
fn ticks_at_1_khz_agree_with_the_continuous_controller_within_the_derived_tolerance() {
    assert!(!REFERENCES.is_empty());
    for r in &REFERENCES {
        check(r);
    }
}

/// Whether the torques of task-3 ticks at `rate_hz` stay bounded over 0.5 s on the arm `p`
/// (the core's tick directly, so a rate `ArmController::new` would refuse can be run).
fn task3_ticks_stay_bounded(p: [f64; 4], rate_hz: f64) -> bool {
    let tool = Arm2Tool::new(p).unwrap();
    let task = Arm2::paper_task(TaskKind::Acceleration);
    let controller = ActiveInferenceN::new(&tool, &task, 1.0).unwrap();
    let plant = Arm2::dynamics_coefficients(&tool.params());
    let h = 1.0 / rate_hz;
    let (mut x, mut u) = (Arm2::equilibrium_state(), nalgebra::Vector2::repeat(0.1));
    for _ in 0..(0.5 * rate_hz) as usize {
        let f = Arm2::dynamics_with(&x, &u, &plant);
        u = controller.tick(&toolconf_core::observe(&x, &f, &u), h);
        x += Arm2::dynamics_with(&x, &u, &plant) * h;
        if !(u.amax().is_finite() && u.amax() < 1e3) {
            return false;
        }
    }
    true
}

#[test]
fn a_rate_too_low_for_the_ticks_to_settle_is_refused_and_would_diverge() {
    // A light distal link on task 3 (P^θ̈ = 10): ∂θ̈2/∂T2 ~ 3/(m2 l2²) = 375 s⁻² per N m.
    let light = [0.3, 0.2, 0.5, 0.2];
    let tool = Arm2Tool::new(light).unwrap();
    let task = Arm2::paper_task(TaskKind::Acceleration);
    let refused = Arm2Controller::new(&tool, &task, 1.0, [0.1; 2], 1000.0).unwrap_err();
    assert!(
        matches!(refused, Error::InvalidOption { value, .. } if value == 1000.0),
        "{refused}"
    );
    // The lowest rate the controller accepts, to 1 Hz ...
    let accepted = |rate: f64| Arm2Controller::new(&tool, &task, 1.0, [0.1; 2], rate).is_ok();
    let (mut lo, mut hi) = (1000.0, 100_000.0);
    assert!(accepted(hi));
    while hi - lo > 1.0 {
        let mid = 0.5 * (lo + hi);
        if accepted(mid) {
            hi = mid
        } else {
            lo = mid
        }
    }
    // ... is where the ticks stop diverging: 10 % above it they settle, 10 % below they do not.
    assert!(task3_ticks_stay_bounded(light, 1.1 * hi), "rate {hi}");
    assert!(!task3_ticks_stay_bounded(light, 0.9 * hi), "rate {hi}");
    // The paper's arm on task 1 at 1 kHz is well inside.
    let paper = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    assert!(Arm2Controller::paper(&paper, TaskKind::Position).is_ok());
}

#[test]
fn bad_measurements_are_errors_and_leave_the_torque() {
    let tool = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let mut c = Arm2Controller::paper(&tool, TaskKind::Position).unwrap();
    let x = Arm2::equilibrium_state();
    c.tick(&x.into()).unwrap();
    let before = c.torque();
    for bad in [f64::NAN, f64::INFINITY] {
        let err = c.tick(&[x[0], bad, x[2], x[3]]).unwrap_err();
        assert!(err.to_string().contains("measurement"), "{err}");
        assert!(c.tick_with_acceleration(&x.into(), &[0.0, bad]).is_err());
        assert_eq!(c.torque(), before);
    }
    for rate in [0.0, -1.0, f64::NAN] {
        assert!(Arm2Controller::new(
            &tool,
            &Arm2::paper_task(TaskKind::Position),
            1.0,
            [0.1; 2],
            rate
        )
        .is_err());
    }
    assert!(Arm2Controller::new(
        &tool,
        &Arm2::paper_task(TaskKind::Position),
        1.0,
        [f64::NAN, 0.1],
        1e3
    )
    .is_err());
}

#[test]
fn the_confidence_is_the_closed_form_and_arm3_ticks_too() {
    let tool = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let mut c = Arm2Controller::paper(&tool, TaskKind::Velocity).unwrap();
    let pi = Arm2::pi_u(&Arm2::paper_task(TaskKind::Velocity), &tool.params());
    let logdet = (pi[(0, 0)] * pi[(1, 1)] - pi[(0, 1)] * pi[(1, 0)]).ln();
    let command = c.tick(&Arm2::equilibrium_state().into()).unwrap();
    assert!((command.confidence - logdet).abs() <= 1e-12 * logdet.abs());
    let three = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    let mut c3 = Arm3Controller::paper(&three, TaskKind::Position).unwrap();
    let mut x = toolconf_core::Arm3::equilibrium_state();
    let plant = toolconf_core::Arm3::dynamics_coefficients(&three.params());
    let mut last = [0.0; 3];
    for _ in 0..5000 {
        let u = nalgebra::Vector3::from(c3.tick(&x.into()).unwrap().torque);
        x += toolconf_core::Arm3::dynamics_with(&x, &u, &plant) * 1e-3;
        last = u.into();
    }
    // Task 1 of arm3 drives the joints toward θ^g = [π/3, π/3, π/6] with bounded torques.
    let goal = toolconf_core::Arm3::paper_task(TaskKind::Position).goal[Term::Theta.index()];
    let start = (toolconf_core::Arm3::equilibrium_state().fixed_rows::<3>(0) - goal).norm();
    assert!((x.fixed_rows::<3>(0) - goal).norm() < 0.5 * start, "{x}");
    assert!(last.iter().all(|u| u.is_finite() && u.abs() < 50.0));
}

/// The 2-link tool (m1, m2, l1, l2) and the state (θ, θ̇) the tip tests tick at.
const TIP_TOOL: [f64; 4] = [0.3, 0.4, 0.5, 0.2];

fn tip_state() -> nalgebra::Vector4<f64> {
    nalgebra::Vector4::new(-1.4, -1.9, 0.3, -0.2)
}

/// TIP_TOOL, the paper's task `kind` and a controller on it: γ = 1, U = (0.1, 0.1), 1 kHz.
fn tip_controller(kind: TaskKind) -> (Arm2Tool, TaskN<2>, Arm2Controller) {
    let tool = Arm2Tool::new(TIP_TOOL).unwrap();
    let task = Arm2::paper_task(kind);
    let controller = Arm2Controller::new(&tool, &task, 1.0, [0.1; 2], 1000.0).unwrap();
    (tool, task, controller)
}

/// The tick's `torque` is one step U − period·∂F/∂U of the controller from `u` (period 1 ms),
/// to 1e-12 relative (absolute below 1).
fn assert_one_step(torque: [f64; 2], u: nalgebra::Vector2<f64>, gradient: nalgebra::Vector2<f64>) {
    let expected = u - gradient * 1e-3;
    for i in 0..2 {
        let scale = expected[i].abs().max(1.0);
        assert!(
            (torque[i] - expected[i]).abs() <= 1e-12 * scale,
            "{torque:?} vs {expected}"
        );
    }
}

/// On a task on the tool's tip a tick reads the tip: its torque is U + period·U̇ with
/// U̇ = −γ(Σ Sᵀ P (term − goal) + P^U U) over y and ẏ written out from the arm's closed form
/// (y = (l1 cos θ1 + l2 cos θ2, l1 sin θ1 + l2 sin θ2), angles absolute), not the generated tip.
#[test]
fn a_tick_on_a_tip_task_reads_the_tips_closed_form() {
    let (p, x) = (TIP_TOOL, tip_state());
    let (tool, task, mut controller) = tip_controller(TaskKind::TipPosition);
    let torque = controller.tick(&x.into()).unwrap().torque;

    let (l1, l2) = (p[2], p[3]);
    let (s1, c1, s2, c2) = (x[0].sin(), x[0].cos(), x[1].sin(), x[1].cos());
    let y = nalgebra::Vector2::new(l1 * c1 + l2 * c2, l1 * s1 + l2 * s2);
    let j = nalgebra::Matrix2::new(-l1 * s1, -l2 * s2, l1 * c1, l2 * c2);
    let y_dot = j * x.fixed_rows::<2>(2);
    let s = tool.sensitivities(TaskKind::TipPosition);
    let u = nalgebra::Vector2::new(0.1, 0.1);
    let gradient = [(Term::Tip, y), (Term::TipDot, y_dot)]
        .iter()
        .map(|(term, v)| {
            let k = s.of(*term).unwrap().transpose() * task.precision[term.index()];
            k * (v - task.goal[term.index()])
        })
        .fold(task.precision[Term::U.index()] * u, |a, b| a + b);
    assert_one_step(torque, u, gradient);
}

/// On the tip acceleration task a tick with a measured θ̈ reads ÿ = J q̈ + J̇ q̇ from the arm's
/// closed form (ÿ = Σ l_i θ̈_i (−sin θ_i, cos θ_i) − l_i θ̇_i² (cos θ_i, sin θ_i), angles absolute),
/// not the generated tip and its bias.
#[test]
fn a_tick_on_the_tip_acceleration_task_reads_the_tips_closed_form() {
    let (p, x) = (TIP_TOOL, tip_state());
    let (tool, task, mut controller) = tip_controller(TaskKind::TipAcceleration);
    let q_ddot = [2.5, -4.0];
    let torque = controller
        .tick_with_acceleration(&x.into(), &q_ddot)
        .unwrap()
        .torque;

    let l = [p[2], p[3]];
    let y_ddot = (0..2).fold(nalgebra::Vector2::zeros(), |a, i| {
        let (s, c, w) = (x[i].sin(), x[i].cos(), x[2 + i]);
        a + nalgebra::Vector2::new(-s, c) * (l[i] * q_ddot[i])
            - nalgebra::Vector2::new(c, s) * (l[i] * w * w)
    });
    let s = tool.sensitivities(TaskKind::TipAcceleration);
    let k = s.of(Term::TipDdot).unwrap().transpose() * task.precision[Term::TipDdot.index()];
    let u = nalgebra::Vector2::new(0.1, 0.1);
    let gradient =
        k * (y_ddot - task.goal[Term::TipDdot.index()]) + task.precision[Term::U.index()] * u;
    assert_one_step(torque, u, gradient);
}
