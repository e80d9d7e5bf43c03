//! [`ArmController`]: the on-robot controller of one tool for one task, ticking at a fixed rate
//! (1 kHz): each tick takes the measured state X = [θ; θ̇] and returns the torque for the next
//! period and the tool's control confidence ln|Π^U|. `examples/on_robot` (the crate a robot's
//! firmware links) documents and tests it, and a model library built by `make model` exports
//! it through its C ABI (`toolconf_controller_tick`, crates/cabi): one controller, so the
//! C ABI's ticks are this code's, bit for bit.

use nalgebra::{SMatrix, SVector};

use crate::validate::{Range, CONTROL_RATE, LEARNING_RATE, TORQUE};
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
    /// `initial_torque`, ticking at `rate_hz`. Errors for an invalid task; a learning rate,
    /// control rate or initial torque outside its range ([`crate::validate::LEARNING_RATE`],
    /// [`crate::validate::CONTROL_RATE`], [`crate::validate::TORQUE`]); and a learning rate
    /// and rate with which the ticks would not settle for this tool and task ([`unsettled`]
    /// names which to change; `examples/on_robot`'s docs).
    pub fn new(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
        initial_torque: [f64; N],
        rate_hz: f64,
    ) -> Result<Self, Error> {
        within("control rate [Hz]", rate_hz, CONTROL_RATE)?;
        within("learning rate", learning_rate, LEARNING_RATE)?;
        for value in initial_torque {
            within("initial torque U0", value, TORQUE)?;
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
            return Err(unsettled(
                &controller.tick_feedback(&b, &j),
                learning_rate,
                rate_hz,
            ));
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

/// `value` if it is in `range`, else the error naming `name` and the range.
fn within(name: &'static str, value: f64, range: Range) -> Result<(), Error> {
    if range.contains(value) {
        Ok(())
    } else {
        Err(Error::OptionOutOfRange { name, value, range })
    }
}

/// Why ticks with learning rate γ at `rate_hz` would not settle, given the tick's feedback
/// `feedback` (ActiveInferenceN::tick_feedback): each tick multiplies a torque error by
/// I − (γ/rate)·feedback, which must shrink it. The option named is the one to change:
/// * no γ/rate shrinks it (a torque direction the task's precisions on U, θ̈ and ÿ leave
///   without feedback): neither option helps;
/// * γ/rate so small that the step is lost to rounding (I − ε·feedback rounds to I): γ;
/// * γ so large that even the fastest rate ([`CONTROL_RATE`]'s bound) does not settle: γ;
/// * otherwise, a faster rate settles: the rate.
fn unsettled<const N: usize>(
    feedback: &SMatrix<f64, N, N>,
    learning_rate: f64,
    rate_hz: f64,
) -> Error {
    let radius = crate::linalg::spectral_radius(feedback);
    let contraction = |step: f64| {
        crate::linalg::spectral_radius(&(SMatrix::<f64, N, N>::identity() - feedback * step))
    };
    // A step of a thousandth of the feedback's size shrinks every direction it reaches.
    let reaches_all = radius > 0.0 && radius.is_finite() && contraction(1e-3 / radius) < 1.0;
    let (name, value) = if !reaches_all {
        ("control rate [Hz] (no rate makes the ticks settle for this tool and task: its precisions on U, θ̈ and the tip's acceleration leave a torque direction without feedback; give P^U weight)", rate_hz)
    } else if learning_rate / rate_hz * radius < 1e-12 {
        // A tick would change a torque error by less than 10⁻¹² of it: lost to rounding.
        ("learning rate (too small for this tool and task at this control rate: a tick would not change the torque; raise it)", learning_rate)
    } else if !(contraction(learning_rate / CONTROL_RATE.hi) < 1.0) {
        ("learning rate (too large for this tool and task: the ticks would not settle at any control rate up to 1e6 Hz; lower it)", learning_rate)
    } else {
        ("control rate [Hz] (too low for this tool and task: each tick would not shrink a torque error; raise it)", rate_hz)
    };
    Error::InvalidOption { name, value }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Arm2;

    type Controller = ArmController<Arm2, 2, 4, 4, 6>;

    /// The controller of the paper's first arm ([0.3, 0.4, 0.5, 0.2]), or a light one whose
    /// ∂θ̈2/∂T2 ~ 3/(m2 l2²) = 375 s⁻² per N m, on `kind`.
    fn made(
        light: bool,
        kind: TaskKind,
        gamma: f64,
        u0: f64,
        rate: f64,
    ) -> Result<Controller, Error> {
        let p = if light {
            [0.3, 0.2, 0.5, 0.2]
        } else {
            [0.3, 0.4, 0.5, 0.2]
        };
        let tool = ToolN::new(p).unwrap();
        Controller::new(&tool, &Arm2::paper_task(kind), gamma, [u0; 2], rate)
    }

    fn named(e: Error) -> (&'static str, f64) {
        match e {
            Error::InvalidOption { name, value } | Error::OptionOutOfRange { name, value, .. } => {
                (name, value)
            }
            other => panic!("not an option's error: {other}"),
        }
    }

    #[test]
    fn each_refused_option_is_named_as_itself() {
        use TaskKind::{Acceleration, Position};
        let cases: [(bool, TaskKind, f64, f64, f64, &str, f64); 8] = [
            (false, Position, 1e300, 0.1, 1000.0, "learning rate", 1e300),
            (
                false,
                Position,
                1e-300,
                0.1,
                1000.0,
                "learning rate (too small",
                1e-300,
            ),
            (false, Position, -1.0, 0.1, 1000.0, "learning rate", -1.0),
            (
                false,
                Position,
                1.0,
                1e300,
                1000.0,
                "initial torque U0",
                1e300,
            ),
            (false, Position, 1.0, 0.1, 1e300, "control rate [Hz]", 1e300),
            (false, Position, 1.0, 0.1, 0.0, "control rate [Hz]", 0.0),
            // The light arm on task 3 needs a faster rate at γ = 1 ...
            (
                true,
                Acceleration,
                1.0,
                0.1,
                1000.0,
                "control rate [Hz] (too low",
                1000.0,
            ),
            // ... and no rate up to 1 MHz settles γ = 10⁶.
            (
                true,
                Acceleration,
                1e6,
                0.1,
                1000.0,
                "learning rate (too large",
                1e6,
            ),
        ];
        for (light, kind, gamma, u0, rate, name, value) in cases {
            let e = made(light, kind, gamma, u0, rate).unwrap_err();
            let (got, v) = named(e);
            assert!(
                got.starts_with(name) && v == value,
                "γ {gamma}, U0 {u0}, {rate} Hz: {e}"
            );
        }
        assert!(made(false, TaskKind::Position, 1.0, 0.1, 1000.0).is_ok());
        // The message's bound is the range's.
        assert_eq!(CONTROL_RATE.hi, 1e6);
    }
}
