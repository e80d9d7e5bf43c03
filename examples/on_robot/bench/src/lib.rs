//! Only the benchmark (benches/tick.rs).
