//! The default `toolconf reproduce` (the paper's counts, seed 0, every experiment, all cores),
//! writing its CSVs, figures and report into a scratch directory under the system temp dir.
//!
//! `cargo bench --bench reproduce`; about a second per run on 2 cores, so 10 samples.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use toolconf_report::experiments::{reproduce, Config, Plan};

fn default_reproduce(c: &mut Criterion) {
    let out_dir =
        std::env::temp_dir().join(format!("toolconf-bench-reproduce-{}", std::process::id()));
    let config = Config {
        out_dir: out_dir.clone(),
        seed: 0,
        plan: Plan::paper(),
        only: None,
        progress: false,
        command: "toolconf reproduce --out <bench scratch dir> --seed 0".into(),
        // The command line's default (`--method explicit` is ode45's numbers).
        method: toolconf_integrators::Method::Fast,
    };
    let mut group = c.benchmark_group("reproduce");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.bench_function(
        format!("paper_{}_threads", rayon::current_num_threads()),
        |b| b.iter(|| reproduce(&config).expect("reproduce runs").episodes()),
    );
    group.finish();
    let _ = std::fs::remove_dir_all(&out_dir);
}

criterion_group!(benches, default_reproduce);
criterion_main!(benches);
