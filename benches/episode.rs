//! The closed loop: one right-hand-side evaluation, the latency of a chain of dependent ones,
//! one episode per task at the paper's defaults on a fixed arm (one thread), and 1000 task-1
//! episodes on all cores via `select::evaluate`.
//!
//! `cargo bench --bench episode`; target: a task-1 episode ≤ 25 µs on one core.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use toolconf::select::{draw_tools, evaluate};
use toolconf_model::closed_loop::{simulate, ClosedLoop, EpisodeOptions, JointState, Plant};
use toolconf_model::{Arm, Task, TaskKind};

/// The fixed arm of docs/tutorials/paper-arm.md (m1, m2, l1, l2).
fn arm() -> Arm {
    Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap()
}

fn rhs(c: &mut Criterion) {
    let arm = arm();
    let mut group = c.benchmark_group("rhs");
    for kind in TaskKind::ALL {
        let system = ClosedLoop::new(&arm, &Task::paper(kind), 1.0, 0.0).unwrap();
        let z = JointState::from([-1.2, -1.9, 0.7, -0.4, 0.3, -0.2]);
        group.bench_function(kind.name(), |b| b.iter(|| system.rhs(black_box(&z))));
    }
    group.finish();
}

/// 1000 evaluations, each on the previous one's result (z ← z + h·Ż, as a Runge–Kutta stage
/// waits for the one before): the time per element is the latency of one RHS plus a stage
/// combination, the floor of an episode's time per evaluation (docs/explanation/performance.md).
fn rhs_chain(c: &mut Criterion) {
    let arm = arm();
    let mut group = c.benchmark_group("rhs_chain");
    group.throughput(Throughput::Elements(1000));
    let system = ClosedLoop::new(&arm, &Task::paper(TaskKind::Position), 1.0, 0.0).unwrap();
    let z0 = JointState::from([-1.2, -1.9, 0.7, -0.4, 0.3, -0.2]);
    group.bench_function(TaskKind::Position.name(), |b| {
        b.iter(|| {
            let mut z = black_box(z0);
            for _ in 0..1000 {
                z += system.rhs(&z) * 1e-4;
            }
            z
        })
    });
    group.finish();
}

fn episode(c: &mut Criterion) {
    let arm = arm();
    let options = EpisodeOptions::default();
    let mut group = c.benchmark_group("episode");
    for kind in TaskKind::ALL {
        let task = Task::paper(kind);
        group.bench_function(kind.name(), |b| {
            b.iter(|| simulate(black_box(&arm), &task, &options).unwrap().metrics)
        });
    }
    group.finish();
}

fn batch(c: &mut Criterion) {
    let tools = draw_tools(1000, 42);
    let task = Task::paper(TaskKind::Position);
    let options = EpisodeOptions::default();
    let mut group = c.benchmark_group("batch");
    group.sample_size(20);
    group.throughput(Throughput::Elements(tools.len() as u64));
    group.bench_function(
        format!(
            "position_1000_tools_{}_threads",
            rayon::current_num_threads()
        ),
        |b| b.iter(|| evaluate(black_box(&tools), &task, &options, Plant::Paper)),
    );
    group.finish();
}

criterion_group!(benches, rhs, rhs_chain, episode, batch);
criterion_main!(benches);
