//! The cost per Panda tool, side by side in one run, of the three things `rank` can compute for
//! a tool on the Panda's touch task (examples/tasks/panda_touch_point.toml, as shipped):
//!
//! * `prediction`: the episode's cost predicted by the closed loop linearised at the
//!   equilibrium (`toolconf_model::prediction`: linearisation, stability check, Van Loan step, sums);
//! * `logdet`: ln|Π^U| in closed form (the confidence screen's key);
//! * `episode`: one simulated episode (`rank`'s method, `fast`).
//!
//! Each on one thread, over the same 16 random Panda tools (seed 3), per tool.
//! `cargo bench --bench prediction_cost`; the targets: the prediction ≤ 100 µs per tool and at
//! least 5× cheaper than an episode.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use toolconf::rank::ModelTasks;
use toolconf::select::mixed::MixedSampler;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::{AnyTool, ModelKind};

const TOOLS: usize = 16;

fn tools() -> Vec<AnyTool> {
    MixedSampler::new(&[ModelKind::Panda], 3)
        .unwrap()
        .tools(TOOLS)
}

fn touch_task() -> ModelTasks {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/tasks/panda_touch_point.toml"
    );
    let mut spec = TaskSpec::from_file(Path::new(path)).unwrap();
    spec.episode.method = Some(toolconf_integrators::Method::Fast);
    ModelTasks::new(&spec)
}

fn per_tool(c: &mut Criterion) {
    let tasks = touch_task();
    let tools = tools();
    for tool in &tools {
        tasks
            .predict(tool)
            .expect("every tool here has a prediction");
    }
    let mut group = c.benchmark_group("panda_touch_per_tool");
    group.sample_size(20);
    // One iteration handles all TOOLS tools: criterion's time / 16 is the time per tool.
    group.bench_function("prediction_x16", |b| {
        b.iter(|| {
            for tool in &tools {
                black_box(tasks.predict(black_box(tool)).unwrap());
            }
        })
    });
    group.bench_function("logdet_x16", |b| {
        b.iter(|| {
            for tool in &tools {
                black_box(tasks.logdet(black_box(tool)).unwrap());
            }
        })
    });
    group.bench_function("episode_x16", |b| {
        b.iter(|| {
            for tool in &tools {
                black_box(tasks.simulate(black_box(tool)).unwrap());
            }
        })
    });
    group.finish();
}

criterion_group!(benches, per_tool);
criterion_main!(benches);
