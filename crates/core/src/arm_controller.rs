//! [`ArmController`]: the on-robot controller of one tool for one task, ticking at a fixed rate
//! (1 kHz): each tick takes the measured state X = [θ; θ̇] and returns the torque for the next
//! period and the tool's control confidence ln|Π^U|. `examples/on_robot` (the crate a robot's
//! firmware links) documents and tests it, and a model library built by `make model` exports
//! it through its C ABI (`toolconf_controller_tick`, crates/cabi): one controller, so the
//! C ABI's ticks are this code's, bit for bit.

use nalgebra::{SMatrix, SVector};

use crate::{ActiveInferenceN, ArmModel, ControlConfidenceN, Error, TaskKind, TaskN, ToolN};

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
    tip: Option<crate::TipObserver<NP>>,
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    ArmController<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// The controller of `tool` for `task` with learning rate γ, starting from
    /// `initial_torque`, ticking at `rate_hz`. Errors for an invalid task or γ, a rate or torque
    /// that is not finite and positive (finite), and a rate too low for the ticks to settle for
    /// this tool and task (`examples/on_robot`'s docs).
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
        let j = crate::TipKinematics::of::<M, NX, NP, NZ>(&q_e, &tool.params())
            .map_or_else(SMatrix::zeros, |t| t.padded_jacobian());
        let contraction = controller.tick_contraction(&b, &j, period);
        if !(contraction.is_finite() && contraction < 1.0) {
            return Err(Error::InvalidOption {
                name: "control rate [Hz] (too low for this tool and task: each tick would not shrink a torque error; raise it)",
                value: rate_hz,
            });
        }
        let tip = crate::tip_parameters::<M, N, NX, NP, NZ>(&tool.params(), task.kind)?;
        Ok(Self {
            controller,
            dynamics: M::dynamics_coefficients(&tool.params()),
            confidence: crate::control_confidence(tool, task)?,
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
        let observed =
            crate::observe_tool::<M, N, NX, NP, NZ>(x, x_dot, &self.torque, self.tip.as_ref());
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
