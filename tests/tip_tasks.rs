//! Tasks on the tool's tip through the model-generic runtime: the controller observes
//! the tip's forward kinematics y(q), ẏ = J(q) q̇ and ÿ = J(q) q̈ + J̇ q̇, not their
//! linearisation, and ÿ is the time derivative of ẏ along the closed loop's flow; the generated
//! J̇ q̇ is the second derivative of the generated y along q̇; the closed loop's
//! Jacobian (what the stiff integrator steers by) agrees with central differences of its
//! right-hand side; the tip sensitivities are J times the joints' ones; a tip position episode
//! reaches its goal on every tool of the Panda catalogue; tools files without a tip are refused
//! by a tip task, naming the file, the row and the columns.

mod common;

use std::path::Path;

use nalgebra::{SMatrix, SVector};
use toolconf::rank::{screen_file, ModelTasks};
use toolconf_generated::Read;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::inputs::tools_file::read_tools;
use toolconf_model::model::{
    reads_tip, term_components, Arm2, Arm2Tool, Arm3, ArmModel, ClosedLoopN, Panda, PandaTool,
    TaskN, Ur5,
};
use toolconf_model::{TaskKind, Term};

fn repo(path: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The tip tasks `derive/tasks.toml` defines.
fn tip_tasks() -> Vec<TaskKind> {
    let kinds: Vec<TaskKind> = TaskKind::ALL
        .into_iter()
        .filter(|k| reads_tip(*k))
        .collect();
    assert!(
        [
            TaskKind::TipPosition,
            TaskKind::TipVelocity,
            TaskKind::TipAcceleration
        ]
        .iter()
        .all(|k| kinds.contains(k)),
        "{kinds:?}"
    );
    kinds
}

/// A Panda tool: a 0.8 kg body 5 cm out, products of inertia and its tip `tip` (flange frame).
fn panda_tool(tip: [f64; 3]) -> PandaTool {
    PandaTool::new([
        0.8, 0.004, -0.003, 0.05, 3e-3, 2.5e-3, 1.5e-3, 1e-4, -5e-5, 2e-5, tip[0], tip[1], tip[2],
    ])
    .unwrap()
}

/// ∂Ż/∂Z by central differences, column j with the step `1e-6·max(1, |z_j|)`.
fn central_differences<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    system: &ClosedLoopN<P, N, NX, NP, NZ>,
    z: &SVector<f64, NZ>,
) -> SMatrix<f64, NZ, NZ>
where
    P: ArmModel<N, NX, NP, NZ>,
{
    common::central_differences(|z| system.rhs(z), z)
}

/// Largest entry-wise error, relative to the largest entry of its row.
fn row_relative_error<const NZ: usize>(a: &SMatrix<f64, NZ, NZ>, b: &SMatrix<f64, NZ, NZ>) -> f64 {
    (0..NZ)
        .map(|r| (a.row(r) - b.row(r)).amax() / a.row(r).amax().max(1.0))
        .fold(0.0, f64::max)
}

/// A state away from the equilibrium, moving: the ẏ = J(q) q̇ term's ∂/∂q (J̇) is exercised.
fn moving_state<const N: usize, const NX: usize, const NZ: usize>(
    x_e: &SVector<f64, NX>,
) -> SVector<f64, NZ> {
    SVector::from_fn(|i, _| match i {
        i if i < N => x_e[i] + 0.1 * (i as f64 + 1.0).sin(),
        i if i < NX => 0.3 * (i as f64).cos(),
        i => 0.2 * (i as f64).sin(),
    })
}

#[test]
fn the_tip_tasks_closed_loop_jacobian_matches_central_differences() {
    for kind in tip_tasks() {
        let tool = panda_tool([0.02, -0.01, 0.25]);
        let task = Panda::paper_task(kind);
        let system = ClosedLoopN::<Panda, 7, 14, 13, 21>::new(&tool, &task, 1.0, 0.3).unwrap();
        let z = moving_state::<7, 14, 21>(&Panda::equilibrium_state());
        let error = row_relative_error(&system.jacobian(&z), &central_differences(&system, &z));
        assert!(error < 1e-6, "panda {kind}: {error:e}");

        let tool = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
        let task = Arm2::paper_task(kind);
        let system = ClosedLoopN::<Arm2, 2, 4, 4, 6>::new(&tool, &task, 1.0, -0.4).unwrap();
        let z = moving_state::<2, 4, 6>(&Arm2::equilibrium_state());
        let error = row_relative_error(&system.jacobian(&z), &central_differences(&system, &z));
        assert!(error < 1e-6, "arm2 {kind}: {error:e}");
    }
}

