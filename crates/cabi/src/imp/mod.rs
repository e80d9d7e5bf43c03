//! The exports' bodies, generic over a model of toolconf-core ([`ArmModel`]): each reads its
//! arrays (refusing a NULL and a non-finite value), calls the function the Rust code calls, and
//! copies the result out; the whole call runs inside [`guard`], so a panic becomes
//! [`status::INTERNAL`] rather than unwinding into C.
//!
//! # Safety
//!
//! Every `unsafe fn` here takes raw pointers from C: each non-NULL pointer must point to as many
//! `double`s (or `int32_t`s) as the C ABI documents for it (docs/c-abi.md), readable or
//! writable; nothing else can be checked. Reads and writes are unaligned-tolerant.

// Each function's safety contract is the module's (above): one rule for every export.
#![allow(clippy::missing_safety_doc)]

use std::panic::{catch_unwind, AssertUnwindSafe};

use nalgebra::{SMatrix, SVector};
use toolconf_core::{
    control_confidence as core_confidence, ArmController, ArmModel, Error, TaskKind, TaskN, Term,
    ToolN, TERMS,
};

use crate::status::{self, fail, Failure};

/// A controller handle, as C sees it: opaque.
#[repr(C)]
pub struct Controller {
    _opaque: [u8; 0],
}

/// What a handle points to: a tag, then the controller. The tag tells a live controller of
/// this library from a NULL-free pointer to something else, or to a destroyed one (best
/// effort: such a pointer must still be readable for 8 bytes).
#[repr(C)]
struct Handle<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    tag: u64,
    controller: ArmController<M, N, NX, NP, NZ>,
}

/// "toolconf" in ASCII, then the ABI version: the tag of a live handle.
const LIVE: u64 = 0x746f_6f6c_636f_6e66 ^ crate::ABI_VERSION as u64;

/// Runs `f`, turning its failure into its status and a panic into [`status::INTERNAL`].
pub fn guard(function: &str, f: impl FnOnce() -> Result<(), Failure>) -> i32 {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => status::OK,
        Ok(Err(Failure(code))) => code,
        Err(_) => {
            fail(
                status::INTERNAL,
                format_args!("{function}: internal error (a panic, caught at the C boundary)"),
            );
            status::INTERNAL
        }
    }
}

fn null(function: &str, what: &str) -> Failure {
    fail(
        status::NULL_POINTER,
        format_args!("{function}: {what} is a null pointer"),
    )
}

/// `out.len()` doubles from `ptr`, each finite; a bad one is named by its index in the whole
/// array, `offset` + its place here.
unsafe fn read_into(
    ptr: *const f64,
    offset: usize,
    out: &mut [f64],
    function: &str,
    what: &str,
) -> Result<(), Failure> {
    if ptr.is_null() {
        return Err(null(function, what));
    }
    for (i, slot) in out.iter_mut().enumerate() {
        let v = ptr.add(offset + i).read_unaligned();
        if !v.is_finite() {
            return Err(fail(
                status::NOT_FINITE,
                format_args!("{function}: {what}[{}] = {v} is not finite", offset + i),
            ));
        }
        *slot = v;
    }
    Ok(())
}

/// A K-vector from `ptr`.
pub unsafe fn vector<const K: usize>(
    ptr: *const f64,
    function: &str,
    what: &str,
) -> Result<SVector<f64, K>, Failure> {
    let mut v = SVector::<f64, K>::zeros();
    read_into(ptr, 0, v.as_mut_slice(), function, what)?;
    Ok(v)
}

/// A finite scalar.
fn scalar(v: f64, function: &str, what: &str) -> Result<f64, Failure> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(fail(
            status::NOT_FINITE,
            format_args!("{function}: {what} = {v} is not finite"),
        ))
    }
}

