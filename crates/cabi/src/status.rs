//! The status codes every function of the C ABI returns, and the calling thread's message for
//! the last nonzero one (`toolconf_last_error()`), kept in a fixed buffer: a failing call never
//! allocates, so a real-time loop may fail a tick (a NaN from an encoder) without touching the
//! heap.

use core::cell::RefCell;
use core::ffi::{c_char, CStr};
use core::fmt;

/// Success: the outputs are written.
pub const OK: i32 = 0;
/// A pointer the function needs is NULL (nothing is written).
pub const NULL_POINTER: i32 = 1;
/// The task index is not one of the model's tasks (`task_count` of the metadata).
pub const UNKNOWN_TASK: i32 = 2;
/// An input is NaN or infinite, or a result would be (inputs too large for the model's
/// arithmetic): the message names the array and index.
pub const NOT_FINITE: i32 = 3;
/// The tool's parameters break the model's rule (a domain, a constraint, the inertia rule):
/// checked where documented, and the cause named wherever a result is not finite.
pub const INVALID_TOOL: i32 = 4;
/// A goal outside its range, a precision that is not symmetric positive semi-definite, or
/// precisions that leave Π^U singular for every tool.
pub const INVALID_TASK: i32 = 5;
/// A learning rate, control rate or initial torque out of range, a learning rate and control
/// rate with which the ticks would not settle (the message says which to change), or a
/// measurement that drives the torque out of range.
pub const INVALID_OPTION: i32 = 6;
/// Π^U is not positive definite for this tool, or too ill-conditioned for ln|Π^U|.
pub const NOT_POSITIVE_DEFINITE: i32 = 7;
/// A task on the tool's tip, for a model whose description gives no tip.
pub const NO_TIP: i32 = 8;
/// The controller handle is not a live controller of this library and model: destroyed,
/// another library's or model's, or never a handle (crate::handles).
pub const BAD_HANDLE: i32 = 9;
/// An internal error (a panic, caught at the boundary): a bug, to be reported.
pub const INTERNAL: i32 = 10;
/// The allocator had no room for a new controller: nothing was created.
pub const OUT_OF_MEMORY: i32 = 11;

/// Every status by code: its C name.
pub const NAMES: [&CStr; 12] = [
    c"TOOLCONF_OK",
    c"TOOLCONF_NULL_POINTER",
    c"TOOLCONF_UNKNOWN_TASK",
    c"TOOLCONF_NOT_FINITE",
    c"TOOLCONF_INVALID_TOOL",
    c"TOOLCONF_INVALID_TASK",
    c"TOOLCONF_INVALID_OPTION",
    c"TOOLCONF_NOT_POSITIVE_DEFINITE",
    c"TOOLCONF_NO_TIP",
    c"TOOLCONF_BAD_HANDLE",
    c"TOOLCONF_INTERNAL",
    c"TOOLCONF_OUT_OF_MEMORY",
];

/// A status code's C name, `"TOOLCONF_UNKNOWN_STATUS"` for any other number.
pub fn name(code: i32) -> &'static CStr {
    usize::try_from(code)
        .ok()
        .and_then(|i| NAMES.get(i).copied())
        .unwrap_or(c"TOOLCONF_UNKNOWN_STATUS")
}

/// A failed call: its status; the message is already in the thread's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Failure(pub i32);

/// The message buffer's size, its terminating NUL included: a longer message is cut (at a
/// character boundary).
pub const MESSAGE_CAPACITY: usize = 512;

thread_local! {
    static LAST_ERROR: RefCell<[u8; MESSAGE_CAPACITY]> = const { RefCell::new([0; MESSAGE_CAPACITY]) };
}

/// Writes into a fixed buffer, cutting what does not fit.
struct Cut<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl fmt::Write for Cut<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let room = self.buf.len() - self.len;
        let mut take = s.len().min(room);
        while !s.is_char_boundary(take) {
            take -= 1;
        }
        // A NUL inside a message would end the C string early: shown as a space.
        for (dst, src) in self.buf[self.len..self.len + take]
            .iter_mut()
            .zip(s.bytes())
        {
            *dst = if src == 0 { b' ' } else { src };
        }
        self.len += take;
        Ok(())
    }
}

/// Sets the calling thread's message and returns the failure with `status`.
pub fn fail(status: i32, message: fmt::Arguments<'_>) -> Failure {
    // A thread being torn down has no buffer: the status alone then.
    let _ = LAST_ERROR.try_with(|cell| {
        if let Ok(mut buf) = cell.try_borrow_mut() {
            let mut w = Cut {
                buf: &mut buf[..MESSAGE_CAPACITY - 1],
                len: 0,
            };
            let _ = fmt::write(&mut w, message);
            let end = w.len;
            buf[end] = 0;
        }
    });
    Failure(status)
}

/// The calling thread's message (empty before any failure), valid until its next failing call.
pub fn last_error_ptr() -> *const c_char {
    LAST_ERROR
        .try_with(|cell| cell.as_ptr() as *const c_char)
        .unwrap_or(c"".as_ptr())
}

/// The calling thread's message, as Rust text.
pub fn last_error() -> String {
    // SAFETY: the buffer always holds a NUL (its last byte is never written otherwise).
    unsafe { CStr::from_ptr(last_error_ptr()) }
        .to_string_lossy()
        .into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_message_is_cut_at_a_character_and_ends_in_nul() {
        let long = "é".repeat(400);
        assert_eq!(fail(INVALID_TASK, format_args!("{long}")), Failure(5));
        let m = last_error();
        assert!(
            m.len() < MESSAGE_CAPACITY && m.chars().all(|c| c == 'é'),
            "{m}"
        );
        fail(NOT_FINITE, format_args!("a{}b", '\0'));
        assert_eq!(last_error(), "a b");
    }

    #[test]
    fn every_status_has_its_name() {
        assert_eq!(name(OK), c"TOOLCONF_OK");
        assert_eq!(name(INTERNAL), c"TOOLCONF_INTERNAL");
        assert_eq!(name(-1), c"TOOLCONF_UNKNOWN_STATUS");
        assert_eq!(name(OUT_OF_MEMORY), c"TOOLCONF_OUT_OF_MEMORY");
        assert_eq!(name(12), c"TOOLCONF_UNKNOWN_STATUS");
    }
}
