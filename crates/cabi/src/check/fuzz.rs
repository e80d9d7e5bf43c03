//! [`fuzz`]: every export called with generated arguments, each status checked against the C
//! ABI's rules rather than against a list of expected cases. The rules, in order (crate::bodies):
//!
//! 1. a NULL pointer the function needs: `TOOLCONF_NULL_POINTER`, the first in argument order
//!    named (`toolconf_controller_destroy(NULL)` is OK: nothing to do);
//! 2. a handle that is not a live controller of this library and model:
//!    `TOOLCONF_BAD_HANDLE`;
//! 3. a task index the model does not offer: `TOOLCONF_UNKNOWN_TASK`;
//! 4. a NaN or infinite input: `TOOLCONF_NOT_FINITE`, the first in argument order named;
//! 5. what toolconf-core's direct call refuses: its status (`bodies::status_of`);
//! 6. a result that is not finite: `TOOLCONF_INVALID_TOOL` if the tool breaks its rule, else
//!    `TOOLCONF_NOT_FINITE`;
//!
//! else OK, with every output finite and, but for ln|Π^U| (the library's is the libm crate's),
//! the direct call's bits. On a failure no output is touched; on any call nothing is written
//! past an output's end. A controller created through the ABI is mirrored by one created
//! directly, ticked alike, so that a tick's status and torque are checked too.

use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ArmController, ArmModel, TaskKind, TaskN, ToolN, TERMS};

use super::{c_str, random_precisions, random_state, random_tool, Rng};
use crate::bodies::Controller;
use crate::{status, Exports};

/// A bit pattern no export writes (a NaN with a payload): an untouched output holds it.
const SENTINEL: u64 = 0x7ff8_dead_beef_0001;
/// Doubles after each array that no export may write, even on success.
const GUARD: usize = 4;

/// The number of fuzzed calls: `TOOLCONF_FUZZ_CASES` (as the parsers' fuzzers take it), or
/// `default`.
pub fn fuzz_cases(default: usize) -> usize {
    std::env::var("TOOLCONF_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Controllers of another library (or another model): handles the fuzzed library must refuse.
pub struct Foreign<'a> {
    /// A new live controller of the other library or model.
    pub create: &'a dyn Fn() -> *mut Controller,
    /// Destroys one of them, returning its status.
    pub destroy: &'a dyn Fn(*mut Controller) -> i32,
}

/// An array passed to an export: NULL, or `len` doubles at an 8-byte-aligned address or one
/// byte past one, then [`GUARD`] sentinels.
struct Array {
    bytes: Vec<u8>,
    offset: usize,
    len: usize,
    null: bool,
}

impl Array {
    fn new(values: &[f64], len: usize, misaligned: bool, null: bool) -> Self {
        let mut bytes = vec![0u8; (len + GUARD) * 8 + 16];
        let offset = (8 - bytes.as_ptr() as usize % 8) % 8 + usize::from(misaligned);
        for i in 0..len + GUARD {
            let v = values.get(i).map_or(SENTINEL, |v| v.to_bits());
            bytes[offset + 8 * i..offset + 8 * i + 8].copy_from_slice(&v.to_ne_bytes());
        }
        Self {
            bytes,
            offset,
            len,
            null,
        }
    }

    fn ptr(&self) -> *const f64 {
        match self.null {
            true => core::ptr::null(),
            false => self.bytes[self.offset..].as_ptr().cast(),
        }
    }

    fn ptr_mut(&mut self) -> *mut f64 {
        match self.null {
            true => core::ptr::null_mut(),
            false => self.bytes[self.offset..].as_mut_ptr().cast(),
        }
    }

    fn bits(&self, i: usize) -> u64 {
        let at = self.offset + 8 * i;
        u64::from_ne_bytes(self.bytes[at..at + 8].try_into().unwrap_or([0; 8]))
    }

    fn values(&self) -> Vec<f64> {
        (0..self.len)
            .map(|i| f64::from_bits(self.bits(i)))
            .collect()
    }

    fn guard_intact(&self) -> bool {
        (self.len..self.len + GUARD).all(|i| self.bits(i) == SENTINEL)
    }

    fn untouched(&self) -> bool {
        (0..self.len).all(|i| self.bits(i) == SENTINEL)
    }

    /// (NULL?, name): what rule 1 reads.
    fn arg<'n>(&self, name: &'n str) -> (bool, &'n str) {
        (self.null, name)
    }

    /// (name, values): what rule 4 reads.
    fn input<'n>(&self, name: &'n str) -> (&'n str, Vec<f64>, bool) {
        (name, self.values(), false)
    }
}

