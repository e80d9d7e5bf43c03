//! Control confidence per tool, Π^U and ln|Π^U|, for each of the paper's tasks:
//!
//! * `checked`: [`control_confidence`], the public API (validates the task, checks Π^U ≻ 0);
//! * `unchecked`: Π^U ([`ArmModel::pi_u`]) and the log-determinant, the per-tool work once the
//!   task is validated;
//! * `checked_1000_tools`: the API over 1000 random tools (per tool: the time / 1000, printed as
//!   throughput);
//! * `validated`, `validated_1000_tools`: the ranking path, the task checked once
//!   ([`TaskN::validated`]) and then [`ValidatedTaskN::control_confidence`] per tool (Π^U, the
//!   positive-definiteness check and ln|Π^U|);
//! * `pi_u_1000_tools`: Π^U alone per tool ([`ValidatedTaskN::pi_u`]), summed as its
//!   determinant so that every entry is used.
//!
//! `cargo bench --bench confidence`; target ≤ 20 ns per tool on one core.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use toolconf::select::draw_tools;
use toolconf_model::model::{Arm2, ArmModel, ValidatedTaskN};
use toolconf_model::{control_confidence, Arm, Task, TaskKind};

fn confidence(c: &mut Criterion) {
    let arm = Arm::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let tools = draw_tools(1000, 42);
    let mut group = c.benchmark_group("confidence");
    for kind in TaskKind::ALL {
        let task = Task::paper(kind);
        group.throughput(Throughput::Elements(1));
        group.bench_function(format!("{kind}/checked"), |b| {
            b.iter(|| control_confidence(black_box(&arm), black_box(&task)).unwrap())
        });
        group.bench_function(format!("{kind}/unchecked"), |b| {
            b.iter(|| {
                let p = Arm2::pi_u(black_box(&task), &black_box(&arm).params());
                let logdet = (p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)]).ln();
                (p, logdet)
            })
        });
        let validated: ValidatedTaskN<2> = task.validated().unwrap();
        group.bench_function(format!("{kind}/validated"), |b| {
            b.iter(|| {
                black_box(&validated)
                    .control_confidence(black_box(&arm))
                    .unwrap()
            })
        });
        group.throughput(Throughput::Elements(tools.len() as u64));
        group.bench_function(format!("{kind}/validated_1000_tools"), |b| {
            b.iter(|| {
                let v = black_box(&validated);
                black_box(&tools)
                    .iter()
                    .map(|t| v.control_confidence(t).unwrap().logdet)
                    .sum::<f64>()
            })
        });
        group.bench_function(format!("{kind}/pi_u_1000_tools"), |b| {
            b.iter(|| {
                let v = black_box(&validated);
                black_box(&tools)
                    .iter()
                    .map(|t| {
                        let p = v.pi_u(t);
                        p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)]
                    })
                    .sum::<f64>()
            })
        });
        group.bench_function(format!("{kind}/checked_1000_tools"), |b| {
            b.iter(|| {
                black_box(&tools)
                    .iter()
                    .map(|arm| control_confidence(arm, &task).unwrap().logdet)
                    .sum::<f64>()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, confidence);
criterion_main!(benches);