/// TERMS blocks of N × N (column-major) from `ptr`: a task's precisions.
unsafe fn per_term_matrices<const N: usize>(
    ptr: *const f64,
    function: &str,
    what: &str,
) -> Result<[SMatrix<f64, N, N>; TERMS], Failure> {
    let mut m = [SMatrix::<f64, N, N>::zeros(); TERMS];
    if ptr.is_null() {
        return Err(null(function, what));
    }
    for (t, block) in m.iter_mut().enumerate() {
        read_into(ptr, t * N * N, block.as_mut_slice(), function, what)?;
    }
    Ok(m)
}

/// TERMS blocks of N from `ptr`: a task's goals.
unsafe fn per_term_vectors<const N: usize>(
    ptr: *const f64,
    function: &str,
    what: &str,
) -> Result<[SVector<f64, N>; TERMS], Failure> {
    let mut v = [SVector::<f64, N>::zeros(); TERMS];
    if ptr.is_null() {
        return Err(null(function, what));
    }
    for (t, block) in v.iter_mut().enumerate() {
        read_into(ptr, t * N, block.as_mut_slice(), function, what)?;
    }
    Ok(v)
}

fn out<T>(ptr: *mut T, function: &str, what: &str) -> Result<*mut T, Failure> {
    if ptr.is_null() {
        Err(null(function, what))
    } else {
        Ok(ptr)
    }
}

unsafe fn write(ptr: *mut f64, values: &[f64]) {
    for (i, v) in values.iter().enumerate() {
        ptr.add(i).write_unaligned(*v);
    }
}

/// The task with index `index` (`TaskKind::ALL`), which the model must offer.
pub fn task<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    index: u32,
    function: &str,
) -> Result<TaskKind, Failure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let offered = crate::info::generated(M::name()).map_or(&[][..], |g| g.tasks);
    match TaskKind::ALL.get(index as usize) {
        Some(kind) if offered.contains(kind) => Ok(*kind),
        _ => Err(fail(
            status::UNKNOWN_TASK,
            format_args!(
                "{function}: task {index} is not one of model {}'s {} tasks (0 to {})",
                M::name(),
                TaskKind::ALL.len(),
                TaskKind::ALL.len().saturating_sub(1)
            ),
        )),
    }
}

/// A core error's status, its message the error's own.
fn core_error(e: &Error, function: &str) -> Failure {
    let code = match e {
        Error::InvalidParameter { .. }
        | Error::ParameterOutOfDomain { .. }
        | Error::ToolConstraint { .. } => status::INVALID_TOOL,
        Error::InvalidGoal { .. }
        | Error::InvalidPrecision { .. }
        | Error::ConfidenceRank { .. } => status::INVALID_TASK,
        Error::InvalidOption { .. } => status::INVALID_OPTION,
        Error::NotPositiveDefinite { .. } | Error::IllConditioned { .. } => {
            status::NOT_POSITIVE_DEFINITE
        }
        Error::NoTip { .. } => status::NO_TIP,
    };
    fail(code, format_args!("{function}: {e}"))
}

/// `toolconf_check_tool`.
pub unsafe fn check_tool<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: *const f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_check_tool";
    guard(F, || {
        let p = vector::<NP>(params, F, "params")?;
        ToolN::<M, N, NX, NP, NZ>::new(p.into())
            .map(drop)
            .map_err(|e| core_error(&e, F))
    })
}

/// `toolconf_dynamics`.
pub unsafe fn dynamics<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    x_dot: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_dynamics";
    guard(F, || {
        let x = vector::<NX>(x, F, "x")?;
        let u = vector::<N>(u, F, "u")?;
        let p = vector::<NP>(params, F, "params")?;
        let dst = out(x_dot, F, "x_dot")?;
        write(dst, M::dynamics(&x, &u, &p).as_slice());
        Ok(())
    })
}

/// `toolconf_dynamics_jacobian`.
pub unsafe fn dynamics_jacobian<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    f_x: *mut f64,
    f_u: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_dynamics_jacobian";
    guard(F, || {
        let x = vector::<NX>(x, F, "x")?;
        let u = vector::<N>(u, F, "u")?;
        let p = vector::<NP>(params, F, "params")?;
        let (a_dst, b_dst) = (out(f_x, F, "f_x")?, out(f_u, F, "f_u")?);
        let (a, b) = M::dynamics_jacobian(&x, &u, &p);
        write(a_dst, a.as_slice());
        write(b_dst, b.as_slice());
        Ok(())
    })
}

