//! The linearised loop against the runtime's own closed loop, the prediction against episodes
//! near the equilibrium (where the linearisation is exact to first order), and the refusals.

use nalgebra::SVector;

use super::*;
use crate::inputs::task_file::TaskSpec;
use crate::model::{simulate, Arm2, ClosedLoopN, Panda};
use crate::TaskKind;

type PandaTool = ToolN<Panda, 7, 14, 13, 21>;

fn franka_hand() -> PandaTool {
    let mut p = [0.0; 13];
    p[..7].copy_from_slice(&[
        0.73,
        -0.00707107,
        0.00707107,
        0.03,
        0.00175,
        0.00175,
        0.0017,
    ]);
    p[7] = 0.00075;
    p[12] = 0.1034;
    PandaTool::new(p).unwrap()
}

fn panda_task(text: &str) -> (TaskN<7>, EpisodeOptionsN<7, 14>) {
    let spec = TaskSpec::parse(text, "t.toml").unwrap();
    let (task, _) = spec.task_and_offset::<Panda, 7, 14, 13, 21>().unwrap();
    (task, spec.episode::<Panda, 7, 14, 13, 21>().unwrap())
}

/// The linearised loop of `tool` with γ = 1 on each task, [`TOUCH`] and [`PUSH`].
fn linear_loops(tool: &PandaTool) -> [(TaskN<7>, LinearLoop<7, 14, 21>); 2] {
    [TOUCH, PUSH].map(|text| {
        let (task, _) = panda_task(text);
        let linear = LinearLoop::<7, 14, 21>::new(tool, &task, 1.0).unwrap();
        (task, linear)
    })
}

const TOUCH: &str = "kind = \"tip_position\"\n[goal]\ntip = [0.357, 0.030, 0.390]\n\
    [precision]\ntip = 1e6\ntip_dot = 4e4\nu = 0.0132\n[episode]\ninitial_torque = 0.0\n";
const PUSH: &str = "kind = \"tip_acceleration\"\n[goal]\ntip_ddot = [0.2, 0.0, 0.0]\n\
    [precision]\ntip_ddot = 2500.0\nu = 0.0132\n[episode]\nt_end = 1.0\ndt = 0.01\n\
    initial_torque = 0.0\n";

/// |a − b| ≤ tol·max(|a|, |b|, 1) entry by entry.
fn assert_close<const R: usize, const C: usize>(
    a: &nalgebra::SMatrix<f64, R, C>,
    b: &nalgebra::SMatrix<f64, R, C>,
    tol: f64,
) {
    let scale = a.amax().max(b.amax()).max(1.0);
    let gap = (a - b).amax();
    assert!(
        gap <= tol * scale,
        "gap {gap:e} > {tol:e}·{scale:e}\n{a}\n{b}"
    );
}

#[test]
fn m_is_the_runtimes_closed_loop_jacobian_at_the_equilibrium() {
    let tool = franka_hand();
    for (task, linear) in linear_loops(&tool) {
        let system = ClosedLoopN::<Panda, 7, 14, 13, 21>::new(&tool, &task, 1.0, 0.0).unwrap();
        let mut z_e = SVector::<f64, 21>::zeros();
        z_e.fixed_rows_mut::<14>(0)
            .copy_from(&Panda::equilibrium_state());
        z_e.fixed_rows_mut::<7>(14)
            .copy_from(&Panda::equilibrium_control());
        assert_close(&linear.m, &system.jacobian(&z_e), 1e-9);
    }
}

/// At X = X^e the plant is affine in U (q̈ = M(q)⁻¹(τ − …)) and the tip terms are exact, so the
/// linear ż equals the runtime's nonlinear ż for any U and ΔT.
#[test]
fn z_dot_is_the_runtimes_at_the_equilibrium_for_any_torque_and_perturbation() {
    let tool = franka_hand();
    for (task, linear) in linear_loops(&tool) {
        for (u, dt) in [(0.3, 0.0), (-1.2, 0.7), (2.0, -0.4)] {
            let perturbation = SVector::<f64, 7>::from_fn(|i, _| dt * (i as f64 - 3.0));
            let system = ClosedLoopN::<Panda, 7, 14, 13, 21>::with_perturbation(
                &tool,
                &task,
                1.0,
                &perturbation,
            )
            .unwrap();
            let mut z = SVector::<f64, 21>::zeros();
            z.fixed_rows_mut::<14>(0)
                .copy_from(&Panda::equilibrium_state());
            let torque = SVector::<f64, 7>::from_fn(|i, _| u / (1.0 + i as f64));
            z.fixed_rows_mut::<7>(14).copy_from(&torque);
            let mut dz = SVector::<f64, 21>::zeros();
            dz.fixed_rows_mut::<7>(14).copy_from(&torque);
            let linear_rate = linear.m * dz + linear.input(&perturbation);
            assert_close(&linear_rate, &system.rhs(&z), 1e-9);
        }
    }
}

