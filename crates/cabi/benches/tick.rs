//! ns per controller tick of the paper's arm through the C ABI (`toolconf_controller_tick`:
//! the registry's lookup of the handle, the argument checks, the tick) and directly
//! (`ArmController::tick`, the peer), side by side, with 2000 controllers live so that the
//! registry holds as many handles as a large population would. The percentiles over a
//! population of tools are `examples/tick_population.rs`.
//!
//! `cargo bench -p toolconf-cabi --bench tick`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use toolconf_cabi::bodies::Controller;
use toolconf_cabi::check;
use toolconf_cabi::toolconf_core::{ArmController, ArmModel, TaskKind};

toolconf_cabi::export_model!(Arm2, arm2);
use toolconf_cabi::toolconf_core::Arm2;

/// Ticks per measured iteration (the time per tick is the iteration's time / TICKS).
const TICKS: u64 = 1000;
/// Controllers live during the measurement.
const LIVE: usize = 2000;

fn tick(c: &mut Criterion) {
    let p = [0.3, 0.4, 0.5, 0.2];
    let task = Arm2::paper_task(TaskKind::Position);
    let flat = check::flat_paper_task::<Arm2, 2, 4, 4, 6>(TaskKind::Position);
    let handles: Vec<*mut Controller> = (0..LIVE)
        .map(|_| check::create_controller(&EXPORTS, &p, &flat, 1000.0))
        .collect();
    let tool = toolconf_cabi::toolconf_core::ToolN::new(p).unwrap();
    let mut direct =
        ArmController::<Arm2, 2, 4, 4, 6>::new(&tool, &task, 1.0, [0.1; 2], 1000.0).unwrap();
    let xe = Arm2::equilibrium_state();
    let state = |i: u64| {
        let s = i as f64 * 1e-4;
        [xe[0] + s, xe[1] - 0.5 * s, 0.1 + s, -0.2]
    };
    let mut group = c.benchmark_group("tick/arm2");
    group.throughput(Throughput::Elements(TICKS));
    group.bench_function("direct", |b| {
        b.iter(|| {
            (0..TICKS)
                .map(|i| direct.tick(black_box(&state(i))).unwrap().torque[0])
                .sum::<f64>()
        })
    });
    let h = handles[LIVE / 2];
    group.bench_function("c_abi", |b| {
        b.iter(|| {
            let (mut torque, mut confidence) = ([0.0; 2], 0.0);
            (0..TICKS)
                .map(|i| {
                    let x = state(i);
                    // SAFETY: a live handle; the arrays hold the model's sizes.
                    unsafe {
                        toolconf_controller_tick(
                            black_box(h),
                            x.as_ptr(),
                            torque.as_mut_ptr(),
                            &mut confidence,
                        )
                    };
                    torque[0]
                })
                .sum::<f64>()
        })
    });
    group.finish();
    for h in handles {
        // SAFETY: a live handle.
        assert_eq!(unsafe { toolconf_controller_destroy(h) }, 0);
    }
}

criterion_group!(benches, tick);
criterion_main!(benches);
