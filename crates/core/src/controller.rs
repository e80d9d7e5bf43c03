//! [`ActiveInferenceN`]: the task-based active-inference controller of one tool for one task
//! (the paper's appendix "Task specific controllers"), and [`ActiveInferenceN::tick`], one control
//! period of it on a robot.

use nalgebra::{SMatrix, SVector};

use crate::generated::{Read, Term, TERMS};
use crate::{control_confidence, ArmModel, Error, TaskN, ToolN};

/// The value of every free-energy term at one instant, by [`Term::index`] (θ, θ̇, θ̈ and U for
/// the paper's terms): what the controller observes ([`observe`]).
pub type ObservationN<const N: usize> = [SVector<f64, N>; TERMS];

/// Every term read from the state X, its rate Ẋ and the control U, as [`Term::read`] says; a
/// term read from the tool's tip ([`Read::Tip`]) is zero here: [`observe_with_tip`] reads it.
#[inline]
pub fn observe<const N: usize, const NX: usize>(
    x: &SVector<f64, NX>,
    x_dot: &SVector<f64, NX>,
    u: &SVector<f64, N>,
) -> ObservationN<N> {
    Term::ALL.map(|term| match term.read() {
        Read::State { block } => x.fixed_rows::<N>(block * N).into_owned(),
        Read::StateRate { block } => x_dot.fixed_rows::<N>(block * N).into_owned(),
        Read::Control => *u,
        Read::Tip { .. } => SVector::zeros(),
    })
}

/// The tool tip's kinematics at the measured joint positions q: y(q) in the base frame and
/// J(q) = ∂y/∂q (the generated `tip::<model>`), of which a tip task uses the first `dim`
/// components ([`crate::ArmModel::tip_dim`]), and, where the task reads the tip's acceleration,
/// J̇(q, q̇) q̇ (the generated `tip_bias::<model>`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipKinematics<const N: usize> {
    pub position: SVector<f64, 3>,
    pub jacobian: SMatrix<f64, 3, N>,
    pub dim: usize,
    /// J̇ q̇, the tip's acceleration at q̈ = 0: `None` unless asked for ([`Self::with_bias`]).
    pub bias: Option<SVector<f64, 3>>,
}

impl<const N: usize> TipKinematics<N> {
    /// The tip of the tool with parameters `p` at joint positions `q` (`None` for a model
    /// without one).
    #[inline]
    pub fn of<M, const NX: usize, const NP: usize, const NZ: usize>(
        q: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<Self>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::tip(q, p).map(|(position, jacobian)| Self {
            position,
            jacobian,
            dim: M::tip_dim(),
            bias: None,
        })
    }

    /// The same with J̇(q, q̇) q̇ at joint rates `q_dot` (`None` for a model without a tip).
    #[inline]
    pub fn with_bias<M, const NX: usize, const NP: usize, const NZ: usize>(
        self,
        q: &SVector<f64, N>,
        q_dot: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<Self>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::tip_bias(q, q_dot, p).map(|bias| Self {
            bias: Some(bias),
            ..self
        })
    }

    /// The first `dim` components of a tip vector in the N slots of a term, zeros after
    /// ([`crate::TaskN`]'s padding).
    #[inline]
    pub fn pad(&self, v: &SVector<f64, 3>) -> SVector<f64, N> {
        SVector::from_fn(|i, _| if i < self.dim.min(3) { v[i] } else { 0.0 })
    }

    /// J's first `dim` rows in an N × N matrix, zero rows after: ∂(padded y)/∂q.
    #[inline]
    pub fn padded_jacobian(&self) -> SMatrix<f64, N, N> {
        SMatrix::from_fn(|i, j| {
            if i < self.dim.min(3) {
                self.jacobian[(i, j)]
            } else {
                0.0
            }
        })
    }
}

/// [`observe`], and the terms read from the tool's tip at the same instant: y = y(q) (the
/// generated forward kinematics, not its linearisation), ẏ = J(q) q̇ and, where `tip` has its
/// bias, ÿ = J(q) q̈ + J̇ q̇ (q̈ the plant's, from Ẋ), each padded. Without the bias ÿ is zero,
/// as every term the task does not read.
#[inline]
pub fn observe_with_tip<const N: usize, const NX: usize>(
    x: &SVector<f64, NX>,
    x_dot: &SVector<f64, NX>,
    u: &SVector<f64, N>,
    tip: &TipKinematics<N>,
) -> ObservationN<N> {
    let mut observed = observe(x, x_dot, u);
    for term in Term::ALL {
        if let Read::Tip { order } = term.read() {
            observed[term.index()] = match (order, tip.bias) {
                (0, _) => tip.pad(&tip.position),
                (1, _) => tip.pad(&(tip.jacobian * x.fixed_rows::<N>(N))),
                // The derivation's orders stop at 2 (derive/tasks.toml).
                (_, Some(bias)) => tip.pad(&(tip.jacobian * x_dot.fixed_rows::<N>(N) + bias)),
                (_, None) => SVector::zeros(),
            };
        }
    }
    observed
}

