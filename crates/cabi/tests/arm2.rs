//! The C ABI of the paper's arm, exported here as a model library exports it
//! (`export_model!`), checked through its function pointers: bit for bit against the direct
//! calls, and under hostile input. A library `make model` builds runs the same checks on its own
//! model (templates/cabi/tests/abi.rs.tera).

toolconf_cabi::export_model!(Arm2, arm2);

use toolconf_cabi::check;
use toolconf_cabi::toolconf_core::Arm2;

#[test]
fn every_export_gives_the_direct_calls_bits() {
    let compared = check::bit_identity::<Arm2, 2, 4, 4, 6>(&EXPORTS, 50, 1);
    assert!(compared > 10_000, "{compared}");
}

#[test]
fn hostile_input_is_a_status() {
    assert!(check::hostile::<Arm2, 2, 4, 4, 6>(&EXPORTS) > 50);
}

#[test]
fn the_exports_are_the_symbols_listed() {
    // The table names every symbol once, in the order of Exports' fields.
    let mut names = toolconf_cabi::exports::SYMBOLS.to_vec();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), toolconf_cabi::exports::SYMBOLS.len());
}