/// `toolconf_rigid_body_dynamics`.
pub unsafe fn rigid_body_dynamics<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    x_dot: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_rigid_body_dynamics";
    guard(F, || {
        let x = vector::<NX>(x, F, "x")?;
        let u = vector::<N>(u, F, "u")?;
        let p = vector::<NP>(params, F, "params")?;
        let dst = out(x_dot, F, "x_dot")?;
        write(dst, M::rigid_body_dynamics(&x, &u, &p).as_slice());
        Ok(())
    })
}

/// `toolconf_tip`.
pub unsafe fn tip<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    q: *const f64,
    params: *const f64,
    position: *mut f64,
    jacobian: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_tip";
    guard(F, || {
        let q = vector::<N>(q, F, "q")?;
        let p = vector::<NP>(params, F, "params")?;
        let (y_dst, j_dst) = (out(position, F, "position")?, out(jacobian, F, "jacobian")?);
        match M::tip(&q, &p) {
            Some((y, j)) => {
                write(y_dst, y.as_slice());
                write(j_dst, j.as_slice());
                Ok(())
            }
            None => Err(fail(
                status::NO_TIP,
                format_args!(
                    "{F}: model {} has no tip (its description gives no [tip])",
                    M::name()
                ),
            )),
        }
    })
}

/// `toolconf_tip_bias`: J̇(q, q̇) q̇, the tip's acceleration at q̈ = 0 (ÿ = J q̈ + J̇ q̇).
pub unsafe fn tip_bias<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    q: *const f64,
    q_dot: *const f64,
    params: *const f64,
    bias: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_tip_bias";
    guard(F, || {
        let q = vector::<N>(q, F, "q")?;
        let q_dot = vector::<N>(q_dot, F, "q_dot")?;
        let p = vector::<NP>(params, F, "params")?;
        let dst = out(bias, F, "bias")?;
        match M::tip_bias(&q, &q_dot, &p) {
            Some(b) => {
                write(dst, b.as_slice());
                Ok(())
            }
            None => Err(fail(
                status::NO_TIP,
                format_args!(
                    "{F}: model {} has no tip (its description gives no [tip])",
                    M::name()
                ),
            )),
        }
    })
}

/// `toolconf_state_matrix`.
pub unsafe fn state_matrix<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: *const f64,
    a: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_state_matrix";
    guard(F, || {
        let p = vector::<NP>(params, F, "params")?;
        let dst = out(a, F, "a")?;
        write(dst, M::state_matrix(&p).as_slice());
        Ok(())
    })
}

/// `toolconf_input_matrix`.
pub unsafe fn input_matrix<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: *const f64,
    b: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_input_matrix";
    guard(F, || {
        let p = vector::<NP>(params, F, "params")?;
        let dst = out(b, F, "b")?;
        write(dst, M::input_matrix(&p).as_slice());
        Ok(())
    })
}

/// `toolconf_task_defaults`: [`ArmModel::paper_task`]'s goals and (padded) precisions.
pub unsafe fn task_defaults<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    goals: *mut f64,
    precisions: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_task_defaults";
    guard(F, || {
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let (g_dst, p_dst) = (out(goals, F, "goals")?, out(precisions, F, "precisions")?);
        let t = M::paper_task(kind);
        for term in Term::ALL {
            let i = term.index();
            write(g_dst.add(i * N), t.goal[i].as_slice());
            write(p_dst.add(i * N * N), t.precision[i].as_slice());
        }
        Ok(())
    })
}

/// `toolconf_sensitivities`: TERMS blocks of N × N, zero for a term the task does not use (and
/// `used[t]` = 0 there, 1 elsewhere, when `used` is not NULL).
pub unsafe fn sensitivities<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    params: *const f64,
    sensitivities: *mut f64,
    used: *mut i32,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_sensitivities";
    guard(F, || {
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let p = vector::<NP>(params, F, "params")?;
        let dst = out(sensitivities, F, "sensitivities")?;
        let s = M::sensitivities(kind, &p);
        for term in Term::ALL {
            let i = term.index();
            let block = s.d_du[i].unwrap_or_else(SMatrix::zeros);
            write(dst.add(i * N * N), block.as_slice());
            if !used.is_null() {
                used.add(i).write_unaligned(i32::from(s.d_du[i].is_some()));
            }
        }
        Ok(())
    })
}

