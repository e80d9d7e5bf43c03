//! Empty: it makes cargo build this crate's build-dependencies (Cargo.toml).
fn main() {}
