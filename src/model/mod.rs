//! The runtime, generic over the arm model: control confidence, controller, closed loop and
//! episode for any model that `make derive` generates, with fixed sizes as const generics.
//!
//! This is the implementation. The 2-link modules [`crate::confidence`] and
//! [`crate::closed_loop`] are a façade over it for the paper's arm (`Arm`, `Task`, `Matrix2`,
//! `Plant`, errors naming `arm m1=…`): they convert and delegate, so the math lives here once and
//! nothing outside the generated 2-link model assumes 2×2.
//!
//! * [`ArmModel`] is implemented for one marker type per generated model ([`Arm2`],
//!   [`Arm2Exact`], [`Arm3`], ...), forwarding to the generated module; the list comes from the
//!   generated registry ([`crate::for_each_model!`]), so a new model description needs no edit here.
//! * [`ToolN`] (validated parameters), [`TaskN`] (goals and precisions), [`control_confidence`]
//!   (Π^U and ln|Π^U|), [`ActiveInferenceN`], [`ClosedLoopN`], [`simulate`]/[`simulate_on`]
//!   (metrics) and [`episode`]/[`episode_on`] (metrics and trajectory). With [`Arm2`] they are
//!   the 2-link runtime; tests/generic_runtime.rs checks the façade and the generic entry points
//!   agree bit for bit.
//! * [`mixed`] draws and ranks tool sets that mix models.
//!
//! The sizes are N (joints = torques), NX = 2N (state X = [θ; θ̇]), NP (tool parameters) and
//! NZ = NX + N (closed-loop state Z = [X; U]). NZ is a parameter of its own because stable Rust
//! cannot write `NX + N` in a type; the `arm_model!` macro sets it and [`ClosedLoopN::new`]
//! checks `NX == 2N` and `NZ == NX + N` at compile time (a post-monomorphisation assertion).

use std::fmt;
use std::fmt::Debug;
use std::marker::PhantomData;

use nalgebra::{SMatrix, SVector};

use crate::generated;
use crate::generated::TaskKind;
use crate::Error;

pub mod mixed;
pub(crate) mod runtime;

pub use runtime::{
    episode, episode_on, simulate, simulate_on, ActiveInferenceN, ClosedLoopN, EpisodeN,
    EpisodeOptionsN, Metrics, ModelSimulationError, TrajectoryN, MAX_GRID_POINTS,
};