#[test]
fn the_controller_observes_the_tips_forward_kinematics() {
    let tool = panda_tool([0.0, 0.03, 0.2]);
    let p = tool.params();
    for kind in [TaskKind::TipPosition, TaskKind::TipAcceleration] {
        let task = Panda::paper_task(kind);
        let system = ClosedLoopN::<Panda, 7, 14, 13, 21>::new(&tool, &task, 1.0, 0.2).unwrap();
        let z = moving_state::<7, 14, 21>(&Panda::equilibrium_state());
        let (z_dot, observed) = system.rhs_and_observation(&z);
        let q = z.fixed_rows::<7>(0).into_owned();
        let q_dot = z.fixed_rows::<7>(7).into_owned();
        let q_ddot = z_dot.fixed_rows::<7>(7).into_owned();
        let (y, j) = Panda::tip(&q, &p).unwrap();
        let bias = Panda::tip_bias(&q, &q_dot, &p).unwrap();
        for term in Term::ALL {
            let expected: Option<SVector<f64, 3>> = match term.read() {
                Read::Tip { order: 0 } => Some(y),
                Read::Tip { order: 1 } => Some(j * q_dot),
                // ÿ is evaluated only on a task that reads it (J̇ q̇ costs a function call).
                Read::Tip { .. } if task.kind.uses(term) => Some(j * q_ddot + bias),
                Read::Tip { .. } => Some(SVector::zeros()),
                _ => None,
            };
            if let Some(e) = expected {
                let v = observed[term.index()];
                assert_eq!(v.fixed_rows::<3>(0).into_owned(), e, "{kind} {term}");
                assert!(
                    v.rows(3, 4).iter().all(|x| *x == 0.0),
                    "{term}: padding {v}"
                );
            }
        }
    }
}

/// ÿ as observed is the time derivative of ẏ as observed along the closed loop's own flow:
/// (ẏ(Z + hŻ) − ẏ(Z − hŻ)) / 2h, an identity the generated J̇ q̇ and the plant's q̈ must satisfy
/// together (a wrong sign or a missing term in either shows at once).
#[test]
fn the_tips_acceleration_is_the_rate_of_its_velocity_along_the_flow() {
    fn check<P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        system: &ClosedLoopN<P, N, NX, NP, NZ>,
        z: &SVector<f64, NZ>,
        label: &str,
    ) where
        P: ArmModel<N, NX, NP, NZ>,
    {
        let (z_dot, observed) = system.rhs_and_observation(z);
        let h = 1e-6;
        let velocity = |z: &SVector<f64, NZ>| system.rhs_and_observation(z).1[Term::TipDot.index()];
        let rate = (velocity(&(z + z_dot * h)) - velocity(&(z - z_dot * h))) / (2.0 * h);
        let acceleration = observed[Term::TipDdot.index()];
        let error = (acceleration - rate).amax() / acceleration.amax().max(1.0);
        assert!(
            error < 1e-7,
            "{label}: ÿ {acceleration} vs dẏ/dt {rate}: {error:e}"
        );
        assert!(
            acceleration.amax() > 1e-3,
            "{label}: a trivial state {acceleration}"
        );
    }
    let kind = TaskKind::TipAcceleration;
    for tip in [[0.0, 0.0, 0.1], [0.05, -0.02, 0.37]] {
        let tool = panda_tool(tip);
        let task = Panda::paper_task(kind);
        let system = ClosedLoopN::<Panda, 7, 14, 13, 21>::new(&tool, &task, 1.0, 0.3).unwrap();
        check(
            &system,
            &moving_state::<7, 14, 21>(&Panda::equilibrium_state()),
            "panda",
        );
    }
    let tool = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let system =
        ClosedLoopN::<Arm2, 2, 4, 4, 6>::new(&tool, &Arm2::paper_task(kind), 1.0, -0.4).unwrap();
    check(
        &system,
        &moving_state::<2, 4, 6>(&Arm2::equilibrium_state()),
        "arm2",
    );
}

