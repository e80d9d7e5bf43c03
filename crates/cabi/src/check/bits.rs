//! [`bit_identity`]: every export through its pointer against the direct Rust call, bit for
//! bit.

use core::ffi::c_char;

use nalgebra::{SMatrix, SVector};
use toolconf_core::{
    control_confidence, ArmController, ArmModel, TaskKind, TaskN, Term, ToolN, TERMS,
};

use super::{flat, random_precisions, random_state, random_tool, Rng};
use crate::imp::{status_of, Controller};
use crate::{status, Exports};

fn same(what: &str, case: usize, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}, case {case}: length");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            g.to_bits() == w.to_bits(),
            "{what}, case {case}, entry {i}: the C ABI gives {g:e} ({:#018x}), the direct call {w:e} ({:#018x})",
            g.to_bits(),
            w.to_bits()
        );
    }
}

/// [`same`], and how many numbers it compared.
fn counted(what: &str, case: usize, got: &[f64], want: &[f64]) -> usize {
    same(what, case, got, want);
    got.len()
}

fn ok(what: &str, e: &Exports, code: i32) {
    assert!(
        code == status::OK,
        "{what}: status {code} ({}): {}",
        c_str(e, (e.status_name)(code)),
        c_str(e, (e.last_error)())
    );
}

fn c_str(_: &Exports, p: *const c_char) -> String {
    super::c_str(p)
}

