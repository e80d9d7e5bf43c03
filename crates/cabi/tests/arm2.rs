//! The C ABI of the paper's arm, exported here as a model library exports it
//! (`export_model!`), checked through its function pointers: bit for bit against the direct
//! calls, and under hostile input: the table of cases, the fuzzer (another model's
//! controllers its foreign handles), and controllers used from several threads at once. A
//! library `make model` builds runs the same checks on its own model
//! (templates/cabi/tests/abi.rs.tera); tests/loaded_models.rs fuzzes the libraries with each
//! other's handles.

toolconf_cabi::export_model!(Arm2, arm2);

use nalgebra::SVector;
use toolconf_cabi::bodies::{Bodies, Controller};
use toolconf_cabi::check::{self, Foreign};
use toolconf_cabi::status;
use toolconf_cabi::toolconf_core::{Arm2, Arm3, ArmModel};

#[test]
fn every_export_gives_the_direct_calls_bits() {
    let compared = check::bit_identity::<Arm2, 2, 4, 4, 6>(&EXPORTS, 50, 1);
    assert!(compared > 10_000, "{compared}");
}

#[test]
fn hostile_input_is_a_status() {
    let calls = check::hostile::<Arm2, 2, 4, 4, 6>(&EXPORTS);
    eprintln!("{calls} hostile calls");
    assert!(calls > 3000, "{calls}");
}

/// The fuzzer with a real other model's controllers (the 3-link arm's, made in this binary:
/// the same registry, another type) as the foreign handles; every rule's status is reached.
#[test]
fn the_fuzzer_reaches_every_rule_with_another_models_handles() {
    let create = || check::cases::controller_of::<Arm3, 3, 6, 6, 9>();
    // SAFETY: any handle value is checked.
    let destroy = |h: *mut Controller| unsafe { Bodies::<Arm3, 3, 6, 6, 9>::controller_destroy(h) };
    let foreign = Foreign {
        create: &create,
        destroy: &destroy,
    };
    let (calls, seen) =
        check::fuzz::<Arm2, 2, 4, 4, 6>(&EXPORTS, &foreign, check::fuzz_cases(4000), 7);
    for (code, n) in seen.iter().enumerate() {
        eprintln!("{:<32} {n}", status::NAMES[code].to_str().unwrap());
    }
    let reached = [
        status::OK,
        status::NULL_POINTER,
        status::UNKNOWN_TASK,
        status::NOT_FINITE,
        status::INVALID_TOOL,
        status::INVALID_TASK,
        status::INVALID_OPTION,
        status::BAD_HANDLE,
    ];
    if calls >= 4000 {
        for code in reached {
            assert!(
                seen[code as usize] > 0,
                "never {:?}",
                status::NAMES[code as usize]
            );
        }
    }
}

/// A tool of zeros makes the paper's arm's dynamics NaN (its mass matrix is zero), and
/// velocities of 1e300 overflow it: each is a status naming its cause, never OK with NaN.
#[test]
fn a_result_that_would_not_be_finite_is_a_status() {
    let x = Arm2::equilibrium_state();
    let direct = Arm2::dynamics(&x, &SVector::zeros(), &SVector::zeros());
    assert!(direct.iter().any(|v| !v.is_finite()), "{direct}");
    let mut out = [7.0; 4];
    // SAFETY (both calls): the arrays hold the model's sizes.
    let code = unsafe {
        toolconf_dynamics(
            x.as_ptr(),
            [0.0; 2].as_ptr(),
            [0.0; 4].as_ptr(),
            out.as_mut_ptr(),
        )
    };
    assert_eq!(code, status::INVALID_TOOL);
    assert!(check::cases::last_error(&EXPORTS).contains("invalid arm parameter"));
    let fast = [x[0], x[1], 1e300, 1e300];
    let p = [0.3, 0.4, 0.5, 0.2];
    let code = unsafe {
        toolconf_dynamics(
            fast.as_ptr(),
            [0.0; 2].as_ptr(),
            p.as_ptr(),
            out.as_mut_ptr(),
        )
    };
    assert_eq!(code, status::NOT_FINITE);
    assert!(check::cases::last_error(&EXPORTS).contains("too large"));
    assert_eq!(out, [7.0; 4]);
}

#[test]
fn the_exports_are_the_symbols_listed() {
    // The table names every symbol once, in the order of Exports' fields.
    let mut names = toolconf_cabi::exports::SYMBOLS.to_vec();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), toolconf_cabi::exports::SYMBOLS.len());
}