/// What a call must give: its outputs (None: finite, bits not compared), or a status and a
/// fragment of its message.
type Want = Result<Vec<Option<Vec<f64>>>, (i32, String)>;

/// Rules 1, 3 and 4: the first NULL pointer, an unknown task, the first non-finite input
/// (`scalar`: a number passed by value, named without an index).
fn rules(
    pointers: &[(bool, &str)],
    task: Option<(u32, &[TaskKind])>,
    inputs: &[(&str, Vec<f64>, bool)],
) -> Option<(i32, String)> {
    if let Some((_, name)) = pointers.iter().find(|(null, _)| *null) {
        return Some((status::NULL_POINTER, format!("{name} is a null pointer")));
    }
    if let Some((index, offered)) = task {
        if !TaskKind::ALL
            .get(index as usize)
            .is_some_and(|k| offered.contains(k))
        {
            return Some((status::UNKNOWN_TASK, format!("task {index} is not")));
        }
    }
    for (name, values, scalar) in inputs {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            let at = if *scalar {
                String::new()
            } else {
                format!("[{i}]")
            };
            return Some((status::NOT_FINITE, format!("{name}{at} = ")));
        }
    }
    None
}

/// Rule 6 for `outputs`: all finite (their bits compared), else the cause.
fn results<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    p: &SVector<f64, NP>,
    outputs: Vec<Vec<f64>>,
) -> Want
where
    M: ArmModel<N, NX, NP, NZ>,
{
    if outputs.iter().flatten().all(|v| v.is_finite()) {
        return Ok(outputs.into_iter().map(Some).collect());
    }
    match ToolN::<M, N, NX, NP, NZ>::new((*p).into()) {
        Err(_) => Err((status::INVALID_TOOL, "is not finite: invalid".into())),
        Ok(_) => Err((
            status::NOT_FINITE,
            "is not finite: the inputs are too large".into(),
        )),
    }
}

/// A number that breaks something: NaN, ±∞, huge, tiny, subnormal, zero of either sign.
fn special(rng: &mut Rng) -> f64 {
    rng.pick(&[
        f64::NAN,
        -f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e300,
        -1e300,
        f64::MAX,
        f64::MIN,
        1e-300,
        5e-324,
        -5e-324,
        f64::MIN_POSITIVE / 2.0,
        0.0,
        -0.0,
        1e6,
        -1e6,
        1e12,
    ])
}

/// A handle argument and what rule 2 says of it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Handle {
    Null,
    /// The index of a live controller of this library.
    Live(usize),
    Destroyed,
    Foreign,
    Forged,
}

