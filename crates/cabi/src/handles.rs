//! The controllers a library has handed out, by handle: what makes a destroyed, foreign or
//! forged handle a status ([`status::BAD_HANDLE`]) rather than undefined behaviour.
//!
//! * **Nothing is read through a handle.** A handle is looked up in this library's registry of
//!   live controllers by its value (a binary search under a read lock) before any memory is
//!   touched; only a handle found there is turned back into its controller. So a pointer into
//!   another library's allocation, an integer made up by a caller, a misaligned or a freed
//!   pointer are all refused the same way, and none of them is dereferenced.
//! * **A handle is never reused.** Its value is not the controller's address (an allocator
//!   gives a freed block back to the next allocation of its size, so a stale handle would
//!   silently name the next controller) but a number drawn once: a bijective mix of the
//!   library's tag and a counter of the controllers it created, never 0. A destroyed handle
//!   stays refused for the life of the library.
//! * **Per library.** The tag mixes the address of this registry (each loaded library has its
//!   own) with the task list's names, so two libraries in one process draw from unrelated
//!   sequences: another library's handle is not in this registry (a collision of two 64-bit
//!   mixes, about one in 2⁶⁴ per pair of live handles, would name a live controller of this
//!   library: still no undefined behaviour). Within one binary exporting several models (a Rust
//!   program linking several model crates shares this registry), each entry also records its
//!   controller's type, and a handle of another model is refused.
//! * **Thread-safe.** Every call on a controller holds the registry's lock for its duration
//!   (a tick: about 0.1 µs), so calls on the library's controllers take turns, two threads
//!   ticking one controller included, and a destroy waits for the call in progress; a call
//!   after it finds no handle. One lock rather than a read lock and a lock per controller: a
//!   tick then takes two atomic operations instead of four (85 ns against 103 ns a tick of
//!   the paper's arm, crates/cabi/examples/tick_population.rs), and robots tick few
//!   controllers, from one thread each, a thousand times a second.
//! * **Fallible.** Creating a controller allocates twice at most (its box, and room in the
//!   registry), each checked: out of memory is [`status::OUT_OF_MEMORY`], never an abort.

use core::any::TypeId;
use std::alloc::{alloc, Layout};
use std::sync::{Mutex, PoisonError};

use toolconf_core::{TaskKind, Term};

use crate::bodies::Controller;
use crate::status::{self, fail, Failure};

/// A live controller: its handle's value, its type, and its box.
struct Entry {
    handle: usize,
    kind: TypeId,
    /// A `Box<C>` for the `C` of `kind`, as a raw pointer.
    slot: *mut (),
}

/// The live controllers, sorted by handle, and how many were ever created.
struct Registry {
    entries: Vec<Entry>,
    created: u64,
}

// SAFETY: the slots are owned by the registry and reached only under its lock; each is a
// `C: Send` (`create`'s bound).
unsafe impl Send for Registry {}
unsafe impl Sync for Registry {}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    entries: Vec::new(),
    created: 0,
});

/// SplitMix64's finaliser: a bijection of u64 that scatters consecutive inputs.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// This library's tag: its registry's address mixed with the task list's names (what the
/// fingerprint hashes), folded without allocating: the tag is drawn inside `create`, where an
/// allocation may fail.
fn library_tag() -> u64 {
    let names = Term::ALL.iter().map(|t| t.name());
    let names = names.chain(TaskKind::ALL.iter().map(|k| k.name()));
    names
        .flat_map(str::bytes)
        .fold(core::ptr::addr_of!(REGISTRY) as u64, |h, b| {
            mix(h ^ u64::from(b))
        })
}

/// The `index`-th handle this library hands out (distinct for distinct `index`, never 0).
fn handle_value(tag: u64, index: u64) -> usize {
    mix(tag.wrapping_add(index)) as usize
}

fn bad_handle(function: &str, why: &str) -> Failure {
    fail(
        status::BAD_HANDLE,
        format_args!("{function}: the handle is not a live controller of this library ({why})"),
    )
}

fn out_of_memory(function: &str, what: &str) -> Failure {
    fail(
        status::OUT_OF_MEMORY,
        format_args!("{function}: out of memory ({what})"),
    )
}

