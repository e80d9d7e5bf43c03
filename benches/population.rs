//! Ranking throughput: 2000 random tools (`draw_tools(2000, 1)`, the paper's
//! parameter range) per task on one thread, `ode45` (`Method::Explicit`, the old default) and
//! `Method::Fast` (the default of select, rank and reproduce) side by side. Criterion's
//! throughput is per tool, so its "elem/s" is tools per second and the time per element the mean
//! time per tool. The percentiles and the accuracy against a tight reference are
//! `benches/population.sh` (`benches/timing/population.rs`).
//!
//! `cargo bench --bench population`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use toolconf::select::draw_tools;
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{simulate, EpisodeOptions};
use toolconf_model::{Task, TaskKind};

const TOOLS: usize = 2000;

fn population(c: &mut Criterion) {
    let tools = draw_tools(TOOLS, 1);
    let mut group = c.benchmark_group("population");
    group.throughput(Throughput::Elements(TOOLS as u64));
    // One sample ranks 2000 tools (≈ 0.1–0.6 s).
    group.sample_size(10);
    for kind in TaskKind::ALL {
        let task = Task::paper(kind);
        for (name, method) in [("explicit", Method::Explicit), ("fast", Method::Fast)] {
            let mut options = EpisodeOptions::default();
            options.integrator.method = method;
            group.bench_function(format!("{}/{name}", kind.name()), |b| {
                b.iter(|| {
                    tools
                        .iter()
                        .map(|arm| {
                            simulate(black_box(arm), &task, &options)
                                .map_or(f64::NAN, |e| e.metrics.free_energy)
                        })
                        .sum::<f64>()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, population);
criterion_main!(benches);