/// The generated J̇ q̇ against the generated y alone: d²/ds² y(q + s q̇) at s = 0 is q̇ᵀ∇²y q̇ =
/// J̇ q̇, taken by a second central difference (step 1e-4: truncation ~1e-8, rounding ~1e-8
/// relative), on the URDF arms, the paper's arm and the 3-link chain, at random states and tools.
#[test]
fn the_generated_tip_bias_is_the_tips_second_derivative_along_q_dot() {
    fn check<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        p: &SVector<f64, NP>,
        seed: u64,
    ) where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let mut state = seed;
        let mut uniform = |lo: f64, hi: f64| {
            // A 64-bit LCG (Knuth's MMIX): reproducible without a dependency.
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
        };
        for _ in 0..20 {
            let q = SVector::<f64, N>::from_fn(|_, _| uniform(-3.0, 3.0));
            let v = SVector::<f64, N>::from_fn(|_, _| uniform(-2.0, 2.0));
            let y = |s: f64| M::tip(&(q + v * s), p).unwrap().0;
            let h = 1e-4;
            let second = (y(h) - y(0.0) * 2.0 + y(-h)) / (h * h);
            let bias = M::tip_bias(&q, &v, p).unwrap();
            let error = (bias - second).amax() / bias.amax().max(1.0);
            assert!(
                error < 1e-6,
                "{}: J̇q̇ {bias} vs {second}: {error:e}",
                M::name()
            );
        }
    }
    check::<Panda, 7, 14, 13, 21>(&panda_tool([0.05, -0.02, 0.37]).params(), 1);
    let ur5 = SVector::<f64, 13>::from_row_slice(&[
        1.2, 0.01, 0.0, 0.08, 4e-3, 4e-3, 2e-3, 1e-4, 0.0, 0.0, 0.0, 0.02, 0.25,
    ]);
    check::<Ur5, 6, 12, 13, 18>(&ur5, 2);
    check::<Arm2, 2, 4, 4, 6>(&SVector::from([0.3, 0.4, 0.5, 0.2]), 3);
    let arm3 = SVector::from_fn(|i, _| 0.3 + 0.1 * i as f64);
    check::<Arm3, 3, 6, { toolconf_generated::arm3::PARAMETER_COUNT }, 9>(&arm3, 4);
}

/// The derivation writes ∂y/∂U = J ∂θ/∂U (J at q^e, its first TIP_DIM rows): the generated
/// tip sensitivities against J from the generated tip and the joint position task's own.
#[test]
fn the_tip_sensitivities_are_the_tip_jacobian_times_the_joints() {
    for tip in [[0.0, 0.0, 0.1], [0.05, -0.02, 0.37]] {
        let tool = panda_tool(tip);
        let q_e = Panda::equilibrium_state().fixed_rows::<7>(0).into_owned();
        let (_, j) = Panda::tip(&q_e, &tool.params()).unwrap();
        let pairs = [
            (
                TaskKind::Position,
                TaskKind::TipPosition,
                Term::Theta,
                Term::Tip,
            ),
            (
                TaskKind::Position,
                TaskKind::TipPosition,
                Term::ThetaDot,
                Term::TipDot,
            ),
            (
                TaskKind::Acceleration,
                TaskKind::TipAcceleration,
                Term::ThetaDdot,
                Term::TipDdot,
            ),
        ];
        for (joint_task, tip_task, joint, tip_term) in pairs {
            let joints = tool.sensitivities(joint_task);
            let at_tip = tool.sensitivities(tip_task);
            let (Some(s), Some(t)) = (joints.of(joint), at_tip.of(tip_term)) else {
                panic!("{joint} or {tip_term} has no sensitivity");
            };
            let expected = j * s;
            let scale = expected.amax().max(1e-12);
            let error = (t.fixed_rows::<3>(0) - expected).amax() / scale;
            assert!(error < 1e-10, "{tip_term} at tip {tip:?}: {error:e}");
            assert!(t.rows(3, 4).iter().all(|x| *x == 0.0));
        }
    }
}