/// The fuzzer's state: the library, the generator, the live controllers (each with its direct
/// twin), the destroyed and foreign handles, and what was seen.
struct Fuzz<'a, M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    e: &'a Exports,
    rng: Rng,
    offered: &'static [TaskKind],
    live: Vec<(*mut Controller, ArmController<M, N, NX, NP, NZ>)>,
    destroyed: Vec<*mut Controller>,
    foreign: Vec<*mut Controller>,
    calls: usize,
    seen: [usize; status::NAMES.len()],
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    Fuzz<'_, M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    /// An input array: usually `typical`, at times with one or all entries broken or scaled
    /// by a power of ten, misaligned, or NULL.
    fn array(&mut self, typical: &[f64]) -> Array {
        let mut values = typical.to_vec();
        match self.rng.below(10) {
            0..=4 => {}
            5..=7 if !values.is_empty() => {
                let i = self.rng.below(values.len());
                values[i] = special(&mut self.rng);
            }
            8 => {
                let scale = 10f64.powi(self.rng.below(601) as i32 - 300);
                values.iter_mut().for_each(|v| *v *= scale);
            }
            _ => values.iter_mut().for_each(|v| *v = special(&mut self.rng)),
        }
        let misaligned = self.rng.one_in(4);
        Array::new(&values, typical.len(), misaligned, self.rng.one_in(25))
    }

    /// An output array of `len` doubles (NULL at times, misaligned at times).
    fn out(&mut self, len: usize) -> Array {
        let misaligned = self.rng.one_in(4);
        Array::new(&[], len, misaligned, self.rng.one_in(25))
    }

    /// A task index: mostly one of the task list's, at times past it.
    fn task(&mut self) -> u32 {
        let count = TaskKind::ALL.len() as u32;
        match self.rng.below(8) {
            0 => {
                let any = self.rng.next_u64() as u32;
                self.rng.pick(&[count, count + 1, u32::MAX, any])
            }
            _ => self.rng.below(count as usize) as u32,
        }
    }

    /// A number passed by value: usually `typical`, at times a special one.
    fn scalar(&mut self, typical: f64) -> f64 {
        match self.rng.below(4) {
            0 => special(&mut self.rng),
            1 => -typical,
            _ => typical,
        }
    }

    fn tool(&mut self) -> Vec<f64> {
        random_tool::<M, N, NX, NP, NZ>(&mut self.rng)
            .as_slice()
            .to_vec()
    }

    fn state(&mut self) -> Vec<f64> {
        random_state(&mut self.rng, &M::equilibrium_state())
            .as_slice()
            .to_vec()
    }

    fn small(&mut self, len: usize) -> Vec<f64> {
        (0..len).map(|_| self.rng.uniform(-5.0, 5.0)).collect()
    }

    /// A task's goals and precisions: its defaults, or random precisions.
    fn goals_and_precisions(&mut self, task: u32) -> (Vec<f64>, Vec<f64>) {
        let kind = TaskKind::ALL.get(task as usize).copied();
        let t = kind.map_or(
            TaskN::<N> {
                kind: TaskKind::ALL[0],
                goal: [SVector::zeros(); TERMS],
                precision: [SMatrix::zeros(); TERMS],
            },
            M::paper_task,
        );
        let precision = match self.rng.one_in(4) {
            true => random_precisions::<N>(&mut self.rng),
            false => t.precision,
        };
        let flat = |blocks: &[_]| super::flat::<N, N>(blocks);
        let goals = t.goal.iter().flat_map(|g| g.as_slice().to_vec()).collect();
        (goals, flat(&precision))
    }

    /// Checks one call's status, message and outputs against `want`.
    fn check(&mut self, function: &str, code: i32, want: Want, outputs: &[&Array]) {
        self.calls += 1;
        if let Some(n) = usize::try_from(code)
            .ok()
            .and_then(|c| self.seen.get_mut(c))
        {
            *n += 1;
        }
        let message = c_str((self.e.last_error)());
        let fail = |what: String| -> ! {
            panic!(
                "{function}: {what}; status {code} ({}), message: {message}",
                c_str((self.e.status_name)(code))
            )
        };
        for (k, o) in outputs.iter().enumerate() {
            if !o.null && !o.guard_intact() {
                fail(format!("output {k} was written past its end"));
            }
        }
        match want {
            Err((want, fragment)) => {
                if code != want {
                    fail(format!(
                        "expected status {want} ({}) for '{fragment}'",
                        c_str((self.e.status_name)(want))
                    ));
                }
                if !message.starts_with(function) || !message.contains(&fragment) {
                    fail(format!(
                        "the message does not name the function and '{fragment}'"
                    ));
                }
                if let Some(k) = outputs.iter().position(|o| !o.null && !o.untouched()) {
                    fail(format!("output {k} was written by a failing call"));
                }
            }
            Ok(values) => {
                if code != status::OK {
                    fail("expected TOOLCONF_OK".into());
                }
                for (k, (o, want)) in outputs.iter().zip(values).enumerate() {
                    let got = o.values();
                    if got.iter().any(|v| !v.is_finite()) {
                        fail(format!("output {k} holds a non-finite number: {got:?}"));
                    }
                    if want.is_some_and(|w| {
                        w.iter().zip(&got).any(|(a, b)| a.to_bits() != b.to_bits())
                    }) {
                        fail(format!("output {k} differs from the direct call's"));
                    }
                }
            }
        }
    }
}

