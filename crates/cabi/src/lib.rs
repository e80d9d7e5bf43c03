//! # toolconf-cabi: the C ABI of a model library
//!
//! `make model DESC=<description> OUT=<folder>` builds one model into a shared library (a
//! `cdylib`) whose exports are this crate's: [`export_model!`] defines them in the library's own
//! crate (templates/cabi/src/lib.rs.tera), for the model's marker type in toolconf-core and its
//! module in the generated crate. The header `toolconf_model.h` beside the library
//! (templates/cabi/toolconf_model.h.tera) declares the same functions and types; docs/reference/c-abi.md
//! is the reference.
//!
//! * **Versioned.** [`ABI_VERSION`] (`toolconf_abi_version()`) is checked first by any loader;
//!   any change to a signature, a struct or a status code's meaning raises it. The task list the
//!   model was derived with has a fingerprint ([`fingerprint`], `toolconf_tasks_fingerprint()`):
//!   task and term indices mean the same only between a library and a loader whose
//!   fingerprints agree.
//! * **Flat arrays.** Every vector or matrix is a flat `const double*` in or `double*` out, a
//!   matrix column-major (nalgebra's storage: entry (i, j) of an R × C matrix at `i + j·R`). The
//!   per-term arrays (goals, precisions, sensitivities) hold one block per term of
//!   `derive/tasks.toml`, in its order (`Term::ALL`): goals `TERMS × N`, precisions and
//!   sensitivities `TERMS × N × N`, a tip term padded to N as toolconf-core's `TaskN` does.
//! * **Status, never a crash.** Every function returns an `int32_t` [`status`]: 0, or why not
//!   (a null pointer, an unknown task, a non-finite input, ...), the arguments checked in one
//!   order ([`bodies`]), with a message for the calling thread in `toolconf_last_error()`. Outputs
//!   are written only on success, and only finite numbers. A panic is caught at the boundary
//!   ([`status::INTERNAL`]); nothing unwinds into C; an allocation that fails is
//!   [`status::OUT_OF_MEMORY`].
//! * **Checked handles.** A controller handle is a key of the library's registry of live
//!   controllers ([`handles`]): a destroyed, foreign or forged one is
//!   [`status::BAD_HANDLE`], and nothing is read through it.
//! * **The same numbers.** Each function calls the generated function (through toolconf-core's
//!   [`toolconf_core::ArmModel`]) the Rust code calls, and copies; `check::bit_identity` (the
//!   feature `check`) compares every export through its function pointer with the direct
//!   call, bit for bit.
//!
//! Nothing here allocates per call but the controller's creation (its box and room in the
//! registry, both fallible) and the metadata, built once on first use.

use core::ffi::c_char;

pub mod bodies;
#[cfg(feature = "check")]
pub mod check;
pub mod exports;
pub mod fingerprint;
pub mod handles;
pub mod info;
pub mod status;

pub use exports::Exports;
pub use info::{Constraint, Domain, InertiaRule, ModelInfo};

/// toolconf-core, whose marker types and generated crate [`export_model!`] names.
pub use toolconf_core;

/// The version of the C ABI: `toolconf_abi_version()`. A loader refuses a library whose version
/// is not the one it was built for. 2: controller handles are keys of the library's registry
/// (checked, never reused), results are checked finite, and `TOOLCONF_OUT_OF_MEMORY` is new.
pub const ABI_VERSION: u32 = 2;

/// `toolconf_abi_version()`.
pub extern "C" fn abi_version() -> u32 {
    ABI_VERSION
}

/// `toolconf_last_error()`: the calling thread's message for its last nonzero status.
pub extern "C" fn last_error() -> *const c_char {
    status::last_error_ptr()
}

/// `toolconf_status_name(status)`: `"TOOLCONF_OK"`, `"TOOLCONF_NULL_POINTER"`, ...
pub extern "C" fn status_name(code: i32) -> *const c_char {
    status::name(code).as_ptr()
}

/// `toolconf_tasks_fingerprint()`: [`fingerprint::hex`] as a C string.
pub extern "C" fn tasks_fingerprint() -> *const c_char {
    fingerprint::c_hex().as_ptr()
}