/// The equations and closed forms of one generated model, with N joints, state dimension NX,
/// NP tool parameters and closed-loop dimension NZ = NX + N.
pub trait ArmModel<const N: usize, const NX: usize, const NP: usize, const NZ: usize>:
    Copy + Debug + Default + Send + Sync + 'static
{
    /// The model's name (`generated::<name>`).
    const NAME: &'static str;
    /// The tool parameters in the order every function takes them.
    const PARAMETER_NAMES: [&'static str; NP];
    /// The equilibrium state X^e the model is linearised at.
    const EQUILIBRIUM_STATE: [f64; NX];

    /// The parameter-only factors of [`ArmModel::dynamics`], computed once per tool.
    type DynamicsCoefficients: Copy + Debug + Send + Sync;
    /// The parameter-only factors of [`ArmModel::dynamics_jacobian`], computed once per tool.
    type JacobianCoefficients: Copy + Debug + Send + Sync;

    fn dynamics_coefficients(p: &SVector<f64, NP>) -> Self::DynamicsCoefficients;
    fn jacobian_coefficients(p: &SVector<f64, NP>) -> Self::JacobianCoefficients;
    /// Ẋ = f(X, U; p) with the tool's coefficients: what an integrator calls ~10³ times per episode.
    fn dynamics_with(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        k: &Self::DynamicsCoefficients,
    ) -> SVector<f64, NX>;
    /// (∂f/∂X, ∂f/∂U) with the tool's coefficients.
    fn dynamics_jacobian_with(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        k: &Self::JacobianCoefficients,
    ) -> (SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>);
    /// Ẋ = f(X, U; p), for a one-off evaluation (an integrator keeps the coefficients).
    #[inline]
    fn dynamics(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> SVector<f64, NX> {
        Self::dynamics_with(x, u, &Self::dynamics_coefficients(p))
    }
    /// (∂f/∂X, ∂f/∂U) at any X, U, for a one-off evaluation.
    #[inline]
    fn dynamics_jacobian(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> (SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        Self::dynamics_jacobian_with(x, u, &Self::jacobian_coefficients(p))
    }
    /// A = ∂f/∂X at the equilibrium.
    fn state_matrix(p: &SVector<f64, NP>) -> SMatrix<f64, NX, NX>;
    /// B = ∂f/∂U at the equilibrium.
    fn input_matrix(p: &SVector<f64, NP>) -> SMatrix<f64, NX, N>;
    /// The task's sensitivities ∂(task variable)/∂U.
    fn sensitivities(kind: TaskKind, p: &SVector<f64, NP>) -> SensitivitiesN<N>;
    /// Π^U = Σ Sᵀ P S over the task's terms + P^U, unvalidated (the generated closed form).
    fn pi_u(task: &TaskN<N>, p: &SVector<f64, NP>) -> SMatrix<f64, N, N>;
    /// ∂ln|Π^U|/∂p = tr((Π^U)⁻¹ ∂Π^U/∂p_i) per tool parameter (Jacobi's formula; the generated
    /// `<task>_logdet_gradient`): what `toolconf design` climbs. Unvalidated like [`ArmModel::pi_u`].
    fn logdet_gradient(task: &TaskN<N>, p: &SVector<f64, NP>) -> SVector<f64, NP>;
    /// The model's paper-style task: its own goals (`derive/models/<name>.toml`) and the
    /// paper's precisions (`derive/tasks.toml`).
    fn paper_task(kind: TaskKind) -> TaskN<N>;

    /// X^e as a vector.
    fn equilibrium_state() -> SVector<f64, NX> {
        SVector::from(Self::EQUILIBRIUM_STATE)
    }
}

/// Implements [`ArmModel`] for a marker type by forwarding to `crate::generated::$module`.
macro_rules! arm_model {
    ($(#[$doc:meta])* $marker:ident => $module:ident) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
        pub struct $marker;

        impl
            ArmModel<
                { generated::$module::DOF },
                { generated::$module::STATE_DIM },
                { generated::$module::PARAMETER_COUNT },
                { generated::$module::STATE_DIM + generated::$module::DOF },
            > for $marker
        {
            const NAME: &'static str = generated::$module::NAME;
            const PARAMETER_NAMES: [&'static str; generated::$module::PARAMETER_COUNT] =
                generated::$module::PARAMETER_NAMES;
            const EQUILIBRIUM_STATE: [f64; generated::$module::STATE_DIM] =
                generated::$module::EQUILIBRIUM_STATE;
            type DynamicsCoefficients = generated::$module::DynamicsCoefficients;
            type JacobianCoefficients = generated::$module::DynamicsJacobianCoefficients;

            #[inline]
            fn dynamics_coefficients(
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> Self::DynamicsCoefficients {
                generated::$module::DynamicsCoefficients::new(p)
            }

            #[inline]
            fn jacobian_coefficients(
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> Self::JacobianCoefficients {
                generated::$module::DynamicsJacobianCoefficients::new(p)
            }

            #[inline]
            fn dynamics_with(
                x: &SVector<f64, { generated::$module::STATE_DIM }>,
                u: &SVector<f64, { generated::$module::DOF }>,
                k: &Self::DynamicsCoefficients,
            ) -> SVector<f64, { generated::$module::STATE_DIM }> {
                generated::$module::dynamics_with(x, u, k)
            }

            #[inline]
            fn dynamics_jacobian_with(
                x: &SVector<f64, { generated::$module::STATE_DIM }>,
                u: &SVector<f64, { generated::$module::DOF }>,
                k: &Self::JacobianCoefficients,
            ) -> (
                SMatrix<f64, { generated::$module::STATE_DIM }, { generated::$module::STATE_DIM }>,
                SMatrix<f64, { generated::$module::STATE_DIM }, { generated::$module::DOF }>,
            ) {
                generated::$module::dynamics_jacobian_with(x, u, k)
            }

            #[inline]
            fn state_matrix(
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> SMatrix<f64, { generated::$module::STATE_DIM }, { generated::$module::STATE_DIM }>
            {
                generated::$module::state_matrix(p)
            }

            #[inline]
            fn input_matrix(
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> SMatrix<f64, { generated::$module::STATE_DIM }, { generated::$module::DOF }> {
                generated::$module::input_matrix(p)
            }

            #[inline]
            fn sensitivities(
                kind: TaskKind,
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> SensitivitiesN<{ generated::$module::DOF }> {
                generated::$module::task_sensitivities(kind, p)
            }

            #[inline]
            fn pi_u(
                task: &TaskN<{ generated::$module::DOF }>,
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> SMatrix<f64, { generated::$module::DOF }, { generated::$module::DOF }> {
                generated::$module::task_control_confidence(
                    task.kind,
                    p,
                    &task.precision_theta,
                    &task.precision_theta_dot,
                    &task.precision_theta_ddot,
                    &task.precision_u,
                )
            }

            #[inline]
            fn logdet_gradient(
                task: &TaskN<{ generated::$module::DOF }>,
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> SVector<f64, { generated::$module::PARAMETER_COUNT }> {
                generated::$module::task_logdet_gradient(
                    task.kind,
                    p,
                    &task.precision_theta,
                    &task.precision_theta_dot,
                    &task.precision_theta_ddot,
                    &task.precision_u,
                )
            }

            fn paper_task(kind: TaskKind) -> TaskN<{ generated::$module::DOF }> {
                TaskN::from_defaults(kind, &generated::$module::task_defaults(kind))
            }
        }
    };
}

/// One marker type, its [`ArmModel`] implementation and its tool alias per generated model.
macro_rules! arm_models {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        $(
            arm_model!(
                #[doc = concat!($title, " (`generated::", $name, "`).")]
                $marker => $module
            );
            #[doc = concat!("A tool of the `", $name, "` model.")]
            pub type $tool = ToolN<
                $marker,
                { generated::$module::DOF },
                { generated::$module::STATE_DIM },
                { generated::$module::PARAMETER_COUNT },
                { generated::$module::STATE_DIM + generated::$module::DOF },
            >;
        )*
    };
}

crate::for_each_model!(arm_models);

/// The sensitivities ∂θ/∂U, ∂θ̇/∂U, ∂θ̈/∂U that a task's controller uses (eq. U_dot_deriv), `None`
/// for a term the task does not use ([`crate::Sensitivities`] is the 2-link one). Task 1's ∂θ/∂U
/// is [I O]A⁻¹(∂Ẋ/∂U − B) with ∂Ẋ/∂U = [I; I]; ∂θ̇/∂U is [O I]A⁻¹(∂Ẋ/∂U − B) = I in task 1 and
/// −[I O]A⁻¹B in task 2, as the paper prints it; ∂θ̈/∂U is I in every task (zero jerk in tasks
/// 1–2, [I O](A²∂X/∂U + AB) = I in task 3). The formulas are `derive/tasks.toml`'s.
pub type SensitivitiesN<const N: usize> = generated::TaskSensitivities<N>;

/// One tool of model `M`: its parameters, each finite and > 0.
///
/// The parameters are private so that every `ToolN` has passed [`ToolN::new`].
pub struct ToolN<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> {
    params: SVector<f64, NP>,
    model: PhantomData<M>,
}

// Manual impls: derives would require `M: Clone` etc. through `PhantomData`'s bounds anyway, and
// `M` is a zero-sized marker.
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Clone
    for ToolN<M, N, NX, NP, NZ>
{
    fn clone(&self) -> Self {
        *self
    }
}
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Copy
    for ToolN<M, N, NX, NP, NZ>
{
}
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> PartialEq
    for ToolN<M, N, NX, NP, NZ>
{
    fn eq(&self, other: &Self) -> bool {
        self.params == other.params
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// Validates and builds a tool from its parameters in [`ArmModel::PARAMETER_NAMES`] order.
    /// A non-positive, NaN or infinite value is an [`Error::InvalidParameter`] naming it.
    pub fn new(params: [f64; NP]) -> Result<Self, Error> {
        for (name, value) in M::PARAMETER_NAMES.into_iter().zip(params) {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::InvalidParameter { name, value });
            }
        }
        Ok(Self {
            params: SVector::from(params),
            model: PhantomData,
        })
    }

    /// A tool from parameters a caller has already checked (finite, > 0), such as an
    /// [`crate::Arm`]'s: no second check on the 2-link façade's hot path.
    pub(crate) fn from_checked(params: SVector<f64, NP>) -> Self {
        debug_assert!(params.iter().all(|v| v.is_finite() && *v > 0.0));
        Self {
            params,
            model: PhantomData,
        }
    }

    /// The parameter vector p the generated functions take.
    pub fn params(&self) -> SVector<f64, NP> {
        self.params
    }

    /// The model's name.
    pub fn model_name(&self) -> &'static str {
        M::NAME
    }

    /// (name, value) of every parameter, in order.
    pub fn named_parameters(&self) -> [(&'static str, f64); NP] {
        std::array::from_fn(|i| (M::PARAMETER_NAMES[i], self.params[i]))
    }

    /// Ẋ = f(X, U; p).
    pub fn dynamics(&self, x: &SVector<f64, NX>, u: &SVector<f64, N>) -> SVector<f64, NX> {
        M::dynamics(x, u, &self.params)
    }

    /// A at the equilibrium.
    pub fn state_matrix(&self) -> SMatrix<f64, NX, NX> {
        M::state_matrix(&self.params)
    }

    /// B at the equilibrium.
    pub fn input_matrix(&self) -> SMatrix<f64, NX, N> {
        M::input_matrix(&self.params)
    }

    /// The task's sensitivities.
    pub fn sensitivities(&self, kind: TaskKind) -> SensitivitiesN<N> {
        M::sensitivities(kind, &self.params)
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Debug
    for ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}({self})", M::NAME)
    }
}

/// `m1=… m2=… …`, as [`Arm`] prints itself.
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> fmt::Display
    for ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (name, value)) in self.named_parameters().iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{name}={value}")?;
        }
        Ok(())
    }
}

/// A task for N joints: goals and prior precisions (the N-joint [`Task`]). A term the task's
/// controller does not use has precision zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskN<const N: usize> {
    pub kind: TaskKind,
    pub goal_theta: SVector<f64, N>,
    pub goal_theta_dot: SVector<f64, N>,
    pub goal_theta_ddot: SVector<f64, N>,
    pub precision_theta: SMatrix<f64, N, N>,
    pub precision_theta_dot: SMatrix<f64, N, N>,
    pub precision_theta_ddot: SMatrix<f64, N, N>,
    pub precision_u: SMatrix<f64, N, N>,
}

impl<const N: usize> TaskN<N> {
    /// Checks the task once for ranking many tools ([`ValidatedTaskN::control_confidence`]).
    pub fn validated(&self) -> Result<ValidatedTaskN<N>, Error> {
        self.validate()?;
        Ok(ValidatedTaskN(*self))
    }

    /// The task with a model's generated defaults (goals; precisions P = value · I).
    pub fn from_defaults(kind: TaskKind, d: &generated::TaskDefaults<N>) -> Self {
        let eye = SMatrix::<f64, N, N>::identity();
        TaskN {
            kind,
            goal_theta: SVector::from(d.goal_theta),
            goal_theta_dot: SVector::from(d.goal_theta_dot),
            goal_theta_ddot: SVector::from(d.goal_theta_ddot),
            precision_theta: eye * d.precision_theta,
            precision_theta_dot: eye * d.precision_theta_dot,
            precision_theta_ddot: eye * d.precision_theta_ddot,
            precision_u: eye * d.precision_u,
        }
    }

    /// Model `M`'s paper-style task ([`ArmModel::paper_task`]).
    pub fn paper<M, const NX: usize, const NP: usize, const NZ: usize>(kind: TaskKind) -> Self
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::paper_task(kind)
    }

    /// Checks goals are finite and precisions finite, symmetric and positive semi-definite,
    /// with the errors [`Task::validate`] gives.
    pub fn validate(&self) -> Result<(), Error> {
        for (name, goal) in [
            ("theta_g", &self.goal_theta),
            ("theta_dot_g", &self.goal_theta_dot),
            ("theta_ddot_g", &self.goal_theta_ddot),
        ] {
            if let Some(&value) = goal.iter().find(|v| !v.is_finite()) {
                return Err(Error::InvalidGoal {
                    name: name.into(),
                    value,
                });
            }
        }
        for (name, p) in [
            ("P_theta", &self.precision_theta),
            ("P_theta_dot", &self.precision_theta_dot),
            ("P_theta_ddot", &self.precision_theta_ddot),
            ("P_u", &self.precision_u),
        ] {
            check_precision(name, p)?;
        }
        Ok(())
    }
}

/// Finite, symmetric (to 1e-12 relative) and positive semi-definite: the smallest eigenvalue
/// of the symmetric part is ≥ −1e-12·max|P| (for N = 2 the closed-form determinant test).
fn check_precision<const N: usize>(name: &str, p: &SMatrix<f64, N, N>) -> Result<(), Error> {
    let invalid = |reason: String| Error::InvalidPrecision {
        name: name.into(),
        reason,
    };
    if p.iter().any(|v| !v.is_finite()) {
        return Err(invalid(format!(
            "has a non-finite entry: {:?}",
            p.as_slice()
        )));
    }
    let scale = p.amax();
    for i in 0..N {
        for j in (i + 1)..N {
            if (p[(i, j)] - p[(j, i)]).abs() > 1e-12 * scale.max(1.0) {
                return Err(invalid(format!(
                    "is not symmetric ({} vs {})",
                    p[(i, j)],
                    p[(j, i)]
                )));
            }
        }
    }
    let not_psd = || invalid("is not positive semi-definite".into());
    if N == 2 {
        let det = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)];
        if p[(0, 0)] < 0.0 || p[(1, 1)] < 0.0 || det < -1e-12 * scale.powi(2) {
            return Err(not_psd());
        }
    } else if N > 0 {
        // Dynamic storage: nalgebra's eigen-decomposition needs dimension bounds a const
        // generic N cannot state on stable Rust. Once per task, so the allocation is moot.
        let symmetric = nalgebra::DMatrix::from_fn(N, N, |i, j| 0.5 * (p[(i, j)] + p[(j, i)]));
        let smallest = symmetric.symmetric_eigenvalues().min();
        if smallest < -1e-12 * scale {
            return Err(not_psd());
        }
    }
    Ok(())
}

/// Π^U with its log-determinant ln|Π^U|, the confidence term of the free energy
/// (eq. FE_components); [`crate::ControlConfidence`] is the 2-link one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlConfidenceN<const N: usize> {
    /// Π^U, symmetric positive definite.
    pub pi_u: SMatrix<f64, N, N>,
    /// ln|Π^U|.
    pub logdet: f64,
}