/// What observing a tool's tip needs on a tip task ([`tip_parameters`]): the tool's
/// parameters, for y(q; p), and whether the task reads the tip's acceleration, for which each
/// observation also evaluates J̇ q̇.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipObserver<const NP: usize> {
    pub params: SVector<f64, NP>,
    pub acceleration: bool,
}

/// What observing a tool's tip on model `M` needs: on a task that reads the tip
/// ([`crate::reads_tip`]), the tool's parameters `p`, for y(q; p); `None` on a joint-space task,
/// which never evaluates the tip. A tip task on a model without a tip is [`Error::NoTip`].
pub fn tip_parameters<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    p: &SVector<f64, NP>,
    kind: crate::TaskKind,
) -> Result<Option<TipObserver<NP>>, Error>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    if !crate::reads_tip(kind) {
        return Ok(None);
    }
    let q_e = M::equilibrium_state().fixed_rows::<N>(0).into_owned();
    let acceleration = crate::reads_tip_acceleration(kind);
    let bias = !acceleration || M::tip_bias(&q_e, &SVector::zeros(), p).is_some();
    match M::tip(&q_e, p) {
        Some(_) if bias => Ok(Some(TipObserver {
            params: *p,
            acceleration,
        })),
        _ => Err(Error::NoTip {
            kind,
            model: M::name(),
        }),
    }
}

/// The tip's kinematics at state `x` for [`observe_with_tip`]: J̇ q̇ too where the task reads ÿ.
#[inline]
pub fn tip_kinematics<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    x: &SVector<f64, NX>,
    tip: &TipObserver<NP>,
) -> Option<TipKinematics<N>>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let q = x.fixed_rows::<N>(0).into_owned();
    let kinematics = TipKinematics::of::<M, NX, NP, NZ>(&q, &tip.params)?;
    if !tip.acceleration {
        return Some(kinematics);
    }
    let q_dot = x.fixed_rows::<N>(N).into_owned();
    kinematics.with_bias::<M, NX, NP, NZ>(&q, &q_dot, &tip.params)
}

/// [`observe_with_tip`] of the tool `tip` ([`tip_parameters`]), or [`observe`] on a
/// joint-space task (`None`).
#[inline]
pub fn observe_tool<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    x: &SVector<f64, NX>,
    x_dot: &SVector<f64, NX>,
    u: &SVector<f64, N>,
    tip: Option<&TipObserver<NP>>,
) -> ObservationN<N>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    match tip.and_then(|t| tip_kinematics::<M, N, NX, NP, NZ>(x, t)) {
        Some(tip) => observe_with_tip(x, x_dot, u, &tip),
        None => observe(x, x_dot, u),
    }
}

/// The control U of an observation (the value of the term [`Read::Control`] reads).
#[inline]
pub fn control_of<const N: usize>(observation: &ObservationN<N>) -> &SVector<f64, N> {
    &observation[Term::CONTROL.index()]
}

/// Σ of `terms` in order, the first one as it is (no zero it is added to: −0 stays −0).
fn sum<const R: usize, const C: usize>(
    terms: impl Iterator<Item = SMatrix<f64, R, C>>,
) -> SMatrix<f64, R, C> {
    terms.reduce(|a, b| a + b).unwrap_or_else(SMatrix::zeros)
}

/// The task-based active-inference controller of one tool for one task, U̇ = −γ ∂F/∂U
/// (eq. U_dot_deriv), with every matrix that does not change during an episode precomputed.
///
/// The runtime integrates U̇ with the plant (`toolconf_model::model::ClosedLoopN`); a robot calls
/// [`ActiveInferenceN::tick`] once per control period instead.
#[derive(Debug, Clone, Copy)]
pub struct ActiveInferenceN<const N: usize> {
    pub task: TaskN<N>,
    /// Learning rate γ of the gradient descent (eq. AIC_gradient_des).
    pub learning_rate: f64,
    /// K = Sᵀ P for each term, by [`Term::index`], so that ∂F/∂U = Σ K (e − e^g): zero for a
    /// term the task does not use, P^U for the control's own term (S = ∂U/∂U = I).
    gain: [SMatrix<f64, N, N>; TERMS],
    /// ln|Π^U|, constant for the tool and task (eq. control_conf).
    pub logdet: f64,
}

