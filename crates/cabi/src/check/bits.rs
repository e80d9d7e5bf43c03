//! [`bit_identity`]: every export through its pointer against the direct Rust call, bit for
//! bit.

use core::ffi::c_char;

use nalgebra::{SMatrix, SVector};
use toolconf_core::{
    control_confidence, ArmController, ArmModel, TaskKind, TaskN, Term, ToolN, TERMS,
};

use super::{
    flat, random_precisions, random_state, random_tool, try_create_controller, Create, Rng,
};
use crate::bodies::{status_of, Controller};
use crate::{status, Exports, ModelInfo};

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

/// An output compared: its name, the C ABI's numbers, the direct call's.
type Compared<'a> = (&'a str, &'a [f64], &'a [f64]);

/// One case's comparisons: the library's exports, the case's number, and how many numbers
/// were compared so far.
struct Case<'a> {
    e: &'a Exports,
    case: usize,
    compared: usize,
}

impl Case<'_> {
    /// `code` is OK and each output (its name, the C ABI's numbers, the direct call's) is the
    /// same bit for bit.
    fn outputs(&mut self, what: &str, code: i32, outputs: &[Compared]) {
        ok(what, self.e, code);
        for (name, got, want) in outputs {
            self.compared += counted(name, self.case, got, want);
        }
    }

    /// As [`Case::outputs`] for a function with one output, named as the function is.
    fn output(&mut self, what: &str, code: i32, got: &[f64], want: &[f64]) {
        self.outputs(what, code, &[(what, got, want)]);
    }

    /// As [`Case::outputs`] when the direct call has a result (`want`); else `code` is `refused`.
    fn optional(&mut self, what: &str, code: i32, want: Option<Vec<Compared>>, refused: i32) {
        match want {
            Some(outputs) => self.outputs(what, code, &outputs),
            None => assert_eq!(code, refused, "{what}: refused"),
        }
    }
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
        let mut c = Case { e, case, compared };
        let p = random_tool::<M, N, NX, NP, NZ>(&mut rng);
        let x = random_state(&mut rng, &x_e);
        let u = SVector::<f64, N>::from_fn(|_, _| rng.uniform(-5.0, 5.0));
        state_functions::<M, N, NX, NP, NZ>(&mut c, &x, &u, &p);
        tip_functions::<M, N, NX, NP, NZ>(&mut c, &x, &p);
        let precision = random_precisions::<N>(&mut rng);
        for (index, kind) in TaskKind::ALL.into_iter().enumerate() {
            let t = index as u32;
            let (goals, precisions) = task_functions::<M, N, NX, NP, NZ>(&mut c, t, &p, precision);
            let paper = M::paper_task(kind);
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
        compared = c.compared;
    }
    // The ticks must have been compared at all: some tool and task must make a controller.
    assert!(
        ticks > 0,
        "no controller of {cases} random tools on any task could be made"
    );
    compared + ticks
}

/// The functions of the state: the dynamics, their Jacobian, the rigid-body dynamics, A and B.
fn state_functions<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    c: &mut Case,
    x: &SVector<f64, NX>,
    u: &SVector<f64, N>,
    p: &SVector<f64, NP>,
) where
    M: ArmModel<N, NX, NP, NZ>,
{
    let e = c.e;
    let mut x_dot = [0.0; NX];
    // SAFETY (every call below): each pointer points to the documented number of values.
    let code = unsafe { (e.dynamics)(x.as_ptr(), u.as_ptr(), p.as_ptr(), x_dot.as_mut_ptr()) };
    let want = M::dynamics(x, u, p);
    c.output("dynamics", code, &x_dot, want.as_slice());
    let (mut f_x, mut f_u) = (vec![0.0; NX * NX], vec![0.0; NX * N]);
    let code = unsafe {
        let (x, u, p) = (x.as_ptr(), u.as_ptr(), p.as_ptr());
        (e.dynamics_jacobian)(x, u, p, f_x.as_mut_ptr(), f_u.as_mut_ptr())
    };
    let (a, b) = M::dynamics_jacobian(x, u, p);
    let outputs = [
        ("dynamics_jacobian (f_x)", &f_x[..], a.as_slice()),
        ("dynamics_jacobian (f_u)", &f_u[..], b.as_slice()),
    ];
    c.outputs("dynamics_jacobian", code, &outputs);
    let code =
        unsafe { (e.rigid_body_dynamics)(x.as_ptr(), u.as_ptr(), p.as_ptr(), x_dot.as_mut_ptr()) };
    let want = M::rigid_body_dynamics(x, u, p);
    c.output("rigid_body_dynamics", code, &x_dot, want.as_slice());
    let mut a_e = vec![0.0; NX * NX];
    let code = unsafe { (e.state_matrix)(p.as_ptr(), a_e.as_mut_ptr()) };
    let want = M::state_matrix(p);
    c.output("state_matrix", code, &a_e, want.as_slice());
    let mut b_e = vec![0.0; NX * N];
    let code = unsafe { (e.input_matrix)(p.as_ptr(), b_e.as_mut_ptr()) };
    let want = M::input_matrix(p);
    c.output("input_matrix", code, &b_e, want.as_slice());
}