/// The exports [`export_model!`] forwards to its model's `ToolconfBodies`: for each, its doc,
/// its C name, the body it calls and its arguments (each written once, for the signature and
/// the call).
#[doc(hidden)]
#[macro_export]
macro_rules! export_forwards {
    ($($(#[$doc:meta])* $export:ident => $body:ident($($arg:ident: $ty:ty),* $(,)?);)*) => {
        $(
            $(#[$doc])*
            #[no_mangle]
            pub unsafe extern "C" fn $export($($arg: $ty),*) -> i32 {
                ToolconfBodies::$body($($arg),*)
            }
        )*
    };
}

/// Defines the exports of a model library for one generated model: `export_model!(Panda,
/// panda)` with the marker type of toolconf-core (`toolconf_core::Panda`) and the model's module
/// in the generated crate. It also defines `EXPORTS`, the same functions as an [`Exports`] table
/// of pointers, for the library's own tests.
#[macro_export]
macro_rules! export_model {
    ($marker:ident, $module:ident) => {
        type ToolconfModel = $crate::toolconf_core::$marker;
        const TOOLCONF_N: usize = $crate::toolconf_core::generated::$module::DOF;
        const TOOLCONF_NX: usize = $crate::toolconf_core::generated::$module::STATE_DIM;
        const TOOLCONF_NP: usize = $crate::toolconf_core::generated::$module::PARAMETER_COUNT;
        const TOOLCONF_NZ: usize = TOOLCONF_NX + TOOLCONF_N;
        type ToolconfBodies = $crate::bodies::Bodies<
            ToolconfModel,
            TOOLCONF_N,
            TOOLCONF_NX,
            TOOLCONF_NP,
            TOOLCONF_NZ,
        >;

        /// The version of the C ABI (checked first).
        #[no_mangle]
        pub extern "C" fn toolconf_abi_version() -> u32 {
            $crate::abi_version()
        }

        /// SHA-256 (hex) of the task and term list the model was derived with.
        #[no_mangle]
        pub extern "C" fn toolconf_tasks_fingerprint() -> *const ::core::ffi::c_char {
            $crate::tasks_fingerprint()
        }

        /// The model's metadata, built on first use, valid while the library is loaded.
        #[no_mangle]
        pub extern "C" fn toolconf_model_info() -> *const $crate::ModelInfo {
            static INFO: ::std::sync::OnceLock<$crate::info::InfoStorage> =
                ::std::sync::OnceLock::new();
            $crate::info::model_info::<
                ToolconfModel,
                TOOLCONF_N,
                TOOLCONF_NX,
                TOOLCONF_NP,
                TOOLCONF_NZ,
            >(&INFO)
        }

        /// The calling thread's message for its last nonzero status.
        #[no_mangle]
        pub extern "C" fn toolconf_last_error() -> *const ::core::ffi::c_char {
            $crate::last_error()
        }

        /// A status code's name.
        #[no_mangle]
        pub extern "C" fn toolconf_status_name(status: i32) -> *const ::core::ffi::c_char {
            $crate::status_name(status)
        }

        $crate::export_forwards! {
            /// Whether `params` is a valid tool by the model's rule.
            toolconf_check_tool => check_tool(params: *const f64);
            /// Ẋ = f(X, U; p).
            toolconf_dynamics => dynamics(
                x: *const f64, u: *const f64, params: *const f64, x_dot: *mut f64,
            );
            /// (∂f/∂X, ∂f/∂U) at (X, U).
            toolconf_dynamics_jacobian => dynamics_jacobian(
                x: *const f64, u: *const f64, params: *const f64, f_x: *mut f64, f_u: *mut f64,
            );
            /// The rigid-body dynamics alone, U the joint torques.
            toolconf_rigid_body_dynamics => rigid_body_dynamics(
                x: *const f64, u: *const f64, params: *const f64, x_dot: *mut f64,
            );
            /// The tool tip y(q) and its Jacobian ∂y/∂q (3 × N).
            toolconf_tip => tip(
                q: *const f64, params: *const f64, position: *mut f64, jacobian: *mut f64,
            );
            /// The tip's acceleration at q̈ = 0, J̇(q, q̇) q̇ (3).
            toolconf_tip_bias => tip_bias(
                q: *const f64, q_dot: *const f64, params: *const f64, bias: *mut f64,
            );
            /// A = ∂f/∂X at the equilibrium.
            toolconf_state_matrix => state_matrix(params: *const f64, a: *mut f64);
            /// B = ∂f/∂U at the equilibrium.
            toolconf_input_matrix => input_matrix(params: *const f64, b: *mut f64);
            /// The model's default goals and precisions of a task.
            toolconf_task_defaults => task_defaults(
                task: u32, goals: *mut f64, precisions: *mut f64,
            );
            /// A task's sensitivities ∂(term)/∂U.
            toolconf_sensitivities => sensitivities(
                task: u32, params: *const f64, sensitivities: *mut f64, used: *mut i32,
            );
            /// Π^U of a task for a tool, given the precisions (the closed form, unvalidated).
            toolconf_pi_u => pi_u(
                task: u32, params: *const f64, precisions: *const f64, pi_u: *mut f64,
            );
            /// ∂ln|Π^U|/∂p (the closed form, unvalidated).
            toolconf_logdet_gradient => logdet_gradient(
                task: u32, params: *const f64, precisions: *const f64, gradient: *mut f64,
            );
            /// Π^U and ln|Π^U| of a valid tool on a valid task.
            toolconf_control_confidence => control_confidence(
                task: u32, params: *const f64, goals: *const f64, precisions: *const f64,
                pi_u: *mut f64, logdet: *mut f64,
            );
            /// A controller of a tool for a task (the on-robot controller), into `*controller`.
            toolconf_controller_create => controller_create(
                params: *const f64, task: u32, goals: *const f64, precisions: *const f64,
                learning_rate: f64, initial_torque: *const f64, rate_hz: f64,
                controller: *mut *mut $crate::bodies::Controller,
            );
            /// Frees a controller (NULL: nothing).
            toolconf_controller_destroy => controller_destroy(
                controller: *mut $crate::bodies::Controller,
            );
            /// One tick: the measured state in, the torque and ln|Π^U| out.
            toolconf_controller_tick => controller_tick(
                controller: *mut $crate::bodies::Controller, state: *const f64, torque: *mut f64,
                confidence: *mut f64,
            );
            /// One tick with the joint accelerations measured too.
            toolconf_controller_tick_with_acceleration => controller_tick_with_acceleration(
                controller: *mut $crate::bodies::Controller, state: *const f64,
                acceleration: *const f64, torque: *mut f64, confidence: *mut f64,
            );
            /// The controller's Π^U (N × N).
            toolconf_controller_pi_u => controller_pi_u(
                controller: *const $crate::bodies::Controller, pi_u: *mut f64,
            );
        }

        /// Every export as a table of function pointers (the library's own tests go through it).
        pub const EXPORTS: $crate::Exports = $crate::Exports {
            abi_version: toolconf_abi_version,
            tasks_fingerprint: toolconf_tasks_fingerprint,
            model_info: toolconf_model_info,
            last_error: toolconf_last_error,
            status_name: toolconf_status_name,
            check_tool: toolconf_check_tool,
            dynamics: toolconf_dynamics,
            dynamics_jacobian: toolconf_dynamics_jacobian,
            rigid_body_dynamics: toolconf_rigid_body_dynamics,
            tip: toolconf_tip,
            tip_bias: toolconf_tip_bias,
            state_matrix: toolconf_state_matrix,
            input_matrix: toolconf_input_matrix,
            task_defaults: toolconf_task_defaults,
            sensitivities: toolconf_sensitivities,
            pi_u: toolconf_pi_u,
            logdet_gradient: toolconf_logdet_gradient,
            control_confidence: toolconf_control_confidence,
            controller_create: toolconf_controller_create,
            controller_destroy: toolconf_controller_destroy,
            controller_tick: toolconf_controller_tick,
            controller_tick_with_acceleration: toolconf_controller_tick_with_acceleration,
            controller_pi_u: toolconf_controller_pi_u,
        };
    };
}
