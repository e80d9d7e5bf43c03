//! The files a user brings, each read under one bound ([`bounded_read`]) and checked row by row
//! and key by key before anything runs: task files ([`task_file`]) and tools files
//! ([`tools_file`]). A design file, which names the design's objective and bounds, is read by the
//! design itself (`toolconf::design::file`).

pub mod bounded_read;
pub mod task_file;
pub mod tools_file;
