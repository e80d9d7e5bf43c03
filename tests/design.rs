//! `toolconf design`'s library: the derived gradient against finite differences and against a
//! hand-derived closed form, a constrained optimum known in closed form, the paper's arm under
//! the stated constraints against 10^5 random feasible tools, infeasibility and determinism.

use toolconf::design::{confidence_optimum, design, DesignError, Setting};
use toolconf::rank::ModelTasks;
use toolconf::select::mixed::MixedSampler;
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::{AnyTool, ModelKind};
use toolconf_model::TaskKind;

const MINIMAL: &str = r#"
objective = "confidence"
constraints = ["l1 + l2 >= 0.7", "m1 + m2 <= 0.5"]
[bounds]
m1 = [0.1, 0.6]
m2 = [0.1, 0.6]
l1 = [0.1, 0.6]
l2 = [0.1, 0.6]
"#;

fn spec(text: &str, model: ModelKind) -> DesignSpec {
    DesignSpec::parse(text, "test.toml", model).expect("valid design file")
}

/// Central difference of ln|Π^U| in parameter j (step 1e-5 relative, or 1e-5 of the sampling
/// box where the parameter is 0): O(h²) ≈ 1e-10 truncation. A product of inertia steps by 1e-5
/// of the tensor's trace, its physical scale: products are often orders of magnitude below the
/// moments, and a step relative to them would leave only rounding (ε·|ln|Π^U||/h ~ 1e-5).
fn central_difference(tasks: &ModelTasks, model: ModelKind, p: &[f64], j: usize) -> f64 {
    let (lo, hi) = model.sample_box()[j];
    let h = match model.info().inertia {
        Some(rule) if rule.products.contains(&j) => {
            1e-5 * rule.moments.iter().map(|&m| p[m]).sum::<f64>()
        }
        _ if p[j] != 0.0 => 1e-5 * p[j],
        _ => 1e-5 * (hi - lo),
    };
    let at = |d: f64| {
        let mut q = p.to_vec();
        q[j] += d;
        tasks.logdet(&AnyTool::new(model, &q).unwrap()).unwrap()
    };
    (at(h) - at(-h)) / (2.0 * h)
}

#[test]
fn gradient_agrees_with_finite_differences_for_every_model_and_task() {
    for model in ModelKind::all() {
        for kind in [
            TaskKind::Position,
            TaskKind::Velocity,
            TaskKind::Acceleration,
        ] {
            let tasks = ModelTasks::new(&TaskSpec::builtin(kind));
            let k = model.parameter_names().len();
            let mut sampler = MixedSampler::new(&[model], 3).unwrap();
            for i in 0..20 {
                // A deterministic spread of tools over the model's sampling box ([0.1, 0.6]^k
                // for the planar arms); where the model's rule refuses a point of it (a URDF
                // tool's moments breaking the triangle inequality), a seeded draw instead.
                let spread: Vec<f64> = model
                    .sample_box()
                    .iter()
                    .enumerate()
                    .map(|(j, &(lo, hi))| lo + (hi - lo) * (((i * 7 + j * 3) % 11) as f64 / 10.0))
                    .collect();
                let tool = AnyTool::new(model, &spread).unwrap_or_else(|_| sampler.next_tool());
                let p: Vec<f64> = tool.named_parameters().iter().map(|(_, v)| *v).collect();
                let (_, gradient) = tasks.logdet_and_gradient(&tool).unwrap();
                assert_eq!(gradient.len(), k);
                for (j, &derived) in gradient.iter().enumerate() {
                    let fd = central_difference(&tasks, model, &p, j);
                    let err = (derived - fd).abs() / derived.abs().max(1.0);
                    assert!(
                        err < 1e-6,
                        "{model} {kind:?} tool {p:?} d/d{}: derived {derived} vs {fd}",
                        model.parameter_names()[j],
                    );
                }
            }
        }
    }
}

