//! Task 3 (stiff for DP5) by each integration method, side by side: DP5 (`ode45`), Rodas5P and
//! Auto (DP5 until Hairer's stiffness test fires, then Rodas5P), on the paper's three reference
//! arms at the default tolerances; and the cost of one closed-loop Jacobian next to one
//! right-hand side (a Rodas5P step takes seven of the latter and one of the former).
//!
//! `cargo bench --bench stiff`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{simulate, ClosedLoop, EpisodeOptions, JointState};
use toolconf_model::{Arm, Task, TaskKind};

const ARMS: [[f64; 4]; 3] = [
    [0.1, 0.1, 0.1, 0.1],
    [0.3, 0.4, 0.5, 0.2],
    [0.6, 0.6, 0.6, 0.6],
];

fn task3_episode(c: &mut Criterion) {
    let task = Task::paper(TaskKind::Acceleration);
    for p in ARMS {
        let arm = Arm::new([p[0], p[1], p[2], p[3]]).unwrap();
        let mut group = c.benchmark_group(format!("task3/{}_{}_{}_{}", p[0], p[1], p[2], p[3]));
        // DP5 needs 289k right-hand sides on the smallest arm.
        group.sample_size(if p[0] < 0.2 { 10 } else { 30 });
        for (name, method) in [
            ("dp5", Method::Explicit),
            ("rodas5p", Method::Stiff),
            ("auto", Method::Auto),
        ] {
            let mut options = EpisodeOptions::default();
            options.integrator.method = method;
            group.bench_function(name, |b| {
                b.iter(|| simulate(black_box(&arm), &task, &options).unwrap().metrics)
            });
        }
        group.finish();
    }
}

fn jacobian(c: &mut Criterion) {
    let arm = Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let system = ClosedLoop::new(&arm, &Task::paper(TaskKind::Acceleration), 1.0, 0.0).unwrap();
    let z = JointState::from([-1.2, -1.9, 0.7, -0.4, 0.3, -0.2]);
    let mut group = c.benchmark_group("closed_loop");
    group.bench_function("rhs", |b| b.iter(|| system.rhs(black_box(&z))));
    group.bench_function("jacobian", |b| b.iter(|| system.jacobian(black_box(&z))));
    group.finish();
}

criterion_group!(benches, task3_episode, jacobian);
criterion_main!(benches);