mod calls;
mod controllers;

/// Calls every export of `e` (model `M`) `cases` times in all with arguments generated from
/// `seed`, handles among them live, destroyed, forged and `foreign` ones, and checks every
/// status against the rules above. Returns how many calls were made, and how many gave each
/// status (indexed by code).
pub fn fuzz<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
    foreign: &Foreign<'_>,
    cases: usize,
    seed: u64,
) -> (usize, [usize; status::NAMES.len()])
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let mut f = Fuzz::<M, N, NX, NP, NZ> {
        e,
        rng: Rng::new(seed),
        offered: crate::info::generated(M::name()).map_or(&[][..], |g| g.tasks),
        live: Vec::new(),
        destroyed: Vec::new(),
        foreign: (0..2).map(|_| (foreign.create)()).collect(),
        calls: 0,
        seen: [0; status::NAMES.len()],
    };
    let dead = (foreign.create)();
    assert_eq!(
        (foreign.destroy)(dead),
        status::OK,
        "the foreign library's destroy"
    );
    f.foreign.push(dead);
    for _ in 0..cases {
        let which = f.rng.below(24);
        f.call(which);
    }
    f.finish();
    for h in f.foreign.drain(..2) {
        assert_eq!(
            (foreign.destroy)(h),
            status::OK,
            "the foreign library's destroy"
        );
    }
    (f.calls, f.seen)
}

/// Ticks, reads and destroys `slots` controllers from `threads` threads at once, each thread
/// also recreating them: every status is OK or `TOOLCONF_BAD_HANDLE` (a handle another thread
/// destroyed meanwhile), a handle one thread destroyed is refused by a second destroy, and
/// `create` is the only other way in. Returns how many calls were made.
pub fn fuzz_threads(
    e: &Exports,
    create: &(dyn Fn() -> *mut Controller + Sync),
    state: &[f64],
    dof: usize,
    threads: usize,
    calls_per_thread: usize,
) -> usize {
    let slots: Vec<AtomicUsize> = (0..4)
        .map(|_| AtomicUsize::new(create() as usize))
        .collect();
    let calls = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for t in 0..threads {
            let (slots, calls) = (&slots, &calls);
            s.spawn(move || {
                let mut rng = Rng::new(t as u64 + 1);
                for _ in 0..calls_per_thread {
                    let slot = &slots[rng.below(slots.len())];
                    let n = controllers::contend(e, create, slot, state, dof, &mut rng);
                    calls.fetch_add(n, Ordering::Relaxed);
                }
            });
        }
    });
    for slot in &slots {
        let h = slot.swap(0, Ordering::AcqRel) as *mut Controller;
        if !h.is_null() {
            // SAFETY: a handle value of this library's, any value is checked.
            assert_eq!(unsafe { (e.controller_destroy)(h) }, status::OK);
        }
    }
    calls.into_inner()
}