/// msd, position task, paper precisions (100, 50, 1, 1): S_θ = −(c + m − 1)/k (generated/msd.md),
/// so Π^U = 100 r² + 52 with r = (c + m − 1)/k, and by hand
/// ∂ln Π/∂m = ∂ln Π/∂c = 200 (c + m − 1)/(k² Π), ∂ln Π/∂k = −200 (c + m − 1)²/(k³ Π).
#[test]
fn msd_gradient_has_its_closed_form() {
    let tasks = ModelTasks::new(&TaskSpec::builtin(TaskKind::Position));
    for (m, k, c) in [(1.0, 1.0, 2.0), (0.3, 2.5, 0.7), (2.0, 0.4, 0.1)] {
        let (logdet, g) = tasks
            .logdet_and_gradient(&AnyTool::new(ModelKind::Msd, &[m, k, c]).unwrap())
            .unwrap();
        let s = c + m - 1.0;
        let pi = 100.0 * s * s / (k * k) + 52.0;
        assert!((logdet - pi.ln()).abs() < 1e-13);
        let want = [
            200.0 * s / (k * k * pi),
            -200.0 * s * s / (k * k * k * pi),
            200.0 * s / (k * k * pi),
        ];
        for (a, b) in g.iter().zip(want) {
            assert!(
                (a - b).abs() <= 1e-13 * b.abs().max(1.0),
                "{g:?} vs {want:?}"
            );
        }
    }
}

/// A constrained optimum by hand. msd on the position task with m, c ∈ [1, 3], k ∈ [0.5, 4],
/// m + c ≤ 3 and k ≥ m: ln Π^U = ln(100 r² + 52) rises with r = (c + m − 1)/k > 0, and
/// r ≤ (3 − 1)/m ≤ 2 with equality only at m = 1, c = 2, k = 1, where ln Π^U = ln 452.
#[test]
fn msd_constrained_optimum_is_the_hand_derived_one() {
    let text = r#"
constraints = ["m + c <= 3", "k - m >= 0"]
[bounds]
m = [1.0, 3.0]
c = [1.0, 3.0]
k = [0.5, 4.0]
"#;
    let s = spec(text, ModelKind::Msd);
    let task = TaskSpec::builtin(TaskKind::Position);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Msd, &task, &tasks);
    let (polytope, o) = confidence_optimum(&s, &setting).unwrap();
    let p = polytope.full(&o.x);
    // Parameter order m, k, c.
    for (got, want) in p.iter().zip([1.0, 1.0, 2.0]) {
        assert!((got - want).abs() < 1e-7, "{p:?}");
    }
    assert!((o.value - 452f64.ln()).abs() < 1e-9, "{}", o.value);
    assert!(o.kkt_residual < 1e-6, "KKT residual {}", o.kkt_residual);
}

/// Bounds of twelve decades: from the box's centre (5·10⁵, where ln|Π^U| of tasks 1 and 2 is
/// flat to 10⁻³⁰) the search must still reach the light, short corner. The optimum is checked
/// against every corner of the box and 2000 tools drawn uniformly in ln p, none better.
#[test]
fn a_box_of_twelve_decades_reaches_its_light_short_corner() {
    let text = "[bounds]\nm1 = [1e-6, 1e6]\nm2 = [1e-6, 1e6]\nl1 = [1e-6, 1e6]\nl2 = [1e-6, 1e6]\n";
    let s = spec(text, ModelKind::Arm2);
    for kind in [TaskKind::Position, TaskKind::Velocity] {
        let task = TaskSpec::builtin(kind);
        let tasks = ModelTasks::new(&task);
        let setting = Setting::new(ModelKind::Arm2, &task, &tasks);
        let (polytope, o) = confidence_optimum(&s, &setting).unwrap();
        assert_eq!(polytope.full(&o.x), [1e-6; 4], "{kind}");
        assert!(o.converged(), "{kind}: KKT residual {}", o.kkt_residual);
        let logdet = |p: &[f64]| {
            tasks
                .logdet(&AnyTool::new(ModelKind::Arm2, p).unwrap())
                .ok()
        };
        assert_eq!(logdet(&[1e-6; 4]), Some(o.value));
        assert!(o.value > 100.0, "{kind}: {}", o.value);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for bits in 0..16usize {
            let corner: Vec<f64> = (0..4)
                .map(|j| if bits >> j & 1 == 0 { 1e-6 } else { 1e6 })
                .collect();
            assert!(logdet(&corner).map_or(true, |l| l <= o.value), "{corner:?}");
        }
        for _ in 0..2000 {
            let p: Vec<f64> = (0..4)
                .map(|_| 10f64.powf(-6.0 + 12.0 * uniform()))
                .collect();
            assert!(logdet(&p).map_or(true, |l| l <= o.value), "{p:?}");
        }
    }
}