impl<const N: usize> ControlConfidenceN<N> {
    /// ln|Π^U|/N: the mean log precision per control channel, ln of the geometric mean of Π^U's
    /// eigenvalues; the quantity comparable across models with different N (docs/mixed-tools.md).
    pub fn logdet_per_joint(&self) -> f64 {
        self.logdet / N as f64
    }
}

/// The closed-form control confidence of `tool` for `task` (eq. control_conf and the closed
/// forms after it): Π^U = Σ Sᵀ P S over the task's terms, plus P^U, and ln|Π^U|.
///
/// It depends only on the tool and the task's precisions, so it can be computed before the tool
/// is used. Errors if the task is invalid or Π^U is not positive definite
/// ([`Error::NotPositiveDefinite`], with the determinant; possible only with user precisions,
/// e.g. all zero). ln|Π^U| comes from [`logdet_of`].
pub fn control_confidence<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
) -> Result<ControlConfidenceN<N>, Error>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    task.validate()?;
    ValidatedTaskN(*task).control_confidence(tool)
}

/// A task whose goals and precisions have been checked once ([`TaskN::validated`]): ranking many
/// tools for one task then costs only the closed form and the log-determinant per tool, not the
/// task's checks (about half of [`control_confidence`]'s time for the 2-link arm, see
/// docs/performance.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidatedTaskN<const N: usize>(TaskN<N>);