/// The task `kind` with `precision` and zero goals: what Π^U and its gradient read.
fn precision_task<const N: usize>(
    kind: TaskKind,
    precision: [SMatrix<f64, N, N>; TERMS],
) -> TaskN<N> {
    TaskN {
        kind,
        goal: [SVector::zeros(); TERMS],
        precision,
    }
}

/// `toolconf_pi_u`: the generated closed form Π^U, as [`ArmModel::pi_u`] (no checks of the task).
pub unsafe fn pi_u<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    params: *const f64,
    precisions: *const f64,
    pi_u: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_pi_u";
    guard(F, || {
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let p = vector::<NP>(params, F, "params")?;
        let precision = per_term_matrices::<N>(precisions, F, "precisions")?;
        let dst = out(pi_u, F, "pi_u")?;
        write(
            dst,
            M::pi_u(&precision_task(kind, precision), &p).as_slice(),
        );
        Ok(())
    })
}

/// `toolconf_logdet_gradient`: ∂ln|Π^U|/∂p, as [`ArmModel::logdet_gradient`].
pub unsafe fn logdet_gradient<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    task_index: u32,
    params: *const f64,
    precisions: *const f64,
    gradient: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_logdet_gradient";
    guard(F, || {
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let p = vector::<NP>(params, F, "params")?;
        let precision = per_term_matrices::<N>(precisions, F, "precisions")?;
        let dst = out(gradient, F, "gradient")?;
        let g = M::logdet_gradient(&precision_task(kind, precision), &p);
        write(dst, g.as_slice());
        Ok(())
    })
}

/// A validated tool and task from C arrays.
unsafe fn tool_and_task<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    params: *const f64,
    goals: *const f64,
    precisions: *const f64,
    function: &str,
) -> Result<(ToolN<M, N, NX, NP, NZ>, TaskN<N>), Failure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let kind = task::<M, N, NX, NP, NZ>(task_index, function)?;
    let p = vector::<NP>(params, function, "params")?;
    let goal = per_term_vectors::<N>(goals, function, "goals")?;
    let precision = per_term_matrices::<N>(precisions, function, "precisions")?;
    let tool = ToolN::<M, N, NX, NP, NZ>::new(p.into()).map_err(|e| core_error(&e, function))?;
    Ok((
        tool,
        TaskN {
            kind,
            goal,
            precision,
        },
    ))
}

/// `toolconf_control_confidence`: toolconf-core's `control_confidence` (tool and task checked).
pub unsafe fn control_confidence<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    task_index: u32,
    params: *const f64,
    goals: *const f64,
    precisions: *const f64,
    pi_u: *mut f64,
    logdet: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_control_confidence";
    guard(F, || {
        let (tool, task) =
            tool_and_task::<M, N, NX, NP, NZ>(task_index, params, goals, precisions, F)?;
        let (pi_dst, ld_dst) = (out(pi_u, F, "pi_u")?, out(logdet, F, "logdet")?);
        let c = core_confidence(&tool, &task).map_err(|e| core_error(&e, F))?;
        write(pi_dst, c.pi_u.as_slice());
        ld_dst.write_unaligned(c.logdet);
        Ok(())
    })
}

