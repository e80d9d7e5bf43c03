//! The exports' bodies, generic over a model of toolconf-core ([`ArmModel`]). Each checks its
//! arguments in one order, the first failure giving the status:
//!
//! 1. every pointer it needs non-NULL ([`status::NULL_POINTER`]), before anything is read;
//! 2. a controller handle live in this library ([`status::BAD_HANDLE`], [`crate::handles`]);
//! 3. the task index one of the model's ([`status::UNKNOWN_TASK`]);
//! 4. every input number finite ([`status::NOT_FINITE`], the array and index named);
//! 5. the model's rules, as toolconf-core judges them (a tool, a task, an option);
//! 6. every result finite: else the tool's rule broken ([`status::INVALID_TOOL`]) or inputs
//!    too large for the model's arithmetic ([`status::NOT_FINITE`], the result named).
//!
//! Then it copies the result out: nothing is written on a failure. The whole call runs inside
//! [`guard`] (through `call`), so a panic becomes [`status::INTERNAL`] rather than unwinding into C.
//!
//! # Safety
//!
//! Every `unsafe fn` here takes raw pointers from C: each non-NULL pointer must point to as many
//! `double`s (or `int32_t`s) as the C ABI documents for it (docs/reference/c-abi.md), readable or
//! writable; nothing else can be checked. Reads and writes are unaligned-tolerant. A
//! controller handle is the exception: any value is checked ([`crate::handles`]).

// Each function's safety contract is the module's (above): one rule for every export.
#![allow(clippy::missing_safety_doc)]

mod controller;
mod functions;

use core::marker::PhantomData;
use std::panic::{catch_unwind, AssertUnwindSafe};

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ArmModel, Error, TaskKind, TaskN, ToolN, TERMS};

use crate::status::{self, fail, Failure};

/// A controller handle, as C sees it: opaque. Its value is a key of this library's registry
/// of live controllers ([`crate::handles`]), never read through.
#[repr(C)]
pub struct Controller {
    _opaque: [u8; 0],
}

/// The exports' bodies for model `M` (its sizes N, NX, NP, NZ): `Bodies::<M, ..>::dynamics` is
/// `toolconf_dynamics`, and so on ([`crate::export_model!`] names each).
pub struct Bodies<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    PhantomData<M>,
);

/// A pointer C passed, as the messages name it.
type Named<'a> = (*const (), &'a str);

/// `[(p.cast(), "p"), ...]`: the pointers an export needs, named by their C parameter's name,
/// inputs first, in the order they are checked.
macro_rules! named {
    ($($p:ident),+ $(,)?) => {
        [$(($p as *const (), stringify!($p))),+]
    };
}
pub(crate) use named;

/// An export's whole call: inside [`guard`], every pointer of `pointers` non-NULL (step 1),
/// then `body` (the steps after it).
fn call(function: &str, pointers: &[Named], body: impl FnOnce() -> Result<(), Failure>) -> i32 {
    guard(function, || {
        present(function, pointers)?;
        body()
    })
}

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

/// Step 1: every pointer of `pointers` non-NULL, else the first NULL one named.
fn present(function: &str, pointers: &[Named]) -> Result<(), Failure> {
    match pointers.iter().find(|(p, _)| p.is_null()) {
        Some((_, what)) => Err(null(function, what)),
        None => Ok(()),
    }
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
    for (t, block) in v.iter_mut().enumerate() {
        read_into(ptr, t * N, block.as_mut_slice(), function, what)?;
    }
    Ok(v)
}

unsafe fn write(ptr: *mut f64, values: &[f64]) {
    for (i, v) in values.iter().enumerate() {
        ptr.add(i).write_unaligned(*v);
    }
}

/// A result to copy out: where, its C name, its values.
type Output<'a> = (*mut f64, &'a str, &'a [f64]);

/// The steps every export of model `M` shares.
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Bodies<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// Step 6 and the copy: every value of `results` finite, else why not, and only then each
    /// written. A tool that breaks its model's rule is the cause when it does
    /// ([`status::INVALID_TOOL`], the rule named: the closed forms are unchecked, and a mass of
    /// 0 divides by it); otherwise the inputs are too large for the model's arithmetic
    /// ([`status::NOT_FINITE`]). The result is named either way.
    unsafe fn finish(
        function: &str,
        params: &SVector<f64, NP>,
        results: &[Output],
    ) -> Result<(), Failure> {
        for (_, what, values) in results {
            let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) else {
                continue;
            };
            return Err(match ToolN::<M, N, NX, NP, NZ>::new((*params).into()) {
                Err(e) => fail(
                    status::INVALID_TOOL,
                    format_args!("{function}: {what}[{i}] = {v} is not finite: {e}"),
                ),
                Ok(_) => fail(
                    status::NOT_FINITE,
                    format_args!(
                        "{function}: {what}[{i}] = {v} is not finite: the inputs are too large \
                         for model {}'s arithmetic",
                        M::name()
                    ),
                ),
            });
        }
        for (ptr, _, values) in results {
            write(*ptr, values);
        }
        Ok(())
    }

    /// Step 3: the task with index `index` (`TaskKind::ALL`), which the model must offer.
    fn task(index: u32, function: &str) -> Result<TaskKind, Failure> {
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

    /// Step 5 for a tool: the model's rule.
    fn checked_tool(
        p: &SVector<f64, NP>,
        function: &str,
    ) -> Result<ToolN<M, N, NX, NP, NZ>, Failure> {
        ToolN::<M, N, NX, NP, NZ>::new((*p).into()).map_err(|e| core_error(&e, function))
    }

    /// Steps 3 and 4 for a task and a tool from C arrays (their pointers checked already): the
    /// task, then the parameters, goals and precisions read and checked finite.
    unsafe fn task_inputs(
        task_index: u32,
        params: *const f64,
        goals: *const f64,
        precisions: *const f64,
        function: &str,
    ) -> Result<(SVector<f64, NP>, TaskN<N>), Failure> {
        let kind = Self::task(task_index, function)?;
        let p = vector::<NP>(params, function, "params")?;
        let goal = per_term_vectors::<N>(goals, function, "goals")?;
        let precision = per_term_matrices::<N>(precisions, function, "precisions")?;
        let task = TaskN {
            kind,
            goal,
            precision,
        };
        Ok((p, task))
    }
}

/// A core error's status: the one C sees for each kind of error toolconf-core gives.
pub fn status_of(e: &Error) -> i32 {
    match e {
        Error::InvalidParameter { .. }
        | Error::ParameterOutOfDomain { .. }
        | Error::ToolConstraint { .. } => status::INVALID_TOOL,
        Error::InvalidGoal { .. }
        | Error::InvalidPrecision { .. }
        | Error::ConfidenceRank { .. } => status::INVALID_TASK,
        Error::InvalidOption { .. } | Error::OptionOutOfRange { .. } => status::INVALID_OPTION,
        Error::NotPositiveDefinite { .. } | Error::IllConditioned { .. } => {
            status::NOT_POSITIVE_DEFINITE
        }
        Error::NoTip { .. } => status::NO_TIP,
    }
}

/// A core error as a failure, its message the error's own.
fn core_error(e: &Error, function: &str) -> Failure {
    fail(status_of(e), format_args!("{function}: {e}"))
}
