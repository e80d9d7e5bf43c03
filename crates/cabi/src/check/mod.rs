//! The checks a model library's own test runs on its exports (templates/cabi/tests/abi.rs.tera;
//! this crate's tests run them on built-in models, tests/loaded_models.rs on the libraries
//! `make model` builds):
//!
//! * [`bit_identity`] calls every export through its function pointer ([`Exports`]) on random
//!   inputs and compares each number with the direct Rust call's by `f64::to_bits`;
//! * [`fuzz`] calls every export with generated arguments (NULL pointers, misaligned arrays,
//!   NaN, infinities, huge, tiny and subnormal numbers, unknown tasks, live, destroyed,
//!   foreign and forged controller handles) and checks each status against the C ABI's rules
//!   (the order of [`crate::imp`]'s checks), the outputs untouched on a failure and finite on
//!   success, and controllers ticked from several threads at once;
//! * [`hostile`] runs the table of named cases ([`cases`]: every class of bad input once, the
//!   regressions among them) and the fuzzer's default count.
//!
//! They panic with the export, the case and what differs.

use core::ffi::{c_char, CStr};

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ArmModel, TERMS};

mod bits;
pub mod cases;
pub mod fuzz;
pub mod table;

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