/// An optimum the SQP does not converge to (found by a search over random design files): ln|Π^U|
/// still rises as l1 falls along the second constraint, but a step that way leaves the tools
/// whose Π^U is well enough conditioned to have a ln|Π^U|. It is reported as not converged,
/// with its KKT residual; `toolconf design` then warns.
#[test]
fn an_unconverged_optimum_is_reported_as_such() {
    let text = "constraints = [\"2*m1 + 10*l2 >= 1\", \"1*m2 + 3*l2 + 2*l1 >= 50\"]\n[bounds]\n\
                m1 = [2.157e-05, 1.116e+03]\nm2 = [2.157e-05, 1.116e+03]\n\
                l1 = [2.157e-05, 1.116e+03]\nl2 = [2.157e-05, 1.116e+03]\n";
    let s = spec(text, ModelKind::Arm2);
    let task = TaskSpec::builtin(TaskKind::Velocity);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Arm2, &task, &tasks);
    let (polytope, o) = confidence_optimum(&s, &setting).unwrap();
    assert!(!o.converged() && o.kkt_residual > 0.1, "{}", o.kkt_residual);
    // Independently: ∂ln|Π^U|/∂l1 is far from balanced by the constraints' multipliers, and
    // moving l1 down by 1 % (l2 up to keep the constraint) is feasible but ill-conditioned.
    assert!(o.gradient[2] * o.x[2] < -1.0, "{:?}", o.gradient);
    let p = polytope.full(&o.x);
    let mut q = p.clone();
    q[2] *= 0.99;
    q[3] += 2.0 * 0.01 * p[2] / 3.0;
    let tool = AnyTool::new(ModelKind::Arm2, &q).unwrap();
    assert!(polytope.contains(&q[..]));
    assert!(
        matches!(
            tasks.logdet(&tool),
            Err(toolconf_model::Error::Core(
                toolconf_model::model::Error::IllConditioned { .. }
            ))
        ),
        "{q:?}"
    );
}

/// The acceptance case: the paper's arm, task 2, l1 + l2 ≥ 0.7, m1 + m2 ≤ 0.5.
#[test]
fn paper_arm_design_beats_the_best_of_100k_random_feasible_tools() {
    let s = spec(MINIMAL, ModelKind::Arm2);
    let task = TaskSpec::builtin(TaskKind::Velocity);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Arm2, &task, &tasks);
    let r = design(&s, &setting).unwrap();
    assert_eq!(r.random.feasible, 100_000);
    let best_random = r.random.top[0].1;
    assert!(
        r.logdet >= best_random,
        "design {} < random {}",
        r.logdet,
        best_random
    );
    assert!(
        r.gradient_check < 1e-6,
        "gradient vs central differences {}",
        r.gradient_check
    );
    assert!(r.confidence_optimum.kkt_residual < 1e-6);
    // Feasible: the constraints hold at the design.
    let p = &r.params;
    assert!(
        p[2] + p[3] >= 0.7 - 1e-9 && p[0] + p[1] <= 0.5 + 1e-9,
        "{p:?}"
    );
    // The design and the random tools are simulated, with task error and sensitivity.
    assert_eq!(r.checks.len(), 6);
    assert!(r.checks.iter().all(|c| c.simulated.is_ok()));
}