/// The tip and its bias, or NO_TIP for a model without a tip.
fn tip_functions<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    c: &mut Case,
    x: &SVector<f64, NX>,
    p: &SVector<f64, NP>,
) where
    M: ArmModel<N, NX, NP, NZ>,
{
    let e = c.e;
    let q = x.fixed_rows::<N>(0).into_owned();
    let (mut y, mut j) = ([0.0; 3], vec![0.0; 3 * N]);
    // SAFETY (both calls): each pointer points to the documented number of values.
    let code = unsafe { (e.tip)(q.as_ptr(), p.as_ptr(), y.as_mut_ptr(), j.as_mut_ptr()) };
    let want = M::tip(&q, p);
    let want = want.as_ref().map(|(y0, j0)| {
        vec![
            ("tip (position)", &y[..], y0.as_slice()),
            ("tip (jacobian)", &j[..], j0.as_slice()),
        ]
    });
    c.optional("tip", code, want, status::NO_TIP);
    let q_dot = x.fixed_rows::<N>(N).into_owned();
    let mut bias = [0.0; 3];
    let code = unsafe { (e.tip_bias)(q.as_ptr(), q_dot.as_ptr(), p.as_ptr(), bias.as_mut_ptr()) };
    let want = M::tip_bias(&q, &q_dot, p);
    let want = want
        .as_ref()
        .map(|b| vec![("tip_bias", &bias[..], b.as_slice())]);
    c.optional("tip_bias", code, want, status::NO_TIP);
}

/// The functions of task `t` on tool `p`: its defaults (returned: its goals and precisions,
/// flat), its sensitivities, Π^U and ∂ln|Π^U|/∂p on `precision`, and the control confidence on
/// the defaults.
fn task_functions<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    c: &mut Case,
    t: u32,
    p: &SVector<f64, NP>,
    precision: [SMatrix<f64, N, N>; TERMS],
) -> (Vec<f64>, Vec<f64>)
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let e = c.e;
    let kind = TaskKind::ALL[t as usize];
    let name = kind.name();
    let (mut goals, mut precisions) = (vec![0.0; TERMS * N], vec![0.0; TERMS * N * N]);
    // SAFETY (every call below): each pointer points to the documented number of values.
    let code = unsafe { (e.task_defaults)(t, goals.as_mut_ptr(), precisions.as_mut_ptr()) };
    let paper = M::paper_task(kind);
    let (goals_of, precisions_of) = (
        format!("task_defaults {name} (goals)"),
        format!("task_defaults {name} (precisions)"),
    );
    let outputs = [
        (&goals_of[..], &goals[..], &flat(&paper.goal)[..]),
        (
            &precisions_of[..],
            &precisions[..],
            &flat(&paper.precision)[..],
        ),
    ];
    c.outputs("task_defaults", code, &outputs);
    sensitivities::<M, N, NX, NP, NZ>(c, t, p);
    let task = TaskN {
        kind,
        goal: [SVector::zeros(); TERMS],
        precision,
    };
    let pf = flat(&precision);
    let mut pi = vec![0.0; N * N];
    let code = unsafe { (e.pi_u)(t, p.as_ptr(), pf.as_ptr(), pi.as_mut_ptr()) };
    let want = M::pi_u(&task, p);
    c.outputs(
        "pi_u",
        code,
        &[(&format!("pi_u {name}"), &pi, want.as_slice())],
    );
    let mut grad = vec![0.0; NP];
    let code = unsafe { (e.logdet_gradient)(t, p.as_ptr(), pf.as_ptr(), grad.as_mut_ptr()) };
    let want = M::logdet_gradient(&task, p);
    let what = format!("logdet_gradient {name}");
    c.outputs("logdet_gradient", code, &[(&what, &grad, want.as_slice())]);
    confidence::<M, N, NX, NP, NZ>(c, t, p, &goals, &precisions, &paper);
    (goals, precisions)
}

