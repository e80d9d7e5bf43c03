//! [`ArmModel`]: what the controller and the runtime need of a generated model, and one marker
//! type implementing it per model in the generated registry.

use core::fmt::Debug;

use nalgebra::{SMatrix, SVector};

use crate::generated;
use crate::generated::TaskKind;

use super::{SensitivitiesN, TaskN, ToolN};

/// The equations and closed forms of one generated model, with N joints, state dimension NX,
/// NP tool parameters and closed-loop dimension NZ = NX + N.
pub trait ArmModel<const N: usize, const NX: usize, const NP: usize, const NZ: usize>:
    Copy + Debug + Default + Send + Sync + 'static
{
    /// The model's name (`generated::<name>`; a loaded model library's own, or the name it was
    /// loaded under). Functions rather than constants, so that a model whose metadata is known
    /// only at run time (a library loaded by toolconf's runtime) implements the trait too.
    fn name() -> &'static str;
    /// The tool parameters in the order every function takes them.
    fn parameter_names() -> &'static [&'static str; NP];
    /// The equilibrium state X^e the model is linearised at.
    fn equilibrium_state() -> SVector<f64, NX>;
    /// The equilibrium torque U^e.
    fn equilibrium_control() -> SVector<f64, N>;
    /// How many components of the tip a tip task uses (3; 2 for a planar arm, in its plane;
    /// the description's `[tip] components`): see [`TaskN`] for how they are stored.
    fn tip_dim() -> usize;
    /// Which tools are valid (each parameter's domain, constraints across them) and the box
    /// random tools are drawn from: the model description's, `generated::validity::<name>`.
    fn tool_rule() -> &'static generated::validity::ToolRule<NP>;

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
    /// The robot's own rigid-body dynamics Ẋ = [q̇; q̈] with U the joint torques
    /// (`generated::rigid_body::<name>`): a URDF arm's without the joint impedance its plant
    /// [`ArmModel::dynamics`] adds; for the other models, whose plant is their rigid-body
    /// dynamics, the same function.
    fn rigid_body_dynamics(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> SVector<f64, NX>;
    /// The tool's tip y(q; p) in the base frame (m) and its Jacobian J = ∂y/∂q (3 × N)
    /// (`generated::tip::<name>`), `None` for a model whose description gives no tip.
    fn tip(
        q: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<(SVector<f64, 3>, SMatrix<f64, 3, N>)>;
    /// The tip's acceleration at zero joint acceleration, J̇(q, q̇) q̇ (base frame, m/s²;
    /// `generated::tip_bias::<name>`), so that ÿ = J(q) q̈ + J̇ q̇; `None` without a tip.
    fn tip_bias(
        q: &SVector<f64, N>,
        q_dot: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<SVector<f64, 3>>;
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
}

/// Implements [`ArmModel`] for a marker type by forwarding to `toolconf_generated::$module`.
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
            #[inline]
            fn name() -> &'static str {
                generated::$module::NAME
            }

            #[inline]
            fn parameter_names() -> &'static [&'static str; generated::$module::PARAMETER_COUNT] {
                &generated::$module::PARAMETER_NAMES
            }

            #[inline]
            fn equilibrium_state() -> SVector<f64, { generated::$module::STATE_DIM }> {
                SVector::from(generated::$module::EQUILIBRIUM_STATE)
            }

            #[inline]
            fn equilibrium_control() -> SVector<f64, { generated::$module::DOF }> {
                SVector::from(generated::$module::EQUILIBRIUM_CONTROL)
            }

            #[inline]
            fn tip_dim() -> usize {
                generated::$module::TIP_DIM
            }

            #[inline]
            fn tool_rule(
            ) -> &'static generated::validity::ToolRule<{ generated::$module::PARAMETER_COUNT }> {
                &generated::validity::$module::RULE
            }

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

            // Always: a forwarder, which the compiler kept out of line around a small model's
            // inlined body (the generated `dynamics_with` is always inlined where it is cheap).
            #[inline(always)]
            fn dynamics_with(
                x: &SVector<f64, { generated::$module::STATE_DIM }>,
                u: &SVector<f64, { generated::$module::DOF }>,
                k: &Self::DynamicsCoefficients,
            ) -> SVector<f64, { generated::$module::STATE_DIM }> {
                generated::$module::dynamics_with(x, u, k)
            }

            // Always: a forwarder, which the compiler kept out of line around a small model's
            // inlined body (the generated `dynamics_jacobian_with` is always inlined where it is cheap).
            #[inline(always)]
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
            fn rigid_body_dynamics(
                x: &SVector<f64, { generated::$module::STATE_DIM }>,
                u: &SVector<f64, { generated::$module::DOF }>,
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> SVector<f64, { generated::$module::STATE_DIM }> {
                generated::rigid_body::$module(x, u, p)
            }

            #[inline]
            fn tip(
                q: &SVector<f64, { generated::$module::DOF }>,
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> Option<(SVector<f64, 3>, SMatrix<f64, 3, { generated::$module::DOF }>)> {
                generated::tip::$module(q, p)
            }

            #[inline]
            fn tip_bias(
                q: &SVector<f64, { generated::$module::DOF }>,
                q_dot: &SVector<f64, { generated::$module::DOF }>,
                p: &SVector<f64, { generated::$module::PARAMETER_COUNT }>,
            ) -> Option<SVector<f64, 3>> {
                generated::tip_bias::$module(q, q_dot, p)
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
                    &task.precision,
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
                    &task.precision,
                )
            }

            fn paper_task(kind: TaskKind) -> TaskN<{ generated::$module::DOF }> {
                TaskN::from_defaults(
                    kind,
                    &generated::$module::task_defaults(kind),
                    generated::$module::TIP_DIM,
                )
            }
        }
    };
}

/// [`TaskN::paper`](crate::TaskN) for the paper's arm, where the generated crate has it (`arm2`):
/// a crate generated from other models alone (a model library of `make model`) has no such task.
macro_rules! paper_arm {
    (Arm2) => {
        impl TaskN<2> {
            /// The paper's task `kind` for its arm, with the published goals and precisions
            /// ("Implementation details"; [`ArmModel::paper_task`] of [`crate::Arm2`]; another
            /// model's is its own `paper_task`).
            pub fn paper(kind: TaskKind) -> Self {
                crate::Arm2::paper_task(kind)
            }
        }
    };
    ($other:ident) => {};
}

/// One marker type, its [`ArmModel`] implementation and its tool alias per generated model.
macro_rules! arm_models {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        $(
            paper_arm!($marker);
            arm_model!(
                #[doc = concat!($title, " (`toolconf_generated::", $name, "`).")]
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

generated::for_each_model!(arm_models);