#[test]
fn infeasible_constraints_are_refused() {
    let text = MINIMAL.replace("l1 + l2 >= 0.7", "l1 + l2 >= 1.3");
    let s = spec(&text, ModelKind::Arm2);
    let task = TaskSpec::builtin(TaskKind::Velocity);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Arm2, &task, &tasks);
    match design(&s, &setting) {
        Err(DesignError::Infeasible(m)) => assert!(
            m.contains("infeasible") && m.contains("l1 + l2 >= 1.3"),
            "{m}"
        ),
        other => panic!("expected infeasible, got {other:?}"),
    }
}

#[test]
fn same_seed_same_design_whatever_the_thread_count() {
    let s = spec(
        &format!("{MINIMAL}\n[search]\nsamples = 2000\n"),
        ModelKind::Arm2,
    );
    let task = TaskSpec::builtin(TaskKind::Position);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Arm2, &task, &tasks);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| design(&s, &setting).unwrap());
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| design(&s, &setting).unwrap());
    assert_eq!(one, two);
}

#[test]
fn design_file_mistakes_name_the_key_and_value() {
    let err = |text: &str| {
        DesignSpec::parse(text, "d.toml", ModelKind::Arm2)
            .unwrap_err()
            .to_string()
    };
    let e = err(&MINIMAL.replace("m1 + m2 <= 0.5", "m1 + m3 <= 0.5"));
    assert!(
        e.starts_with("d.toml, key constraints[1]: 'm1 + m3 <= 0.5': unknown parameter 'm3'"),
        "{e}"
    );
    let e = err(&MINIMAL.replace("l2 = [0.1, 0.6]", "l2 = [-0.1, 0.6]"));
    assert!(e.contains("key bounds.l2") && e.contains("> 0"), "{e}");
    let e = err(&MINIMAL.replace("\"confidence\"", "\"speed\""));
    assert!(e.contains("key objective") && e.contains("'speed'"), "{e}");
    let e = err(&MINIMAL.replace("l2 = [0.1, 0.6]", ""));
    assert!(e.contains("'l2' has no bounds"), "{e}");
    let e = err(&format!("{MINIMAL}\n[fixed]\nl2 = 0.3\n"));
    assert!(e.contains("also fixed"), "{e}");
    let e = err(&format!("colour = 1\n{MINIMAL}"));
    assert!(e.contains("d.toml") && e.contains("colour"), "{e}");
}

/// The shipped Panda example: its optimum has centres of mass at (or a rounding error from) 0
/// and tool_com_z on its bound 0. A relative step of such a parameter is no step, and a
/// central one leaves the box: the check steps by the box's width there, one-sided into the
/// box, and agrees with the derived gradient (it read 0.59).
#[test]
fn the_gradient_check_holds_where_a_parameter_sits_at_zero_or_a_bound() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    let task = TaskSpec::parse(&read("examples/tasks/panda_wrist_turn.toml"), "task").unwrap();
    let s = spec(&read("examples/design/panda_tool.toml"), ModelKind::Panda);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Panda, &task, &tasks);
    let (polytope, optimum) = confidence_optimum(&s, &setting).unwrap();
    let at_zero_or_bound = (0..optimum.x.len()).filter(|&j| {
        let x = optimum.x[j];
        x.abs() < 1e-9 || x == polytope.lo[j] || x == polytope.hi[j]
    });
    assert!(at_zero_or_bound.count() >= 1, "{:?}", optimum.x);
    let check = toolconf::design::gradient_check(&setting, &polytope, &optimum);
    assert!(
        check < 1e-5,
        "gradient vs finite differences {check:e} at {:?}",
        optimum.x
    );
}
