//! The fingerprint of the task and term list a generated crate was made from
//! (`derive/tasks.toml`): a task or term index means the same in a model library and in the
//! program that loads it only if their fingerprints agree.
//!
//! The canonical text ([`text`]) has one line per term, in `Term::ALL` order, with where it is
//! read, then one line per task, in `TaskKind::ALL` order, with the terms it uses:
//!
//! ```text
//! toolconf-tasks 1
//! term theta state 0
//! term theta_dot state 1
//! term theta_ddot state_rate 1
//! term u control 0
//! task position theta theta_dot theta_ddot u
//! ```
//!
//! and the fingerprint is its SHA-256 in lowercase hex ([`hex`]). The renderer computes the
//! same text from a model's IR (derive/render/src/cabi.rs) for the header's
//! `TOOLCONF_TASKS_FINGERPRINT`; the library's own test checks the two agree.

use std::ffi::CString;
use std::fmt::Write;
use std::sync::OnceLock;

use sha2::{Digest, Sha256};
use toolconf_core::{Read, TaskKind, Term};

/// The canonical text of the task and term list of the generated crate this is built with.
pub fn text() -> String {
    let mut out = String::from("toolconf-tasks 1\n");
    for term in Term::ALL {
        let (source, block) = match term.read() {
            Read::State { block } => ("state", block),
            Read::StateRate { block } => ("state_rate", block),
            Read::Control => ("control", 0),
            Read::Tip { order } => ("tip", order),
        };
        let _ = writeln!(out, "term {} {source} {block}", term.name());
    }
    for kind in TaskKind::ALL {
        let _ = write!(out, "task {}", kind.name());
        for term in kind.terms() {
            let _ = write!(out, " {}", term.name());
        }
        out.push('\n');
    }
    out
}

/// SHA-256 of `text`, in lowercase hex.
pub fn of(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .fold(String::with_capacity(64), |mut s, b| {
            let _ = write!(s, "{b:02x}");
            s
        })
}

/// The fingerprint of the generated crate this is built with: SHA-256 of [`text`].
pub fn hex() -> &'static str {
    static HEX: OnceLock<String> = OnceLock::new();
    HEX.get_or_init(|| of(&text()))
}

/// [`hex`] as a C string, built once.
pub fn c_hex() -> &'static CString {
    static C: OnceLock<CString> = OnceLock::new();
    C.get_or_init(|| CString::new(hex()).unwrap_or_default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_text_lists_every_term_then_every_task() {
        let t = text();
        assert!(
            t.starts_with("toolconf-tasks 1\nterm theta state 0\n"),
            "{t}"
        );
        assert!(
            t.contains("\ntask position theta theta_dot theta_ddot u\n"),
            "{t}"
        );
        assert_eq!(t.lines().count(), 1 + Term::ALL.len() + TaskKind::ALL.len());
        assert_eq!(hex().len(), 64);
        assert_eq!(
            of("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
