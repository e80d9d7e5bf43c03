//! The files a user brings, each read under one bound ([`bounded_read`]) and checked row by row
//! and key by key before anything runs: task files ([`task_file`]), tools files
//! ([`tools_file`]) and design files ([`design_file`]: what a design may vary, between which
//! bounds, under which linear constraints, and what it optimises).

pub mod bounded_read;
pub mod design_file;
pub mod task_file;
pub mod tools_file;
