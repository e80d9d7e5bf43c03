//! The Panda's closed loop: one closed-loop right-hand side (plant and controller, what
//! the integrators call), one episode per task at the paper's tolerances over 5 s on a population
//! of tools, and 1000 Panda tools ranked (`rank`'s simulation stage) on 2 threads, all with
//! `rank`'s default method `fast`.
//!
//! `panda_tip_episode`: one episode of the tip task a user runs (examples/tasks/
//! panda_touch_point.toml, touching a point with the tool's tip, σ = 1 mm) per iteration,
//! cycling through the same 50 tools, with `rank`'s default method; goal ≤ 1 ms (the
//! joint tasks take 0.36–0.41 ms).
//!
//! `cargo bench --bench urdf_episode`; goals: an episode ≤ 2 ms, ≥ 100× SciPy's
//! `solve_ivp` with Pinocchio's `aba` on the same loop (benches/peers/urdf_peers.py, which times the
//! peers and toolconf on one population side by side, mean and percentiles).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::SVector;
use toolconf::rank::{simulate_all, Candidate, ModelTasks};
use toolconf::select::mixed::MixedSampler;
use toolconf_integrators::Method;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::inputs::tools_file::ToolRow;
use toolconf_model::model::{ClosedLoopN, Panda, PandaTool};
use toolconf_model::registry::{AnyTool, ModelKind};
use toolconf_model::TaskKind;

/// `n` Panda tools from the mixed sampler's box (`generated::validity::panda`), seeded.
fn tools(n: usize, seed: u64) -> Vec<AnyTool> {
    MixedSampler::new(&[ModelKind::Panda], seed)
        .unwrap()
        .tools(n)
}

fn panda(tool: &AnyTool) -> PandaTool {
    tool.downcast::<Panda, 7, 14, 13, 21>()
        .expect("the sampler draws Panda tools only")
}

/// The built-in task `kind` with `toolconf rank`'s default integration method, `fast` (the
/// library's default, `auto`, runs ode45 on tasks 1 and 2, which the impedance makes stiff:
/// ~28 000 right-hand sides per Panda episode instead of ~400).
fn rank_task(kind: TaskKind) -> ModelTasks {
    let mut spec = TaskSpec::builtin(kind);
    spec.episode.method = Some(Method::Fast);
    ModelTasks::new(&spec)
}

/// Ż of the closed loop at a state near the equilibrium, per task.
fn closed_loop_rhs(c: &mut Criterion) {
    let tool = panda(&tools(1, 1)[0]);
    let mut z = SVector::<f64, 21>::zeros();
    for (i, v) in toolconf_generated::panda::EQUILIBRIUM_STATE
        .iter()
        .enumerate()
    {
        z[i] = v + 0.01 * (i as f64 + 1.0);
    }
    let mut group = c.benchmark_group("panda_closed_loop_rhs");
    for kind in TaskKind::ALL {
        let task = <Panda as toolconf_model::model::ArmModel<7, 14, 13, 21>>::paper_task(kind);
        let system = ClosedLoopN::<Panda, 7, 14, 13, 21>::new(&tool, &task, 1.0, 0.0).unwrap();
        group.bench_function(kind.name(), |b| b.iter(|| system.rhs(black_box(&z))));
    }
    group.finish();
}

/// One episode per iteration, cycling through 50 tools: the mean over that population.
fn episode(c: &mut Criterion) {
    let population = tools(50, 2);
    let mut group = c.benchmark_group("panda_episode");
    group.sample_size(20);
    for kind in TaskKind::ALL {
        let tasks = rank_task(kind);
        let mut i = 0;
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                i = (i + 1) % population.len();
                tasks.simulate(black_box(&population[i])).unwrap()
            })
        });
    }
    group.finish();
}

/// `rank`'s simulation stage on 1000 Panda tools, on a pool of 2 threads.
fn rank_1000(c: &mut Criterion) {
    let candidates: Vec<Candidate> = tools(1000, 3)
        .into_iter()
        .enumerate()
        .map(|(i, tool)| Candidate {
            row: ToolRow {
                row: i + 1,
                name: None,
                tool,
                defaulted: Vec::new(),
            },
            logdet: Ok(0.0),
            prediction: None,
        })
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("panda_rank_1000");
    group.sample_size(10);
    group.throughput(Throughput::Elements(1000));
    for kind in [TaskKind::Position, TaskKind::Velocity] {
        let tasks = rank_task(kind);
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                pool.install(|| {
                    simulate_all(candidates.clone(), &tasks, |_| Ok::<(), ()>(())).unwrap()
                })
            })
        });
    }
    group.finish();
}

/// One episode of the user's tip task per iteration, cycling through 50 tools.
fn tip_episode(c: &mut Criterion) {
    let population = tools(50, 2);
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/tasks/panda_touch_point.toml");
    let mut spec = TaskSpec::from_file(&file).expect("the example task file");
    spec.episode.method = Some(Method::Fast);
    let tasks = ModelTasks::new(&spec);
    let mut group = c.benchmark_group("panda_tip_episode");
    group.sample_size(20);
    let mut i = 0;
    group.bench_function("touch_point", |b| {
        b.iter(|| {
            i = (i + 1) % population.len();
            tasks.simulate(black_box(&population[i])).unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, closed_loop_rhs, episode, tip_episode, rank_1000);
criterion_main!(benches);
