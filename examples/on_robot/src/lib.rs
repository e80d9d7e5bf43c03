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

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ActiveInferenceN, ArmModel, ControlConfidenceN, Error, TaskN, ToolN};

pub use toolconf_core::{Arm2, Arm2Tool, Arm3, Arm3Tool, TaskKind};

/// The control rate the loop runs at: 1 kHz.
pub const RATE_HZ: f64 = 1000.0;

/// What one tick returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command<const N: usize> {
    /// The joint torques U to apply until the next tick [N m].
    pub torque: [f64; N],
    /// ln|Π^U|, the tool's control confidence for the task (eq. control_conf), the same every
    /// tick: a tool and task have one.
    pub confidence: f64,
}

/// The controller of one tool for one task, ticking at a fixed rate. Tool model `M` (its
/// generated dynamics predict θ̈), N joints, NX = 2N states, NP parameters, NZ = NX + N.
#[derive(Debug, Clone, Copy)]
pub struct ArmController<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    controller: ActiveInferenceN<N>,
    dynamics: M::DynamicsCoefficients,
    confidence: ControlConfidenceN<N>,
    torque: SVector<f64, N>,
    period: f64,
    /// On a task on the tool's tip, the tool's parameters: each tick then reads the tip's
    /// y(q), J(q) q̇ and, for its acceleration, J(q) q̈ + J̇ q̇ from the generated forward
    /// kinematics (`None`: a joint-space task).
    tip: Option<toolconf_core::TipObserver<NP>>,
}

/// The paper's arm (`arm2`).
pub type Arm2Controller = ArmController<Arm2, 2, 4, 4, 6>;
/// The 3-link arm (`arm3`).
pub type Arm3Controller = ArmController<Arm3, 3, 6, 6, 9>;

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    ArmController<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// The controller of `tool` for `task` with learning rate γ, starting from
    /// `initial_torque`, ticking at `rate_hz`. Errors for an invalid task or γ, a rate or torque
    /// that is not finite and positive (finite), and a rate too low for the ticks to settle for
    /// this tool and task (see the crate docs).
    pub fn new(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
        initial_torque: [f64; N],
        rate_hz: f64,
    ) -> Result<Self, Error> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(Error::InvalidOption {
                name: "control rate [Hz]",
                value: rate_hz,
            });
        }
        if let Some(&value) = initial_torque.iter().find(|v| !v.is_finite()) {
            return Err(Error::InvalidOption {
                name: "initial torque U0",
                value,
            });
        }
        let controller = ActiveInferenceN::new(tool, task, learning_rate)?;
        let period = 1.0 / rate_hz;
        let b = M::input_matrix(&tool.params());
        // The tip's Jacobian at the equilibrium, where B is taken (zero without a tip: then no
        // term reads the tip's acceleration).
        let q_e = M::equilibrium_state().fixed_rows::<N>(0).into_owned();
        let j = toolconf_core::TipKinematics::of::<M, NX, NP, NZ>(&q_e, &tool.params())
            .map_or_else(SMatrix::zeros, |t| t.padded_jacobian());
        let contraction = controller.tick_contraction(&b, &j, period);
        if !(contraction.is_finite() && contraction < 1.0) {
            return Err(Error::InvalidOption {
                name: "control rate [Hz] (too low for this tool and task: each tick would not shrink a torque error; raise it)",
                value: rate_hz,
            });
        }
        let tip = toolconf_core::tip_parameters::<M, N, NX, NP, NZ>(&tool.params(), task.kind)?;
        Ok(Self {
            controller,
            dynamics: M::dynamics_coefficients(&tool.params()),
            confidence: toolconf_core::control_confidence(tool, task)?,
            torque: SVector::from(initial_torque),
            period,
            tip,
        })
    }

    /// The paper's controller for `tool` on the model's paper-style task `kind` at 1 kHz:
    /// γ = 1 and U0 = 0.1 on every joint ("Implementation details").
    pub fn paper(tool: &ToolN<M, N, NX, NP, NZ>, kind: TaskKind) -> Result<Self, Error> {
        Self::new(tool, &M::paper_task(kind), 1.0, [0.1; N], RATE_HZ)
    }

    /// One tick: the measured state X = [θ; θ̇] in, the torque for the next period and ln|Π^U|
    /// out. θ̈ is the arm's response to the torque being applied, from the tool's generated
    /// dynamics. A non-finite measurement is an error, and the torque stays as it was.
    #[inline]
    pub fn tick(&mut self, state: &[f64; NX]) -> Result<Command<N>, Error> {
        let x = measured(state)?;
        let x_dot = M::dynamics_with(&x, &self.torque, &self.dynamics);
        self.step(&x, &x_dot)
    }

    /// One tick with θ̈ measured too (by a robot with accelerometers): the controller then
    /// also sees what its model does not, such as a disturbance torque.
    #[inline]
    pub fn tick_with_acceleration(
        &mut self,
        state: &[f64; NX],
        acceleration: &[f64; N],
    ) -> Result<Command<N>, Error> {
        let x = measured(state)?;
        let acceleration = measured(acceleration)?;
        // Ẋ = [q̇; q̈]: the measured velocity and acceleration.
        let mut x_dot = SVector::<f64, NX>::zeros();
        x_dot
            .fixed_rows_mut::<N>(0)
            .copy_from(&x.fixed_rows::<N>(N));
        x_dot.fixed_rows_mut::<N>(N).copy_from(&acceleration);
        self.step(&x, &x_dot)
    }

    #[inline]
    fn step(
        &mut self,
        x: &SVector<f64, NX>,
        x_dot: &SVector<f64, NX>,
    ) -> Result<Command<N>, Error> {
        let observed = toolconf_core::observe_tool::<M, N, NX, NP, NZ>(
            x,
            x_dot,
            &self.torque,
            self.tip.as_ref(),
        );
        let next = self.controller.tick(&observed, self.period);
        if let Some(&value) = next.iter().find(|v| !v.is_finite()) {
            return Err(Error::InvalidOption {
                name: "torque (the measurement drives it out of range)",
                value,
            });
        }
        self.torque = next;
        Ok(Command {
            torque: next.into(),
            confidence: self.confidence.logdet,
        })
    }

    /// The torque being applied [N m].
    pub fn torque(&self) -> [f64; N] {
        self.torque.into()
    }

    /// The control period h = 1/rate, in s.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Π^U and ln|Π^U| of the tool for the task.
    pub fn control_confidence(&self) -> &ControlConfidenceN<N> {
        &self.confidence
    }

    /// The controller: its task, γ, and F, J and the task error at a state
    /// ([`ActiveInferenceN::free_energy`], [`ActiveInferenceN::task_error`]).
    pub fn controller(&self) -> &ActiveInferenceN<N> {
        &self.controller
    }
}

/// A measurement as a vector, or the error naming its first non-finite value.
#[inline]
fn measured<const K: usize>(values: &[f64; K]) -> Result<SVector<f64, K>, Error> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(Error::InvalidOption {
            name: "measurement",
            value,
        }),
        None => Ok(SVector::from(*values)),
    }
}
