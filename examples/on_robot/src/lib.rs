//! # toolconf-on-robot: what a robot links
//!
//! The paper's active-inference controller as a robot runs it: at a fixed rate (1 kHz, one tick
//! per millisecond), each tick takes the measured state X = [θ; θ̇] of the arm and returns the
//! torque U to apply until the next tick and the tool's control confidence ln|Π^U|. `no_std`,
//! no allocation, no integrator and no threads: this crate depends on toolconf's core
//! (`toolconf-core`) and the generated code beneath it (`toolconf-generated`) only, with
//! nalgebra's fixed-size types; `cargo tree` here is what a robot's firmware gets. It builds
//! for a microcontroller without std or an allocator, e.g. a Cortex-M4F: `rustup target add
//! thumbv7em-none-eabihf`, then `cargo build --manifest-path examples/on_robot/Cargo.toml
//! --target thumbv7em-none-eabihf` (the workspace's tests/layers.rs does, where the target is
//! installed).
//!
//! ```
//! use toolconf_on_robot::{Arm2Controller, Arm2Tool, TaskKind};
//!
//! let tool = Arm2Tool::new([0.3, 0.4, 0.5, 0.2]).unwrap();
//! let mut controller = Arm2Controller::paper(&tool, TaskKind::Position).unwrap();
//! // Every millisecond: read the joint encoders, command the motors.
//! let measured = [-1.5707963267948966, -1.5707963267948966, 0.0, 0.0];
//! let command = controller.tick(&measured).unwrap();
//! assert!(command.torque.iter().all(|t| t.is_finite()));
//! assert!(command.confidence > 0.0); // ln|Π^U| of this arm for task 1
//! ```
//!
//! ## One tick
//!
//! The controller descends the free energy, U̇ = −γ ∂F/∂U (eq. U_dot_deriv), with the task's
//! gains precomputed ([`toolconf_core::ActiveInferenceN`]). A tick is one explicit Euler step
//! of that gradient flow over the control period h: U ← U + h·U̇(θ, θ̇, θ̈, U)
//! ([`toolconf_core::ActiveInferenceN::tick`]). θ̈ is the arm's response to the torque it is
//! applying, from the tool's generated dynamics ([`ArmController::tick`]) or measured
//! ([`ArmController::tick_with_acceleration`], for a robot with accelerometers, which then also
//! sees a disturbance torque). Π^U does not change during a task, so its closed form is
//! evaluated once, when the controller is built.
//!
//! The discrete loop settles only if h is short enough: θ̈ follows U through ∂θ̈/∂U, so each
//! tick multiplies a torque error by I − hγ(K_θ̈ ∂θ̈/∂U + P^U). [`ArmController::new`] refuses
//! a rate at which that factor's spectral radius at the hanging equilibrium is not below 1
//! (light distal links and task 3's P^θ̈ = 10 ask for more than 1 kHz).
//!
//! ## How closely it follows the paper's controller
//!
//! The paper integrates the same closed loop continuously (MATLAB's ode45; `toolconf simulate
//! --method explicit`, Dormand–Prince 5(4) at rtol 10⁻³, atol 10⁻⁶). The host tests
//! (`tests/closed_loop.rs`) run this crate's ticks against the generated dynamics of the arm,
//! integrated by classical Runge–Kutta with four steps per tick and the torque held over the
//! tick, and compare the task error TE = Σₖ (e(tₖ) − e^g)ᵀ P (e(tₖ) − e^g) over the paper's
//! 101-point grid with the command's. The tolerance is derived, not chosen:
//!
//! |TE_h − TE_ode45| ≤ |TE_h − TE| + |TE − TE_ode45|, TE the exact continuous value.
//!
//! * The ticks are first order in h (an explicit Euler step of U, the torque held over the
//!   tick; the plant's Runge–Kutta error, O((h/4)⁴) per tick, is ~10⁻¹² of it): TE_h = TE +
//!   c·h + O(h²). Two more runs at h/2 and h/4 measure it: D₁ = TE_h − TE_{h/2} = c·h/2 +
//!   O(h²), D₂ = TE_{h/2} − TE_{h/4}; the test checks the first-order behaviour itself
//!   (D₁/D₂ within 2 ± 0.3), and then the remaining error of TE_h is the geometric series
//!   D₁ + D₂ + … ≈ 2·D₁, bounded by 2·|D₁|·(1 + 0.3) (the ratio's allowance).
//! * ode45's own error, |TE − TE_ode45|, is what its tolerances leave; the reference records
//!   the command's value at the default tolerances and at rtol 10⁻¹⁰, atol 10⁻¹² (whose error
//!   is far below the others), and their difference bounds it.
//!
//! So the test asserts |TE_h − TE_ode45| ≤ 2.6·|D₁| + |TE_ode45 − TE_tight|, and the same for
//! the final joint angles and velocities. On the paper's arm (0.3, 0.4, 0.5, 0.2), task 1, at
//! h = 1 ms: TE_h = 13 599.9 against ode45's 13 612.3 (0.09 % apart); D₁ = −6.17 with
//! D₁/D₂ = 2.00, so the bound is 16.0, of which ode45's own error is 6·10⁻⁴. Task 2: 208.10
//! against 208.19, bound 0.113. A γ off by one per cent (0.99 or 1.01) already lands outside
//! (in θ₁(5 s)), and 2 % in the task error itself.
//!
//! ## Speed
//!
//! A tick of arm2 takes 37 ns, of arm3 72–77 ns (`cargo bench --manifest-path
//! examples/on_robot/bench/Cargo.toml`, one core of the shared 2-core machine, the ticks
//! chained as on a robot: each waits for the torque before it).

#![no_std]

// The controller itself is toolconf-core's (`toolconf_core::ArmController`), so that a model
// library built by `make model` ticks through its C ABI with this very code
// (`toolconf_controller_tick`, docs/reference/c-abi.md); this crate is what a robot's firmware links.
pub use toolconf_core::{Arm2, Arm2Tool, Arm3, Arm3Tool, Panda, PandaTool, TaskKind};
pub use toolconf_core::{ArmController, Command, RATE_HZ};

/// The paper's arm (`arm2`).
pub type Arm2Controller = ArmController<Arm2, 2, 4, 4, 6>;
/// The 3-link arm (`arm3`).
pub type Arm3Controller = ArmController<Arm3, 3, 6, 6, 9>;
/// The Franka Emika Panda with a tool at its flange (`panda`).
pub type PandaController = ArmController<Panda, 7, 14, 13, 21>;