/// Why the task file `t.toml` holding `text` is refused for the model `M`.
fn task_refusal<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    text: &str,
) -> String
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let spec = TaskSpec::parse(text, "t.toml").unwrap();
    spec.task::<M, N, NX, NP, NZ>().unwrap_err().to_string()
}

#[test]
fn task_files_give_tip_goals_with_the_tips_components() {
    let spec = TaskSpec::parse(
        "kind = \"tip_position\"\n[goal]\ntip = [0.5, 0.0, 0.4]\n[precision]\ntip = 1e4\n",
        "t.toml",
    )
    .unwrap();
    let task: TaskN<7> = spec.task::<Panda, 7, 14, 13, 21>().unwrap();
    let goal = task.goal(Term::Tip);
    assert_eq!(
        goal.fixed_rows::<3>(0),
        SVector::<f64, 3>::new(0.5, 0.0, 0.4)
    );
    assert_eq!(goal.rows(3, 4).amax(), 0.0);
    let p = task.precision(Term::Tip);
    assert_eq!(
        p.trace(),
        3e4,
        "σ⁻² on the tip's three components only: {p}"
    );
    assert_eq!(term_components(Term::Tip, 7, Panda::tip_dim()), 3);

    let e =
        task_refusal::<Panda, 7, 14, 13, 21>("kind = \"tip_position\"\n[goal]\ntip = [0.5, 0.0]\n");
    assert!(
        e.contains("t.toml, key goal.tip: 2 values") && e.contains("has 3 components (x, y, z)"),
        "{e}"
    );
    // The planar arm's tip has its plane's two components.
    let e = task_refusal::<Arm2, 2, 4, 4, 6>(
        "kind = \"tip_position\"\n[goal]\ntip = [0.5, 0.0, 0.4]\n",
    );
    assert!(e.contains("has 2 components (x, y)"), "{e}");
}

#[test]
fn a_tip_position_episode_reaches_its_goal_on_every_catalogue_tool() {
    let task_file = "examples/tasks/panda_touch_point.toml";
    let spec = TaskSpec::from_file(&repo(task_file)).unwrap();
    assert_eq!(spec.kind, TaskKind::TipPosition);
    let tasks = ModelTasks::new(&spec);
    let mut tools = 0;
    read_tools(&repo("examples/tools/panda_tools.csv"), |row| {
        let row = row.unwrap();
        assert!(row.missing_tip().is_empty(), "{}", row.label());
        let m = tasks.simulate(&row.tool).unwrap();
        let progress = m.progress.unwrap();
        // 0.8: the tip within a fifth of its starting distance after 5 s, the tip tasks' stated target.
        assert!(
            progress >= 0.8,
            "{task_file}, {}: progress {progress}",
            row.label()
        );
        tools += 1;
        Ok(())
    })
    .unwrap();
    assert!(tools >= 10, "{tools}");
}

#[test]
fn a_tip_task_refuses_a_tools_file_row_without_a_tip() {
    let path = common::fresh_file(
        "tip-tasks",
        "no_tips.csv",
        "name,model,tool_mass,tool_com_x,tool_com_y,tool_com_z,tool_ixx,tool_iyy,tool_izz\n\
         plate,panda,0.5,0,0,0.01,1e-3,1e-3,1e-3\n\
         probe,panda,0.2,0,0,0.05,1e-4,1e-4,1e-4\n",
    );
    let tip = ModelTasks::new(&TaskSpec::builtin(TaskKind::TipPosition));
    let all_refused = screen_file(&path, &tip, "tip_position", None, false, |_| {})
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    // A joint task takes the same rows, their tips at the flange.
    let joint = ModelTasks::new(&TaskSpec::builtin(TaskKind::Velocity));
    let joint_screen = screen_file(&path, &joint, "velocity", None, false, |_| {});
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    assert!(
        all_refused.contains("no_tips.csv, tool 1: the tip_position task reads the tool's tip")
            && all_refused.contains("leaves out tool_tip_x, tool_tip_y, tool_tip_z"),
        "{all_refused}"
    );
    let (screen, _) = joint_screen.unwrap();
    assert!(screen.finish().iter().all(|c| c.logdet.is_ok()));
}