/// `toolconf_controller_create`: [`ArmController::new`] in a new handle.
#[allow(clippy::too_many_arguments)]
pub unsafe fn controller_create<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    params: *const f64,
    task_index: u32,
    goals: *const f64,
    precisions: *const f64,
    learning_rate: f64,
    initial_torque: *const f64,
    rate_hz: f64,
    controller: *mut *mut Controller,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_controller_create";
    guard(F, || {
        let dst = out(controller, F, "controller")?;
        let (tool, task) =
            tool_and_task::<M, N, NX, NP, NZ>(task_index, params, goals, precisions, F)?;
        let learning_rate = scalar(learning_rate, F, "learning_rate")?;
        let u0 = vector::<N>(initial_torque, F, "initial_torque")?;
        let rate_hz = scalar(rate_hz, F, "rate_hz")?;
        let c =
            ArmController::<M, N, NX, NP, NZ>::new(&tool, &task, learning_rate, u0.into(), rate_hz)
                .map_err(|e| core_error(&e, F))?;
        let handle = Box::new(Handle {
            tag: LIVE,
            controller: c,
        });
        dst.write_unaligned(Box::into_raw(handle).cast::<Controller>());
        Ok(())
    })
}

/// The controller behind a handle, if it is a live one of model `M`.
unsafe fn handle<'a, M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    controller: *const Controller,
    function: &str,
) -> Result<&'a mut Handle<M, N, NX, NP, NZ>, Failure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    if controller.is_null() {
        return Err(null(function, "controller"));
    }
    let h = controller as *mut Handle<M, N, NX, NP, NZ>;
    let aligned = h.align_offset(core::mem::align_of::<Handle<M, N, NX, NP, NZ>>()) == 0;
    if !aligned || (h as *const u64).read() != LIVE {
        return Err(fail(
            status::BAD_HANDLE,
            format_args!("{function}: the handle is not a live controller of this library"),
        ));
    }
    Ok(&mut *h)
}

/// `toolconf_controller_destroy`: NULL is nothing to do.
pub unsafe fn controller_destroy<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *mut Controller,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_controller_destroy";
    if controller.is_null() {
        return status::OK;
    }
    guard(F, || {
        let h = handle::<M, N, NX, NP, NZ>(controller, F)?;
        h.tag = 0;
        drop(Box::from_raw(h as *mut Handle<M, N, NX, NP, NZ>));
        Ok(())
    })
}

/// `toolconf_controller_tick` (`acceleration` NULL) and
/// `toolconf_controller_tick_with_acceleration`: [`ArmController::tick`] or
/// [`ArmController::tick_with_acceleration`]. A failed tick leaves the controller's torque as
/// it was.
pub unsafe fn controller_tick<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *mut Controller,
    state: *const f64,
    acceleration: *const f64,
    torque: *mut f64,
    confidence: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_controller_tick";
    guard(F, || {
        let h = handle::<M, N, NX, NP, NZ>(controller, F)?;
        let x = vector::<NX>(state, F, "state")?;
        let a = if acceleration.is_null() {
            None
        } else {
            Some(vector::<N>(acceleration, F, "acceleration")?)
        };
        let (u_dst, c_dst) = (out(torque, F, "torque")?, out(confidence, F, "confidence")?);
        let command = match a {
            None => h.controller.tick(&x.into()),
            Some(a) => h.controller.tick_with_acceleration(&x.into(), &a.into()),
        }
        .map_err(|e| core_error(&e, F))?;
        write(u_dst, &command.torque);
        c_dst.write_unaligned(command.confidence);
        Ok(())
    })
}

/// `toolconf_controller_tick_with_acceleration` with a NULL `acceleration`.
pub fn null_acceleration() -> i32 {
    null("toolconf_controller_tick_with_acceleration", "acceleration").0
}

/// `toolconf_controller_pi_u`: the controller's Π^U.
pub unsafe fn controller_pi_u<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *const Controller,
    pi_u: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_controller_pi_u";
    guard(F, || {
        let h = handle::<M, N, NX, NP, NZ>(controller, F)?;
        let dst = out(pi_u, F, "pi_u")?;
        write(dst, h.controller.control_confidence().pi_u.as_slice());
        Ok(())
    })
}

/// A handle's memory, for a test of what a foreign pointer gives.
#[doc(hidden)]
pub fn foreign_handle() -> *mut Controller {
    static mut ZEROS: [u64; 4] = [0; 4];
    // Only the address is taken.
    core::ptr::addr_of_mut!(ZEROS).cast::<Controller>()
}