/// `value` in a new box, or `None` when the allocator has no room (where `Box::new` aborts).
fn try_box<T>(value: T) -> Option<Box<T>> {
    let layout = Layout::new::<T>();
    if layout.size() == 0 {
        return Some(Box::new(value));
    }
    // SAFETY: the layout is T's and not zero-sized; a non-null block is written before use,
    // and Box::from_raw takes a block of the global allocator with T's layout.
    unsafe {
        let p = alloc(layout).cast::<T>();
        if p.is_null() {
            return None;
        }
        p.write(value);
        Some(Box::from_raw(p))
    }
}

/// Registers `controller` and returns its new handle.
pub(crate) fn create<C: Send + 'static>(
    controller: C,
    function: &str,
) -> Result<*mut Controller, Failure> {
    // Allocated before the lock is taken: the calls on the controllers go on meanwhile.
    let slot = try_box(controller).ok_or_else(|| out_of_memory(function, "the controller"))?;
    let mut r = REGISTRY.lock().unwrap_or_else(PoisonError::into_inner);
    r.entries
        .try_reserve(1)
        .map_err(|_| out_of_memory(function, "the registry of handles"))?;
    let tag = library_tag();
    let handle = loop {
        let index = r.created;
        r.created = r.created.wrapping_add(1);
        let h = handle_value(tag, index);
        if h != 0 {
            break h;
        }
    };
    let at = r
        .entries
        .binary_search_by_key(&handle, |e| e.handle)
        .unwrap_or_else(|at| at);
    r.entries.insert(
        at,
        Entry {
            handle,
            kind: TypeId::of::<C>(),
            slot: Box::into_raw(slot).cast(),
        },
    );
    Ok(handle as *mut Controller)
}

/// Runs `f` on the controller behind `handle`, a live one of type `C`, holding the registry's
/// lock: no other call reaches any controller of this library meanwhile, so none frees it.
pub(crate) fn with<C: Send + 'static, R>(
    handle: *const Controller,
    function: &str,
    f: impl FnOnce(&mut C) -> Result<R, Failure>,
) -> Result<R, Failure> {
    if handle.is_null() {
        return Err(fail(
            status::NULL_POINTER,
            format_args!("{function}: controller is a null pointer"),
        ));
    }
    // A panic in an earlier call left its controller as that call found it: each call changes
    // it only at its end (ArmController::tick).
    let r = REGISTRY.lock().unwrap_or_else(PoisonError::into_inner);
    let entry = &r.entries[found::<C>(&r, handle as usize, function)?];
    // SAFETY: the entry is live (its box is freed only after its removal, under the lock held
    // here) and its type is `C` (checked by `found`); the lock makes this the only reference.
    let controller = unsafe { &mut *entry.slot.cast::<C>() };
    f(controller)
}

/// The index of `handle`'s entry, if it is a live controller of type `C`.
fn found<C: 'static>(r: &Registry, handle: usize, function: &str) -> Result<usize, Failure> {
    let i = r
        .entries
        .binary_search_by_key(&handle, |e| e.handle)
        .map_err(|_| bad_handle(function, "destroyed, another library's, or never one"))?;
    if r.entries[i].kind != TypeId::of::<C>() {
        return Err(bad_handle(function, "a controller of another model"));
    }
    Ok(i)
}

/// Destroys the controller behind `handle` (NULL: nothing), after the calls on it in progress.
pub(crate) fn destroy<C: Send + 'static>(
    handle: *mut Controller,
    function: &str,
) -> Result<(), Failure> {
    if handle.is_null() {
        return Ok(());
    }
    let mut r = REGISTRY.lock().unwrap_or_else(PoisonError::into_inner);
    let i = found::<C>(&r, handle as usize, function)?;
    let entry = r.entries.remove(i);
    drop(r);
    // SAFETY: the entry was live and of type `C`; removed from the registry, no call can reach
    // it any more, and none is in progress (calls hold the lock).
    drop(unsafe { Box::from_raw(entry.slot.cast::<C>()) });
    Ok(())
}

/// How many controllers of this library are live (for the tests' leak checks).
pub fn live() -> usize {
    REGISTRY
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .entries
        .len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_are_distinct_and_never_zero() {
        let tag = library_tag();
        let mut seen: Vec<usize> = (0..100_000).map(|i| handle_value(tag, i)).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 100_000);
        assert!(!seen.contains(&0));
    }
}
