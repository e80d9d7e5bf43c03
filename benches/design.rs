//! `toolconf design`'s stages for the example of docs/tutorials/design-a-tool.md (the paper's arm, task 2,
//! l1 + l2 ≥ 0.7, m1 + m2 ≤ 0.5):
//!
//! * `optimum`: the multi-start SQP on ln|Π^U| with the derived gradient (centre, 8 random
//!   starts and the box's feasible corners);
//! * `random_100k`: ln|Π^U| of 10⁵ random feasible tools (what the design is compared with);
//! * `gradient`: one ln|Π^U| and ∂ln|Π^U|/∂p through the dispatch the solver uses.
//!
//! `cargo bench --bench design`; the target: the confidence design well under a second.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use toolconf::design::polytope::Polytope;
use toolconf::design::{confidence_optimum, verify, Setting};
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::{AnyTool, ModelKind};
use toolconf_model::TaskKind;

fn design(c: &mut Criterion) {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/design/reach_and_budget.toml"
    ))
    .unwrap();
    let spec = DesignSpec::parse(&text, "reach_and_budget.toml", ModelKind::Arm2).unwrap();
    let task = TaskSpec::builtin(TaskKind::Velocity);
    let tasks = ModelTasks::new(&task);
    let setting = Setting::new(ModelKind::Arm2, &task, &tasks);
    let polytope = Polytope::new(&spec);
    let tool = AnyTool::new(ModelKind::Arm2, &[0.3, 0.2, 0.4, 0.3]).unwrap();
    let mut group = c.benchmark_group("design");
    group.sample_size(20);
    group.bench_function("optimum", |b| {
        b.iter(|| confidence_optimum(black_box(&spec), &setting).unwrap())
    });
    group.bench_function("random_100k", |b| {
        b.iter(|| {
            verify::random_tools(
                &polytope,
                ModelKind::Arm2,
                &tasks,
                // No validation sample: the draws and the five kept, as before the check existed.
                (100_000, 5, 0),
                black_box(1),
                &mut |_| {},
            )
        })
    });
    group.bench_function("gradient", |b| {
        b.iter(|| tasks.logdet_and_gradient(black_box(&tool)).unwrap())
    });
    group.finish();
}

criterion_group!(benches, design);
criterion_main!(benches);