impl<const N: usize> ActiveInferenceN<N> {
    pub fn new<M, const NX: usize, const NP: usize, const NZ: usize>(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
    ) -> Result<Self, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        if !(learning_rate.is_finite() && learning_rate > 0.0) {
            return Err(Error::InvalidOption {
                name: "learning rate",
                value: learning_rate,
            });
        }
        let confidence = control_confidence(tool, task)?;
        let s = tool.sensitivities(task.kind);
        let gain = Term::ALL.map(|term| match (term.has_sensitivity(), s.of(term)) {
            (false, _) => *task.precision(term),
            (true, Some(s)) => s.transpose() * task.precision(term),
            (true, None) => SMatrix::zeros(),
        });
        Ok(Self {
            task: *task,
            learning_rate,
            gain,
            logdet: confidence.logdet,
        })
    }

    /// U̇ = −γ ∂F/∂U (eq. U_dot_deriv) from the observed terms (η^U = 0).
    #[inline]
    pub fn control_rate(&self, observed: &ObservationN<N>) -> SVector<f64, N> {
        let t = &self.task;
        let gradient = sum(Term::ALL
            .iter()
            .map(|&term| self.gain[term.index()] * (observed[term.index()] - t.goal(term))));
        -self.learning_rate * gradient
    }

    /// One control period on a robot: U̇ = −γ ∂F/∂U (eq. U_dot_deriv, [`Self::control_rate`])
    /// from the measured terms, U among them the torque applied over the last period, then the
    /// torque for the next one, U + period·U̇: the paper's gradient flow discretised by explicit
    /// Euler at the control rate (first order: the torques differ from the continuous
    /// controller's by O(period)). No allocation, a few N×N products.
    ///
    /// The discrete loop can diverge where the continuous one settles: a term read from Ẋ (θ̈)
    /// follows U through the plant's input matrix B, so each tick multiplies a torque error by
    /// I − period·γ(Σ K ∂(term)/∂U); [`Self::tick_contraction`] gives that factor's size.
    #[inline]
    pub fn tick(&self, observed: &ObservationN<N>, period: f64) -> SVector<f64, N> {
        control_of(observed) + self.control_rate(observed) * period
    }

    /// The spectral radius of I − period·γ Σ K ∂(term)/∂U over the terms that follow U within
    /// a tick: B's block for a term read from Ẋ (θ̈: the lower N rows of the plant's input matrix
    /// `b`), the tip's padded Jacobian `tip_jacobian` times it for the tip's acceleration
    /// (ÿ = J q̈ + J̇ q̇), I for U itself. It is how much one [`Self::tick`] multiplies a torque
    /// error by, linearised where B and J were taken. Below 1 the ticks settle as the continuous
    /// controller does; at 1 or above they oscillate without decaying or diverge, and the control
    /// rate must be raised. Light distal links make ∂θ̈/∂U large (~3/(m₂l₂²) for the paper's
    /// arm), and task 3's P^θ̈ = 10 ten times the others'.
    pub fn tick_contraction<const NX: usize>(
        &self,
        b: &SMatrix<f64, NX, N>,
        tip_jacobian: &SMatrix<f64, N, N>,
        period: f64,
    ) -> f64 {
        let g = self.learning_rate * period;
        let step = SMatrix::<f64, N, N>::identity() - self.tick_feedback(b, tip_jacobian) * g;
        crate::linalg::spectral_radius(&step)
    }

    /// Σ K ∂(term)/∂U over the terms that follow U within a tick ([`Self::tick_contraction`]
    /// without γ and the period): how a tick feeds a torque error back, per unit of γ·period.
    pub fn tick_feedback<const NX: usize>(
        &self,
        b: &SMatrix<f64, NX, N>,
        tip_jacobian: &SMatrix<f64, N, N>,
    ) -> SMatrix<f64, N, N> {
        sum(Term::ALL.iter().filter_map(|&term| {
            let k = self.gain[term.index()];
            match term.read() {
                Read::State { .. } | Read::Tip { order: 0 | 1 } => None,
                Read::StateRate { block } => Some(k * b.fixed_rows::<N>(block * N)),
                Read::Tip { .. } => Some(k * tip_jacobian * b.fixed_rows::<N>(N)),
                Read::Control => Some(k),
            }
        }))
    }

    /// The gains γ·K of U̇ = −γ ∂F/∂U by [`Term::index`] (γ·P^U for the control's term), for
    /// the closed-loop Jacobian.
    pub fn scaled_gains(&self) -> [SMatrix<f64, N, N>; TERMS] {
        let g = self.learning_rate;
        self.gain.map(|k| g * k)
    }

    /// The performance and control-cost part of F, ½[Σ eᵀPe + UᵀP^U U] over the task's terms:
    /// the optimal-control cost J of the paper (F without the confidence term), summed in
    /// [`Term::COST_ORDER`].
    #[inline]
    pub fn cost_j(&self, observed: &ObservationN<N>) -> f64 {
        let t = &self.task;
        let mut sum = 0.0;
        for term in Term::COST_ORDER {
            if t.kind.uses(term) {
                let e = observed[term.index()] - t.goal(term);
                sum += e.dot(&(t.precision(term) * e));
            }
        }
        0.5 * sum
    }

    /// F = J − ½ ln|Π^U| (eq. free_energy).
    #[inline]
    pub fn free_energy(&self, observed: &ObservationN<N>) -> f64 {
        self.cost_j(observed) - 0.5 * self.logdet
    }

    /// The task's own weighted error at one instant, the summand of the paper's task error:
    /// (e − e^g)ᵀP(e − e^g) on the task's error term e ([`crate::TaskKind::error_term`]): θ in
    /// task 1, θ̇ in task 2, θ̈ in task 3.
    #[inline]
    pub fn task_error(&self, observed: &ObservationN<N>) -> f64 {
        let t = &self.task;
        let term = t.kind.error_term();
        let e = observed[term.index()] - t.goal(term);
        e.dot(&(t.precision(term) * e))
    }
}