/// The sensitivities of task `t` on tool `p`, and which terms it uses.
fn sensitivities<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    c: &mut Case,
    t: u32,
    p: &SVector<f64, NP>,
) where
    M: ArmModel<N, NX, NP, NZ>,
{
    let kind = TaskKind::ALL[t as usize];
    let name = kind.name();
    let (mut s, mut used) = (vec![f64::NAN; TERMS * N * N], [7_i32; TERMS]);
    // SAFETY: each pointer points to the documented number of values.
    let code = unsafe { (c.e.sensitivities)(t, p.as_ptr(), s.as_mut_ptr(), used.as_mut_ptr()) };
    ok("sensitivities", c.e, code);
    let direct = M::sensitivities(kind, p);
    for term in Term::ALL {
        let i = term.index();
        let want = direct.d_du[i].unwrap_or_else(SMatrix::zeros);
        c.compared += counted(
            &format!("sensitivities {name} {}", term.name()),
            c.case,
            &s[i * N * N..(i + 1) * N * N],
            want.as_slice(),
        );
        assert_eq!(
            used[i],
            i32::from(direct.d_du[i].is_some()),
            "sensitivities {name}: used[{i}]"
        );
    }
}

/// The validated path on the model's own task (`paper`, flat in `goals` and `precisions`): the
/// same status as the direct call, and the same bits.
fn confidence<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    c: &mut Case,
    t: u32,
    p: &SVector<f64, NP>,
    goals: &[f64],
    precisions: &[f64],
    paper: &TaskN<N>,
) where
    M: ArmModel<N, NX, NP, NZ>,
{
    let e = c.e;
    let name = paper.kind.name();
    let (mut pi_c, mut logdet) = (vec![0.0; N * N], 0.0);
    // SAFETY: each pointer points to the documented number of values.
    let code = unsafe {
        let (g, pr) = (goals.as_ptr(), precisions.as_ptr());
        (e.control_confidence)(t, p.as_ptr(), g, pr, pi_c.as_mut_ptr(), &mut logdet)
    };
    let tool = ToolN::<M, N, NX, NP, NZ>::new((*p).into());
    let direct = tool
        .as_ref()
        .map_err(status_of)
        .and_then(|tool| control_confidence(tool, paper).map_err(|e| status_of(&e)));
    match direct {
        Ok(want) => {
            let (pi_of, logdet_of) = (
                format!("control_confidence {name} (pi_u)"),
                format!("control_confidence {name} (logdet)"),
            );
            let outputs = [
                (&pi_of[..], &pi_c[..], want.pi_u.as_slice()),
                (&logdet_of[..], &[logdet][..], &[want.logdet][..]),
            ];
            c.outputs("control_confidence", code, &outputs);
        }
        Err(want) => assert_eq!(
            code,
            want,
            "control_confidence {name}: {}",
            c_str(e, (e.last_error)())
        ),
    }
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
    let flat_task = (t, goals.to_vec(), precisions.to_vec());
    // SAFETY: the arrays hold the model's sizes.
    let create = |c: Create| unsafe { c.through(e) };
    let (code, handle) = try_create_controller(create, p.as_slice(), &flat_task, 1000.0);
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
    let compared = ticks::<M, N, NX, NP, NZ>(e, rng, (case, name), handle, &mut direct);
    ok("controller_destroy", e, unsafe {
        (e.controller_destroy)(handle)
    });
    compared
}

/// The controller behind `handle` against `direct`, the same controller made directly (case
/// `case`, task `name`): its Π^U, then four ticks on random measurements (with the accelerations every other one).
fn ticks<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
    rng: &mut Rng,
    (case, name): (usize, &str),
    handle: *mut Controller,
    direct: &mut ArmController<M, N, NX, NP, NZ>,
) -> usize
where
    M: ArmModel<N, NX, NP, NZ>,
{
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
    check_tool_rule::<NP>(i, g);
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

/// `n` C strings of the metadata from `p`.
fn strings(p: *const *const c_char, n: usize) -> Vec<String> {
    // SAFETY: the metadata's arrays hold their documented counts of live C strings.
    (0..n).map(|k| super::c_str(unsafe { *p.add(k) })).collect()
}

/// `n` numbers of the metadata from `p`.
fn numbers(p: *const f64, n: usize) -> Vec<f64> {
    // SAFETY: the metadata's arrays hold their documented counts of numbers.
    (0..n).map(|k| unsafe { *p.add(k) }).collect()
}

/// The tool's rule in the metadata equals the generated one: the domains, the constraints,
/// the sampling box, the defaults and the inertia rule.
fn check_tool_rule<const NP: usize>(i: &ModelInfo, g: &toolconf_core::generated::ModelInfo) {
    let s = super::c_str;
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
    let (lo, hi): (Vec<f64>, Vec<f64>) = g.sample.iter().copied().unzip();
    same("sample_lo", 0, &numbers(i.sample_lo, NP), &lo);
    same("sample_hi", 0, &numbers(i.sample_hi, NP), &hi);
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
}
