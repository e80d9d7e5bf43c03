//! [`Exports`]: every function of the C ABI as a pointer, with the C signature: what
//! [`crate::export_model!`] defines (its `EXPORTS`), and what a loader fills from the symbols of
//! a library it opened (`toolconf_<field>`).

use core::ffi::c_char;

use crate::bodies::Controller;
use crate::ModelInfo;

/// The exports of one model library, by their C names without the `toolconf_` prefix.
#[derive(Debug, Clone, Copy)]
pub struct Exports {
    pub abi_version: extern "C" fn() -> u32,
    pub tasks_fingerprint: extern "C" fn() -> *const c_char,
    pub model_info: extern "C" fn() -> *const ModelInfo,
    pub last_error: extern "C" fn() -> *const c_char,
    pub status_name: extern "C" fn(i32) -> *const c_char,
    pub check_tool: unsafe extern "C" fn(*const f64) -> i32,
    pub dynamics: unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64) -> i32,
    pub dynamics_jacobian:
        unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64, *mut f64) -> i32,
    pub rigid_body_dynamics:
        unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64) -> i32,
    pub tip: unsafe extern "C" fn(*const f64, *const f64, *mut f64, *mut f64) -> i32,
    pub tip_bias: unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64) -> i32,
    pub state_matrix: unsafe extern "C" fn(*const f64, *mut f64) -> i32,
    pub input_matrix: unsafe extern "C" fn(*const f64, *mut f64) -> i32,
    pub task_defaults: unsafe extern "C" fn(u32, *mut f64, *mut f64) -> i32,
    pub sensitivities: unsafe extern "C" fn(u32, *const f64, *mut f64, *mut i32) -> i32,
    pub pi_u: unsafe extern "C" fn(u32, *const f64, *const f64, *mut f64) -> i32,
    pub logdet_gradient: unsafe extern "C" fn(u32, *const f64, *const f64, *mut f64) -> i32,
    pub control_confidence:
        unsafe extern "C" fn(u32, *const f64, *const f64, *const f64, *mut f64, *mut f64) -> i32,
    #[allow(clippy::type_complexity)]
    pub controller_create: unsafe extern "C" fn(
        *const f64,
        u32,
        *const f64,
        *const f64,
        f64,
        *const f64,
        f64,
        *mut *mut Controller,
    ) -> i32,
    pub controller_destroy: unsafe extern "C" fn(*mut Controller) -> i32,
    pub controller_tick:
        unsafe extern "C" fn(*mut Controller, *const f64, *mut f64, *mut f64) -> i32,
    pub controller_tick_with_acceleration:
        unsafe extern "C" fn(*mut Controller, *const f64, *const f64, *mut f64, *mut f64) -> i32,
    pub controller_pi_u: unsafe extern "C" fn(*const Controller, *mut f64) -> i32,
}

/// Every export's C name, in the order of [`Exports`]' fields: what a loader looks up, and what
/// the header declares (a test compares the header with this list).
pub const SYMBOLS: [&str; 23] = [
    "toolconf_abi_version",
    "toolconf_tasks_fingerprint",
    "toolconf_model_info",
    "toolconf_last_error",
    "toolconf_status_name",
    "toolconf_check_tool",
    "toolconf_dynamics",
    "toolconf_dynamics_jacobian",
    "toolconf_rigid_body_dynamics",
    "toolconf_tip",
    "toolconf_tip_bias",
    "toolconf_state_matrix",
    "toolconf_input_matrix",
    "toolconf_task_defaults",
    "toolconf_sensitivities",
    "toolconf_pi_u",
    "toolconf_logdet_gradient",
    "toolconf_control_confidence",
    "toolconf_controller_create",
    "toolconf_controller_destroy",
    "toolconf_controller_tick",
    "toolconf_controller_tick_with_acceleration",
    "toolconf_controller_pi_u",
];