impl<const N: usize> ValidatedTaskN<N> {
    pub fn task(&self) -> &TaskN<N> {
        &self.0
    }

    /// Π^U of `tool` (eq. control_conf), the closed form alone: no positive-definiteness check
    /// and no logarithm (rank by confidence with [`ValidatedTaskN::control_confidence`]).
    #[inline]
    pub fn pi_u<M, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> SMatrix<f64, N, N>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::pi_u(&self.0, &tool.params)
    }

    /// ∂ln|Π^U|/∂p of `tool`, one entry per tool parameter (the generated closed form of
    /// Jacobi's formula, d ln|Π| = tr(Π⁻¹ dΠ)); meaningful where Π^U is positive definite.
    #[inline]
    pub fn logdet_gradient<M, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> SVector<f64, NP>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        M::logdet_gradient(&self.0, &tool.params)
    }

    /// Π^U and ln|Π^U| of `tool` (eq. control_conf); errors only if Π^U is not positive definite.
    #[inline]
    pub fn control_confidence<M, const NX: usize, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> Result<ControlConfidenceN<N>, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let pi_u = self.pi_u(tool);
        let logdet = logdet_of(&pi_u)?;
        Ok(ControlConfidenceN { pi_u, logdet })
    }
}

/// ln|Π| of a symmetric positive definite Π, or [`Error::NotPositiveDefinite`].
///
/// In general 2 Σ ln L_ii of the Cholesky factor. For N = 2 it is ln(Π₀₀Π₁₁ − Π₀₁Π₁₀) instead:
/// a symmetric 2×2 is positive definite iff Π₀₀ > 0 and its determinant > 0, so one product and
/// one logarithm decide and give ln|Π| exactly; Cholesky would also round differently in the last
/// bits, and the paper's numbers (tests/numbers_snapshot.rs and the figure snapshots) are pinned
/// to every digit of this closed form. `N` is a constant, so the branch is resolved at compile
/// time.
#[inline]
pub fn logdet_of<const N: usize>(pi: &SMatrix<f64, N, N>) -> Result<f64, Error> {
    if N == 2 {
        let determinant = pi[(0, 0)] * pi[(1, 1)] - pi[(0, 1)] * pi[(1, 0)];
        if !(pi[(0, 0)] > 0.0 && determinant > 0.0 && determinant.is_finite()) {
            return Err(Error::NotPositiveDefinite { determinant });
        }
        return Ok(determinant.ln());
    }
    let not_pd = || Error::NotPositiveDefinite {
        determinant: nalgebra::DMatrix::from_fn(N, N, |i, j| pi[(i, j)]).determinant(),
    };
    if pi.iter().any(|v| !v.is_finite()) {
        return Err(not_pd());
    }
    let cholesky = nalgebra::Cholesky::new(*pi).ok_or_else(not_pd)?;
    let l = cholesky.l_dirty();
    let mut logdet = 0.0;
    for i in 0..N {
        let d = l[(i, i)];
        if !(d > 0.0 && d.is_finite()) {
            return Err(not_pd());
        }
        logdet += 2.0 * d.ln();
    }
    if logdet.is_finite() {
        Ok(logdet)
    } else {
        Err(not_pd())
    }
}
