//! The cost of one controller tick through the C ABI against the same tick called directly
//! (toolconf-core's `ArmController`, the peer: no handle, no argument checks), on a population
//! of the paper's arm: `TOOLS` random tools from the model's sampling box, each with its own
//! controller, all of them live at once (so that the library's registry of handles holds
//! `TOOLS` entries). Each tool is ticked `TICKS` times through one path, then through the other
//! (A B per tool, so that a drift of the machine's speed hits both alike); the time per tick is
//! the block's time over `TICKS`. Prints mean, p50, p90 and p99 over the tools of each path and
//! of their ratio.
//!
//! `cargo run --release -p toolconf-cabi --example tick_population [TOOLS] [TICKS] [ROUNDS]`:
//! ROUNDS passes over the population (so that a small one, a robot's few controllers, gives
//! as many samples as a large one).

use std::hint::black_box;
use std::time::Instant;

use toolconf_cabi::bodies::Controller;
use toolconf_cabi::check::{self, Rng};
use toolconf_cabi::toolconf_core::{ArmController, ArmModel, TaskKind, TaskN, ToolN};

toolconf_cabi::export_model!(Arm2, arm2);
use toolconf_cabi::toolconf_core::Arm2;

type Direct = ArmController<Arm2, 2, 4, 4, 6>;

/// Valid tools with a controller at 1 kHz on the position task, from the sampling box.
fn population(count: usize, task: &TaskN<2>) -> Vec<([f64; 4], Direct)> {
    let mut rng = Rng::new(7);
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let p: [f64; 4] = core::array::from_fn(|i| {
            let (lo, hi) = Arm2::tool_rule().sample[i];
            rng.uniform(lo, hi)
        });
        let made = ToolN::<Arm2, 2, 4, 4, 6>::new(p)
            .and_then(|tool| Direct::new(&tool, task, 1.0, [0.1; 2], 1000.0));
        if let Ok(c) = made {
            out.push((p, c));
        }
    }
    out
}

fn stats(name: &str, mut v: Vec<f64>) {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    println!(
        "{name:<22} mean {mean:8.2}  p50 {:8.2}  p90 {:8.2}  p99 {:8.2}",
        at(0.5),
        at(0.9),
        at(0.99)
    );
}

fn main() {
    let mut args = std::env::args()
        .skip(1)
        .map(|a| a.parse::<usize>().expect("a count"));
    let tools = args.next().unwrap_or(2000);
    let ticks = args.next().unwrap_or(200);
    let rounds = args.next().unwrap_or(1);
    let task = Arm2::paper_task(TaskKind::Position);
    let flat = check::flat_paper_task::<Arm2, 2, 4, 4, 6>(TaskKind::Position);
    let mut population = population(tools, &task);
    let handles: Vec<*mut Controller> = population
        .iter()
        .map(|(p, _)| check::create_controller(&EXPORTS, p, &flat, 1000.0))
        .collect();
    let (mut direct_ns, mut abi_ns, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    let mut sink = 0.0;
    let pairs = (0..rounds).flat_map(|_| 0..handles.len());
    for k in pairs {
        let (d, a) = time_pair(&mut population[k].1, handles[k], ticks, &mut sink);
        direct_ns.push(d);
        abi_ns.push(a);
        ratio.push(a / d);
    }
    for h in handles {
        // SAFETY: a live handle.
        assert_eq!(unsafe { (EXPORTS.controller_destroy)(h) }, 0);
    }
    println!(
        "{tools} tools of arm2 (position task, 1 kHz), {rounds} × {ticks} ticks each; ns per tick:"
    );
    stats("direct (ArmController)", direct_ns);
    stats("C ABI (handle)", abi_ns);
    stats("ratio C ABI / direct", ratio);
    black_box(sink);
}

/// ns per tick of `ticks` ticks of one tool: directly, then through the C ABI's `handle` (the
/// same controller); what they return is added to `sink`, so that no tick is optimised away.
fn time_pair(
    direct: &mut Direct,
    handle: *mut Controller,
    ticks: usize,
    sink: &mut f64,
) -> (f64, f64) {
    // A measured state near the equilibrium, different at each tick.
    let xe = Arm2::equilibrium_state();
    let state = |i: usize| {
        let s = i as f64 * 1e-4;
        [xe[0] + s, xe[1] - 0.5 * s, 0.1 + s, -0.2]
    };
    let start = Instant::now();
    for i in 0..ticks {
        *sink += direct
            .tick(black_box(&state(i)))
            .map_or(0.0, |c| c.torque[0]);
    }
    let d = start.elapsed().as_secs_f64() * 1e9 / ticks as f64;
    let (mut torque, mut confidence) = ([0.0; 2], 0.0);
    let start = Instant::now();
    for i in 0..ticks {
        let x = state(i);
        // SAFETY: a live handle; the arrays hold the model's sizes.
        let code = unsafe {
            (EXPORTS.controller_tick)(
                black_box(handle),
                x.as_ptr(),
                torque.as_mut_ptr(),
                &mut confidence,
            )
        };
        *sink += f64::from(code) + torque[0];
    }
    let a = start.elapsed().as_secs_f64() * 1e9 / ticks as f64;
    (d, a)
}
