//! No code: see Cargo.toml (the features shared by the Python extension and the tests).
#![no_std]
