//! ns per control tick of the on-robot controller, for the paper's arm (arm2) and the 3-link arm,
//! on each task: `cargo bench --manifest-path examples/on_robot/bench/Cargo.toml`. A tick is
//! what a robot calls every millisecond: the model's θ̈ at the measured state (the generated
//! dynamics, one `sin_cos` per joint) and one step of U̇ = −γ ∂F/∂U. The measured state varies
//! from tick to tick (a slow sweep), so that neither the trigonometry nor a branch is predicted
//! from a constant input. Target: below 100 ns for arm2 on this machine.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use toolconf_core::ArmModel;
use toolconf_on_robot::{Arm2, Arm2Controller, Arm2Tool, Arm3, Arm3Controller, Arm3Tool, TaskKind};

/// Ticks per measured iteration (the time per tick is the iteration's time / TICKS).
const TICKS: u64 = 1000;

fn arm2(c: &mut Criterion) {
    let tool = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
    let xe = Arm2::equilibrium_state();
    ticks(
        c,
        "tick/arm2",
        |kind| Arm2Controller::paper(&tool, kind).unwrap(),
        |controller, x| controller.tick(x).unwrap().torque[0],
        |s| [xe[0] + s, xe[1] - 0.5 * s, 0.1 + s, -0.2],
    );
}

fn arm3(c: &mut Criterion) {
    let tool = Arm3Tool::new([0.3, 0.25, 0.2, 0.4, 0.35, 0.3]).unwrap();
    let xe = Arm3::equilibrium_state();
    ticks(
        c,
        "tick/arm3",
        |kind| Arm3Controller::paper(&tool, kind).unwrap(),
        |controller, x| controller.tick(x).unwrap().torque[0],
        |s| {
            [
                xe[0] + s,
                xe[1] - 0.5 * s,
                xe[2] + 0.3 * s,
                0.1 + s,
                -0.2,
                0.05,
            ]
        },
    );
}

/// Group `name`: on each task, TICKS ticks of `controller(kind)` (`tick`: one tick, its first
/// torque) at the states `state(s)` of a slow sweep s = 0, 0.001, ...
fn ticks<C, const N: usize>(
    c: &mut Criterion,
    name: &str,
    controller: impl Fn(TaskKind) -> C,
    mut tick: impl FnMut(&mut C, &[f64; N]) -> f64,
    state: impl Fn(f64) -> [f64; N],
) {
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(TICKS));
    for kind in [TaskKind::Position, TaskKind::Velocity] {
        let mut controller = controller(kind);
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                let mut last = 0.0;
                for i in 0..TICKS {
                    let x = state(i as f64 * 1e-3);
                    last = tick(&mut controller, black_box(&x));
                }
                last
            })
        });
    }
    group.finish();
}

criterion_group!(benches, arm2, arm3);
criterion_main!(benches);