/// Every export through `e` against the direct Rust call, on `cases` random inputs from
/// `seed`: bit for bit. Returns how many numbers were compared.
pub fn bit_identity<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
    cases: usize,
    seed: u64,
) -> usize
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let (mut compared, mut ticks) = (0, 0);
    assert_eq!((e.abi_version)(), crate::ABI_VERSION);
    assert_eq!(c_str(e, (e.tasks_fingerprint)()), crate::fingerprint::hex());
    check_info::<M, N, NX, NP, NZ>(e);
    let mut rng = Rng::new(seed);
    let x_e = M::equilibrium_state();
    for case in 0..cases {
        let p = random_tool::<M, N, NX, NP, NZ>(&mut rng);
        let x = random_state(&mut rng, &x_e);
        let u = SVector::<f64, N>::from_fn(|_, _| rng.uniform(-5.0, 5.0));
        let mut x_dot = [0.0; NX];
        // SAFETY (every call below): each pointer points to the documented number of values.
        ok("dynamics", e, unsafe {
            (e.dynamics)(x.as_ptr(), u.as_ptr(), p.as_ptr(), x_dot.as_mut_ptr())
        });
        compared += counted("dynamics", case, &x_dot, M::dynamics(&x, &u, &p).as_slice());
        let (mut f_x, mut f_u) = (vec![0.0; NX * NX], vec![0.0; NX * N]);
        ok("dynamics_jacobian", e, unsafe {
            (e.dynamics_jacobian)(
                x.as_ptr(),
                u.as_ptr(),
                p.as_ptr(),
                f_x.as_mut_ptr(),
                f_u.as_mut_ptr(),
            )
        });
        let (a, b) = M::dynamics_jacobian(&x, &u, &p);
        compared += counted("dynamics_jacobian (f_x)", case, &f_x, a.as_slice());
        compared += counted("dynamics_jacobian (f_u)", case, &f_u, b.as_slice());
        ok("rigid_body_dynamics", e, unsafe {
            (e.rigid_body_dynamics)(x.as_ptr(), u.as_ptr(), p.as_ptr(), x_dot.as_mut_ptr())
        });
        compared += counted(
            "rigid_body_dynamics",
            case,
            &x_dot,
            M::rigid_body_dynamics(&x, &u, &p).as_slice(),
        );
        let q = x.fixed_rows::<N>(0).into_owned();
        let (mut y, mut j) = ([0.0; 3], vec![0.0; 3 * N]);
        let code = unsafe { (e.tip)(q.as_ptr(), p.as_ptr(), y.as_mut_ptr(), j.as_mut_ptr()) };
        match M::tip(&q, &p) {
            Some((y0, j0)) => {
                ok("tip", e, code);
                compared += counted("tip (position)", case, &y, y0.as_slice());
                compared += counted("tip (jacobian)", case, &j, j0.as_slice());
            }
            None => assert_eq!(code, status::NO_TIP, "tip of a model without one"),
        }
        let q_dot = x.fixed_rows::<N>(N).into_owned();
        let mut bias = [0.0; 3];
        let code =
            unsafe { (e.tip_bias)(q.as_ptr(), q_dot.as_ptr(), p.as_ptr(), bias.as_mut_ptr()) };
        match M::tip_bias(&q, &q_dot, &p) {
            Some(b) => {
                ok("tip_bias", e, code);
                compared += counted("tip_bias", case, &bias, b.as_slice());
            }
            None => assert_eq!(code, status::NO_TIP, "tip_bias of a model without a tip"),
        }
        let mut a_e = vec![0.0; NX * NX];
        ok("state_matrix", e, unsafe {
            (e.state_matrix)(p.as_ptr(), a_e.as_mut_ptr())
        });
        compared += counted("state_matrix", case, &a_e, M::state_matrix(&p).as_slice());
        let mut b_e = vec![0.0; NX * N];
        ok("input_matrix", e, unsafe {
            (e.input_matrix)(p.as_ptr(), b_e.as_mut_ptr())
        });
        compared += counted("input_matrix", case, &b_e, M::input_matrix(&p).as_slice());
        let precision = random_precisions::<N>(&mut rng);
        let pf = flat(&precision);
        for (index, kind) in TaskKind::ALL.into_iter().enumerate() {
            let t = index as u32;
            let name = kind.name();
            let (mut goals, mut precisions) = (vec![0.0; TERMS * N], vec![0.0; TERMS * N * N]);
            ok("task_defaults", e, unsafe {
                (e.task_defaults)(t, goals.as_mut_ptr(), precisions.as_mut_ptr())
            });
            let paper = M::paper_task(kind);
            compared += counted(
                &format!("task_defaults {name} (goals)"),
                case,
                &goals,
                &flat(&paper.goal),
            );
            compared += counted(
                &format!("task_defaults {name} (precisions)"),
                case,
                &precisions,
                &flat(&paper.precision),
            );
            let (mut s, mut used) = (vec![f64::NAN; TERMS * N * N], [7_i32; TERMS]);
            ok("sensitivities", e, unsafe {
                (e.sensitivities)(t, p.as_ptr(), s.as_mut_ptr(), used.as_mut_ptr())
            });
            let direct = M::sensitivities(kind, &p);
            for term in Term::ALL {
                let i = term.index();
                let want = direct.d_du[i].unwrap_or_else(SMatrix::zeros);
                compared += counted(
                    &format!("sensitivities {name} {}", term.name()),
                    case,
                    &s[i * N * N..(i + 1) * N * N],
                    want.as_slice(),
                );
                assert_eq!(
                    used[i],
                    i32::from(direct.d_du[i].is_some()),
                    "sensitivities {name}: used[{i}]"
                );
            }
            let task = TaskN {
                kind,
                goal: [SVector::zeros(); TERMS],
                precision,
            };
            let mut pi = vec![0.0; N * N];
            ok("pi_u", e, unsafe {
                (e.pi_u)(t, p.as_ptr(), pf.as_ptr(), pi.as_mut_ptr())
            });
            compared += counted(
                &format!("pi_u {name}"),
                case,
                &pi,
                M::pi_u(&task, &p).as_slice(),
            );
            let mut grad = vec![0.0; NP];
            ok("logdet_gradient", e, unsafe {
                (e.logdet_gradient)(t, p.as_ptr(), pf.as_ptr(), grad.as_mut_ptr())
            });
            compared += counted(
                &format!("logdet_gradient {name}"),
                case,
                &grad,
                M::logdet_gradient(&task, &p).as_slice(),
            );
            // The validated paths on the model's own task: the same status, and the same bits.
            let tool = ToolN::<M, N, NX, NP, NZ>::new(p.into());
            let (mut pi_c, mut logdet) = (vec![0.0; N * N], 0.0);
            let code = unsafe {
                (e.control_confidence)(
                    t,
                    p.as_ptr(),
                    goals.as_ptr(),
                    precisions.as_ptr(),
                    pi_c.as_mut_ptr(),
                    &mut logdet,
                )
            };
            match tool
                .as_ref()
                .map_err(status_of)
                .and_then(|tool| control_confidence(tool, &paper).map_err(|e| status_of(&e)))
            {
                Ok(c) => {
                    ok("control_confidence", e, code);
                    compared += counted(
                        &format!("control_confidence {name} (pi_u)"),
                        case,
                        &pi_c,
                        c.pi_u.as_slice(),
                    );
                    compared += counted(
                        &format!("control_confidence {name} (logdet)"),
                        case,
                        &[logdet],
                        &[c.logdet],
                    );
                }
                Err(want) => assert_eq!(
                    code,
                    want,
                    "control_confidence {name}: {}",
                    c_str(e, (e.last_error)())
                ),
            }
            ticks += controller::<M, N, NX, NP, NZ>(
                e,
                &mut rng,
                case,
                &p,
                t,
                &goals,
                &precisions,
                &paper,
            );
        }
    }
    // The ticks must have been compared at all: some tool and task must make a controller.
    assert!(
        ticks > 0,
        "no controller of {cases} random tools on any task could be made"
    );
    compared + ticks
}

