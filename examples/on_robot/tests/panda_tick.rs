//! The Panda's tick that the C example controller (examples/c_controller/main.c) makes through
//! the Panda's model library: the same tool, task, rate and measured state, here through the
//! Rust controller itself. `make c-example-test` runs this with `--nocapture` and compares the
//! `bits` lines it prints with the C program's, which must be the same bits.

use toolconf_core::ArmModel;
use toolconf_on_robot::{Panda, PandaController, PandaTool, TaskKind};

/// The Franka Hand at the flange, as `toolconf tool --urdf ... --flange panda_link8` gives it
/// (docs/how-to/tool-from-urdf.md): main.c's `params`.
const FRANKA_HAND: [f64; 13] = [
    0.76,
    -0.006791946714028682,
    0.006791946714028679,
    0.03112105263157894,
    0.001803432452631579,
    0.0018034324526315793,
    0.0017523815789473685,
    0.0007274407894736841,
    -5.786738600352437e-6,
    5.7867386003524354e-6,
    0.0,
    0.0,
    0.1034,
];

fn bits(name: &str, values: &[f64]) {
    for (i, v) in values.iter().enumerate() {
        println!("bits {name}[{i}] 0x{:016x}", v.to_bits());
    }
}

#[test]
fn one_tick_of_the_c_example() {
    let tool = PandaTool::new(FRANKA_HAND).unwrap();
    let task = Panda::paper_task(TaskKind::Position);
    let mut controller = PandaController::new(&tool, &task, 1.0, [0.1; 7], 1000.0).unwrap();
    // The equilibrium, joint i 0.01·(i+1) rad off it and moving at 0.05·(i−3) rad/s.
    let x_e = Panda::equilibrium_state();
    let mut state = [0.0; 14];
    for i in 0..7 {
        state[i] = x_e[i] + 0.01 * (i + 1) as f64;
        state[7 + i] = 0.05 * (i as f64 - 3.0);
    }
    let command = controller.tick(&state).unwrap();
    println!("rust: one tick of the Panda's controller (task position, 1000 Hz)");
    for (i, t) in command.torque.iter().enumerate() {
        println!("torque[{i}] = {t:e} N m");
    }
    println!("confidence ln|Pi^U| = {:e}", command.confidence);
    bits("params", &FRANKA_HAND);
    bits("state", &state);
    bits("torque", &command.torque);
    bits("confidence", &[command.confidence]);
    assert!(command.torque.iter().all(|t| t.is_finite()));
    assert!(command.confidence.is_finite());
}
