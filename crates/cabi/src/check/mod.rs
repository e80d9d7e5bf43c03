//! The checks a model library's own test runs on its exports (templates/cabi/tests/abi.rs.tera;
//! this crate's tests run them on built-in models, tests/loaded_models.rs on the libraries
//! `make model` builds):
//!
//! * [`bit_identity`] calls every export through its function pointer ([`Exports`]) on random
//!   inputs and compares each number with the direct Rust call's by `f64::to_bits`;
//! * [`fuzz`] calls every export with generated arguments (NULL pointers, misaligned arrays,
//!   NaN, infinities, huge, tiny and subnormal numbers, unknown tasks, live, destroyed,
//!   foreign and forged controller handles) and checks each status against the C ABI's rules
//!   (the order of [`crate::bodies`]'s checks), the outputs untouched on a failure and finite on
//!   success, and controllers ticked from several threads at once;
//! * [`hostile`] runs the table of named cases ([`cases`]: every class of bad input once, the
//!   regressions among them) and the fuzzer's default count.
//!
//! They panic with the export, the case and what differs.

use core::ffi::{c_char, CStr};

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ArmModel, TaskKind, TERMS};

use crate::bodies::Controller;
use crate::Exports;

pub mod bad_inputs;
mod bits;
pub mod cases;
pub mod fuzz;

pub use bits::bit_identity;
pub use cases::hostile;
pub use fuzz::{fuzz, fuzz_cases, fuzz_threads, Foreign};

/// SplitMix64: a small, documented generator, so that a failing case can be replayed from its
/// seed.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    /// True with probability 1/n.
    pub fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }

    /// One of `items` (not empty).
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())]
    }
}

/// A C string of a library as text ("(null)" for NULL).
pub(crate) fn c_str(p: *const c_char) -> String {
    if p.is_null() {
        return "(null)".into();
    }
    // SAFETY: the library's strings are NUL-terminated and live while it is loaded.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

/// A random tool from the model's sampling box.
pub(crate) fn random_tool<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    rng: &mut Rng,
) -> SVector<f64, NP>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    SVector::from_fn(|i, _| {
        let (lo, hi) = M::tool_rule().sample[i];
        rng.uniform(lo, hi)
    })
}

/// A random state about the equilibrium (q within ±1 rad, q̇ within ±2 rad/s).
pub(crate) fn random_state<const NX: usize>(
    rng: &mut Rng,
    around: &SVector<f64, NX>,
) -> SVector<f64, NX> {
    SVector::from_fn(|i, _| {
        let spread = if i < NX / 2 { 1.0 } else { 2.0 };
        around[i] + rng.uniform(-spread, spread)
    })
}

/// Random symmetric positive definite precisions, one N × N per term.
pub(crate) fn random_precisions<const N: usize>(rng: &mut Rng) -> [SMatrix<f64, N, N>; TERMS] {
    core::array::from_fn(|_| {
        let a = SMatrix::<f64, N, N>::from_fn(|_, _| rng.uniform(-1.0, 1.0));
        let d =
            SMatrix::<f64, N, N>::from_diagonal(&SVector::from_fn(|_, _| rng.uniform(0.5, 100.0)));
        a * a.transpose() + d
    })
}

pub(crate) fn flat<const R: usize, const C: usize>(blocks: &[SMatrix<f64, R, C>]) -> Vec<f64> {
    blocks.iter().flat_map(|m| m.as_slice().to_vec()).collect()
}

/// Model `M`'s task `kind` with its defaults, as the C ABI takes a task: its index, its goals
/// and its precisions, flat.
pub fn flat_paper_task<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    kind: TaskKind,
) -> (u32, Vec<f64>, Vec<f64>)
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let index = TaskKind::ALL.iter().position(|k| *k == kind);
    let task = M::paper_task(kind);
    let index = index.expect("a task of TaskKind::ALL") as u32;
    (index, flat(&task.goal), flat(&task.precision))
}

/// Creates a controller with `create` (`toolconf_controller_create` of a library, or a body of
/// its signature, unsafe: [`crate::bodies`]): tool `p` on `task` (as [`flat_paper_task`]
/// gives it) at learning rate 1, initial torque 0.1 on every joint and `rate_hz`. Returns the
/// status and the handle.
pub fn try_create_controller<F>(
    create: F,
    p: &[f64],
    (index, goals, precisions): &(u32, Vec<f64>, Vec<f64>),
    rate_hz: f64,
) -> (i32, *mut Controller)
where
    F: FnOnce(Create) -> i32,
{
    let torque = vec![0.1; goals.len() / TERMS];
    let mut h = core::ptr::null_mut();
    let code = create(Create {
        params: p.as_ptr(),
        task: *index,
        goals: goals.as_ptr(),
        precisions: precisions.as_ptr(),
        learning_rate: 1.0,
        initial_torque: torque.as_ptr(),
        rate_hz,
        controller: &mut h,
    });
    (code, h)
}

/// The arguments of `toolconf_controller_create`, each pointer to as many values as the model
/// needs.
pub struct Create {
    pub params: *const f64,
    pub task: u32,
    pub goals: *const f64,
    pub precisions: *const f64,
    pub learning_rate: f64,
    pub initial_torque: *const f64,
    pub rate_hz: f64,
    pub controller: *mut *mut Controller,
}

impl Create {
    /// Library `e`'s `toolconf_controller_create` on these arguments.
    ///
    /// # Safety
    ///
    /// Each pointer points to as many values as `e`'s model needs.
    pub unsafe fn through(self, e: &Exports) -> i32 {
        (e.controller_create)(
            self.params,
            self.task,
            self.goals,
            self.precisions,
            self.learning_rate,
            self.initial_torque,
            self.rate_hz,
            self.controller,
        )
    }
}

/// [`try_create_controller`] through library `e`, which must accept.
pub fn create_controller(
    e: &Exports,
    p: &[f64],
    task: &(u32, Vec<f64>, Vec<f64>),
    rate_hz: f64,
) -> *mut Controller {
    // SAFETY: the arrays hold the model's sizes, if `task` is the model's.
    let (code, h) = try_create_controller(|c| unsafe { c.through(e) }, p, task, rate_hz);
    assert_eq!(code, crate::status::OK, "{}", c_str((e.last_error)()));
    h
}