/// A controller through the C ABI against [`ArmController`] directly: the same creation
/// status, then a few ticks on random measurements, bit for bit.
#[allow(clippy::too_many_arguments)]
fn controller<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
    rng: &mut Rng,
    case: usize,
    p: &SVector<f64, NP>,
    t: u32,
    goals: &[f64],
    precisions: &[f64],
    task: &TaskN<N>,
) -> usize
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let name = task.kind.name();
    let u0 = [0.1; N];
    let mut handle: *mut Controller = core::ptr::null_mut();
    let code = unsafe {
        (e.controller_create)(
            p.as_ptr(),
            t,
            goals.as_ptr(),
            precisions.as_ptr(),
            1.0,
            u0.as_ptr(),
            1000.0,
            &mut handle,
        )
    };
    let direct = ToolN::<M, N, NX, NP, NZ>::new((*p).into())
        .and_then(|tool| ArmController::<M, N, NX, NP, NZ>::new(&tool, task, 1.0, u0, 1000.0));
    let mut direct = match direct {
        Ok(c) => {
            ok("controller_create", e, code);
            c
        }
        Err(err) => {
            assert_eq!(
                code,
                status_of(&err),
                "controller_create {name}: {}",
                c_str(e, (e.last_error)())
            );
            assert!(handle.is_null());
            return 0;
        }
    };
    let mut compared = 0;
    let mut pi = vec![0.0; N * N];
    ok("controller_pi_u", e, unsafe {
        (e.controller_pi_u)(handle, pi.as_mut_ptr())
    });
    same(
        &format!("controller_pi_u {name}"),
        case,
        &pi,
        direct.control_confidence().pi_u.as_slice(),
    );
    let x_e = M::equilibrium_state();
    for tick in 0..4 {
        let x = random_state(rng, &x_e) * 0.1 + x_e * 0.9;
        let state: [f64; NX] = x.into();
        let (mut torque, mut confidence) = ([0.0; N], 0.0);
        let what = format!("controller_tick {name} #{tick}");
        let (code, want) = if tick % 2 == 0 {
            let c = unsafe {
                (e.controller_tick)(handle, state.as_ptr(), torque.as_mut_ptr(), &mut confidence)
            };
            (c, direct.tick(&state))
        } else {
            let acc = [rng.uniform(-1.0, 1.0); N];
            let c = unsafe {
                (e.controller_tick_with_acceleration)(
                    handle,
                    state.as_ptr(),
                    acc.as_ptr(),
                    torque.as_mut_ptr(),
                    &mut confidence,
                )
            };
            (c, direct.tick_with_acceleration(&state, &acc))
        };
        match want {
            Ok(command) => {
                ok(&what, e, code);
                same(&what, case, &torque, &command.torque);
                same(&what, case, &[confidence], &[command.confidence]);
                compared += N + 1;
            }
            Err(err) => assert_eq!(code, status_of(&err), "{what}"),
        }
    }
    ok("controller_destroy", e, unsafe {
        (e.controller_destroy)(handle)
    });
    compared
}