/// Near the goal the episode stays where the linearisation holds: prediction and episode agree.
#[test]
fn the_prediction_is_the_episode_near_the_equilibrium() {
    let tool = franka_hand();
    let (mut task, mut options) = panda_task(TOUCH);
    let q_e = Panda::equilibrium_state().fixed_rows::<7>(0).into_owned();
    let (rest, _) = tool.tip(&q_e).unwrap();
    for i in 0..3 {
        task.goal[crate::Term::Tip.index()][i] = rest[i] + [1e-3, -5e-4, 8e-4][i];
    }
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    for t_end in [5.0, 1.03] {
        options.t_end = t_end;
        let predicted = predict(&tool, &task, &options).unwrap();
        let simulated = simulate(&tool, &task, &options).unwrap();
        for (p, s) in [
            (predicted.task_error, simulated.task_error),
            (predicted.free_energy, simulated.free_energy),
            (predicted.cost_j, simulated.cost_j),
        ] {
            assert!(
                (p / s - 1.0).abs() < 1e-2,
                "t_end {t_end}: predicted {p}, simulated {s}"
            );
        }
    }
}

#[test]
fn the_paper_arm_near_its_equilibrium() {
    let tool = ToolN::<Arm2, 2, 4, 4, 6>::new([1.0, 1.0, 1.0, 1.0]).unwrap();
    let mut task = Arm2::paper_task(TaskKind::Position);
    task.goal[crate::Term::Theta.index()] = SVector::from([-1.55, -1.6]);
    let mut options = EpisodeOptionsN::paper::<Arm2, 4, 6>();
    options.u0 = SVector::zeros();
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    let predicted = predict(&tool, &task, &options).unwrap();
    let simulated = simulate(&tool, &task, &options).unwrap();
    let gap = predicted.task_error / simulated.task_error - 1.0;
    assert!(gap.abs() < 1e-2, "{predicted:?} {simulated:?}");
}

#[test]
fn the_perturbations_effect_is_the_difference_of_two_predictions() {
    let tool = franka_hand();
    let (task, mut options) = panda_task(TOUCH);
    let calm = predict(&tool, &task, &options).unwrap();
    assert_eq!(calm.perturbation_effect, 0.0);
    options.perturbation = 0.5;
    let perturbed = predict(&tool, &task, &options).unwrap();
    let gap = perturbed.task_error - calm.task_error;
    assert!((perturbed.perturbation_effect - gap).abs() <= 1e-9 * perturbed.task_error);
    assert!(perturbed.perturbation_effect != 0.0);
}

#[test]
fn a_horizon_of_zero_is_refused() {
    let tool = franka_hand();
    let (task, mut options) = panda_task(TOUCH);
    options.t_end = 0.0;
    let e = predict(&tool, &task, &options).unwrap_err();
    assert_eq!(e, PredictionError::ZeroHorizon { t_end: 0.0 });
    assert!(e.to_string().contains("horizon of 0"), "{e}");
}

#[test]
fn an_unstable_loop_is_refused_with_its_eigenvalue() {
    let tool = franka_hand();
    let (task, _) = panda_task(TOUCH);
    let mut linear = LinearLoop::<7, 14, 21>::new(&tool, &task, 1.0).unwrap();
    assert!(spectral_abscissa(&linear).unwrap() < 0.0);
    let shift = linear.m.amax() * 1e-6 + 3.0;
    linear.m += nalgebra::SMatrix::<f64, 21, 21>::identity() * shift;
    match spectral_abscissa(&linear) {
        Err(PredictionError::Unstable { abscissa }) => assert!(abscissa > 0.0),
        other => panic!("{other:?}"),
    }
}

/// The linear systems and predictions of tests/fixtures/prediction_scipy.json, which
/// derive/tests/test_prediction_scipy.py recomputes with SciPy's `expm`: the fixture must be
/// what the code gives now (`TOOLCONF_WRITE_FIXTURES=1` rewrites it).
#[test]
fn the_scipy_fixture_is_what_the_code_gives() {
    let tool = franka_hand();
    let mut cases = Vec::new();
    for (name, text, dt) in [("panda touch", TOUCH, 0.0), ("panda push, dT", PUSH, 0.3)] {
        let (task, mut options) = panda_task(text);
        options.perturbation = dt;
        cases.push((
            name,
            LinearSystem::new(&linearise(&tool, &task, &options).unwrap(), &task, &options),
            predict(&tool, &task, &options).unwrap(),
        ));
    }
    let arm = ToolN::<Arm2, 2, 4, 4, 6>::new([1.0, 2.0, 0.8, 1.2]).unwrap();
    let task = Arm2::paper_task(TaskKind::Position);
    let mut options = EpisodeOptionsN::paper::<Arm2, 4, 6>();
    options.t_end = 1.03;
    cases.push((
        "arm2 position, t_end 1.03",
        LinearSystem::new(&linearise(&arm, &task, &options).unwrap(), &task, &options),
        predict(&arm, &task, &options).unwrap(),
    ));
    let json: Vec<serde_json::Value> = cases
        .iter()
        .map(|(name, system, p)| {
            serde_json::json!({"name": name, "system": system, "task_error": p.task_error,
                "free_energy": p.free_energy, "cost_j": p.cost_j})
        })
        .collect();
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/fixtures/prediction_scipy.json"
    );
    if std::env::var_os("TOOLCONF_WRITE_FIXTURES").is_some() {
        std::fs::write(path, serde_json::to_string(&json).unwrap() + "\n").unwrap();
    }
    let stored: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(stored.len(), json.len());
    for (s, j) in stored.iter().zip(&json) {
        for key in ["task_error", "free_energy", "cost_j"] {
            let (a, b) = (s[key].as_f64().unwrap(), j[key].as_f64().unwrap());
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                "{}: {key} {a} != {b}",
                j["name"]
            );
        }
    }
}
