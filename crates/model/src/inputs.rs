//! The files a user brings, each read under one bound ([`bounded_read`]) and checked row by row
//! and key by key before anything runs: task files ([`task_file`]), tools files
//! ([`tools_file`]) and design files ([`design_file`]: what a design may vary, between which
//! bounds, under which linear constraints, and what it optimises).

pub mod bounded_read;
pub mod design_file;
pub mod task_file;
pub mod tools_file;

/// How a bad input file is named in a message: `file: message`, or `file, place: message` where a
/// key or a line is meant ([`task_file::TaskFileError`], [`design_file::DesignFileError`]).
fn write_located(
    f: &mut std::fmt::Formatter<'_>,
    file: &str,
    place: &str,
    message: &str,
) -> std::fmt::Result {
    if place.is_empty() {
        write!(f, "{file}: {message}")
    } else {
        write!(f, "{file}, {place}: {message}")
    }
}