/// The metadata equals the generated `ModelInfo`, entry for entry.
fn check_info<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(e: &Exports)
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let g = crate::info::generated(M::name()).expect("the model's generated ModelInfo");
    let i = (e.model_info)();
    assert!(!i.is_null(), "model_info is NULL");
    // SAFETY: the library's metadata lives while it is loaded; the counts are its own.
    let i = unsafe { &*i };
    let s = |p: *const c_char| c_str(e, p);
    let strings = |p: *const *const c_char, n: usize| -> Vec<String> {
        (0..n).map(|k| s(unsafe { *p.add(k) })).collect()
    };
    let numbers =
        |p: *const f64, n: usize| -> Vec<f64> { (0..n).map(|k| unsafe { *p.add(k) }).collect() };
    assert_eq!(i.abi_version, crate::ABI_VERSION);
    assert_eq!(
        (s(i.name), s(i.title), s(i.description)),
        (g.name.into(), g.title.into(), g.description.into())
    );
    assert_eq!(
        (i.dof, i.state_dim, i.parameter_count, i.tip_dim),
        (N, NX, NP, g.tip_dim)
    );
    assert_eq!((g.dof, g.state_dim), (N, NX));
    assert_eq!(i.has_tip != 0, g.has_tip);
    assert_eq!(strings(i.parameter_names, NP), g.parameter_names);
    assert_eq!(strings(i.parameter_units, NP), g.parameter_units);
    assert_eq!(strings(i.state_names, NX), g.state_names);
    assert_eq!(strings(i.control_names, N), g.control_names);
    for (k, d) in g.domains.iter().enumerate() {
        let c = unsafe { *i.domains.add(k) };
        same("domains", k, &[c.lo, c.hi], &[d.lo, d.hi]);
        assert_eq!(
            (c.lo_open != 0, c.hi_open != 0, s(c.rule)),
            (d.lo_open, d.hi_open, d.rule.into())
        );
    }
    assert_eq!(i.constraint_count, g.constraints.len());
    for (k, c) in g.constraints.iter().enumerate() {
        let got = unsafe { *i.constraints.add(k) };
        same(
            "constraints",
            k,
            &numbers(got.coefficients, NP),
            c.coefficients,
        );
        assert_eq!(s(got.rule), c.rule);
    }
    same(
        "sample_lo",
        0,
        &numbers(i.sample_lo, NP),
        &g.sample.iter().map(|s| s.0).collect::<Vec<_>>(),
    );
    same(
        "sample_hi",
        0,
        &numbers(i.sample_hi, NP),
        &g.sample.iter().map(|s| s.1).collect::<Vec<_>>(),
    );
    for (k, d) in g.defaults.iter().enumerate() {
        let (has, value) = unsafe { (*i.has_default.add(k), *i.defaults.add(k)) };
        assert_eq!(has != 0, d.is_some());
        if let Some(v) = d {
            same("defaults", k, &[value], &[*v]);
        }
    }
    assert_eq!(i.has_inertia != 0, g.inertia.is_some());
    if let Some(r) = g.inertia {
        assert_eq!(i.inertia.moments.map(|v| v as usize), r.moments);
        assert_eq!(i.inertia.products.map(|v| v as usize), r.products);
        same("inertia slack", 0, &[i.inertia.slack], &[r.slack]);
        assert_eq!(s(i.inertia.rule), r.rule);
    }
    same(
        "equilibrium_state",
        0,
        &numbers(i.equilibrium_state, NX),
        g.equilibrium_state,
    );
    same(
        "equilibrium_control",
        0,
        &numbers(i.equilibrium_control, N),
        g.equilibrium_control,
    );
    assert_eq!(i.task_count, TaskKind::ALL.len());
    assert_eq!(
        strings(i.task_names, i.task_count),
        TaskKind::ALL.map(|k| k.name())
    );
    for (k, kind) in TaskKind::ALL.iter().enumerate() {
        assert_eq!(
            unsafe { *i.task_offered.add(k) } != 0,
            g.tasks.contains(kind)
        );
    }
    assert_eq!(i.term_count, TERMS);
    assert_eq!(strings(i.term_names, TERMS), Term::NAMES);
    assert_eq!(s(i.tasks_fingerprint), crate::fingerprint::hex());
}
