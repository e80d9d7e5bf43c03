//! [`hostile`]: a table of named cases, each class of bad input once (the regressions of the
//! C ABI among them: a destroyed, doubly destroyed, foreign or forged handle, a learning rate
//! of 1e300 or 1e-300, an initial torque of 1e300, a result that would be NaN), then the
//! fuzzer ([`super::fuzz`]) and controllers ticked from several threads
//! ([`super::fuzz_threads`]).

use core::marker::PhantomData;

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ArmController, ArmModel, SensitivitiesN, TaskKind, TaskN, ToolN, TERMS};

use super::fuzz::{fuzz, fuzz_cases, fuzz_threads, Foreign};
use super::{c_str, flat, Rng};
use crate::imp::{self, Controller};
use crate::{status, Exports};

/// One case: its name, the call (returning its status and whether its outputs are as the
/// rules want: untouched on a failure, finite on success), the status and a fragment of the
/// message the rules give.
type Case<'a> = (String, Box<dyn FnMut() -> (i32, bool) + 'a>, i32, String);

/// An output array prefilled with a sentinel no export writes.
struct Out(Vec<f64>);

impl Out {
    const SENTINEL: f64 = -12345.678;
    fn new(len: usize) -> Self {
        Self(vec![Self::SENTINEL; len])
    }
    fn ptr(&mut self) -> *mut f64 {
        self.0.as_mut_ptr()
    }
    /// Untouched for a failure, every value finite for a success.
    fn as_wanted(&self, code: i32) -> bool {
        match code {
            status::OK => self.0.iter().all(|v| v.is_finite()),
            _ => self.0.iter().all(|v| *v == Self::SENTINEL),
        }
    }
}

/// A valid tool of `M` with a controller on task `t` at γ = 1 and one of the rates 1, 10 or
/// 100 kHz: (tool, task index, rate), from the sampling box.
fn controllable<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
) -> Option<([f64; NP], u32, f64)>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let offered = crate::info::generated(M::name()).map_or(&[][..], |g| g.tasks);
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let p: [f64; NP] = super::random_tool::<M, N, NX, NP, NZ>(&mut rng).into();
        let Ok(tool) = ToolN::<M, N, NX, NP, NZ>::new(p) else {
            continue;
        };
        for (t, kind) in TaskKind::ALL.iter().enumerate() {
            for rate in [1e3, 1e4, 1e5] {
                let task = M::paper_task(*kind);
                if offered.contains(kind)
                    && ArmController::new(&tool, &task, 1.0, [0.1; N], rate).is_ok()
                {
                    return Some((p, t as u32, rate));
                }
            }
        }
    }
    None
}

/// A new controller of `M` made through `imp` directly (another model's, when `M` is not the
/// library's): NULL if the model has none to make.
pub fn controller_of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
) -> *mut Controller
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let Some((p, t, rate)) = controllable::<M, N, NX, NP, NZ>() else {
        return core::ptr::null_mut();
    };
    let task = M::paper_task(TaskKind::ALL[t as usize]);
    let (g, pr) = (flat(&task.goal), flat(&task.precision));
    let mut h = core::ptr::null_mut();
    // SAFETY: the arrays hold M's sizes.
    unsafe {
        imp::controller_create::<M, N, NX, NP, NZ>(
            p.as_ptr(),
            t,
            g.as_ptr(),
            pr.as_ptr(),
            1.0,
            [0.1; N].as_ptr(),
            rate,
            &mut h,
        )
    };
    h
}

/// A new controller of model `M` made through library `e`'s `toolconf_controller_create` (NULL
/// if the model has none to make).
pub fn controller_through<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
) -> *mut Controller
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let mut h = core::ptr::null_mut();
    if let Some((p, t, rate)) = controllable::<M, N, NX, NP, NZ>() {
        let task = M::paper_task(TaskKind::ALL[t as usize]);
        let (g, pr) = (flat(&task.goal), flat(&task.precision));
        // SAFETY: the arrays hold the model's sizes.
        unsafe {
            (e.controller_create)(
                p.as_ptr(),
                t,
                g.as_ptr(),
                pr.as_ptr(),
                1.0,
                [0.1; N].as_ptr(),
                rate,
                &mut h,
            )
        };
    }
    h
}

/// The cases of the controller's exports: γ and U0 out of range, handles that are not live.
#[allow(clippy::type_complexity)]
fn controller_cases<'a, M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &'a Exports,
    foreign: &'a Foreign<'a>,
) -> Vec<Case<'a>>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let Some((p, t, rate)) = controllable::<M, N, NX, NP, NZ>() else {
        return Vec::new();
    };
    let task = M::paper_task(TaskKind::ALL[t as usize]);
    let arrays = std::rc::Rc::new((flat(&task.goal), flat(&task.precision)));
    // Captures only `e` and copies: a closure every case can call.
    let create = move |d: &(Vec<f64>, Vec<f64>), gamma: f64, u0: f64, rate: f64| {
        let mut h = core::ptr::null_mut();
        // SAFETY: the arrays hold M's sizes.
        let code = unsafe {
            (e.controller_create)(
                p.as_ptr(),
                t,
                d.0.as_ptr(),
                d.1.as_ptr(),
                gamma,
                [u0; N].as_ptr(),
                rate,
                &mut h,
            )
        };
        (code, h)
    };
    let made = |gamma, u0, rate| -> Box<dyn FnMut() -> (i32, bool) + 'a> {
        let d = arrays.clone();
        Box::new(move || {
            let (code, h) = create(&d, gamma, u0, rate);
            (code, h.is_null())
        })
    };
    // A handle destroyed, then (most allocators would give a new controller its memory) a
    // new controller: the old handle stays refused.
    let (_, destroyed) = create(&arrays, 1.0, 0.1, rate);
    // SAFETY (every call below): any handle value is checked.
    assert_eq!(unsafe { (e.controller_destroy)(destroyed) }, status::OK);
    let (_, reborn) = create(&arrays, 1.0, 0.1, rate);
    let other = (foreign.create)();
    static MEMORY: [f64; 2] = [0.0; 2];
    let misaligned = (MEMORY.as_ptr() as usize + 1) as *mut Controller;
    let state: Vec<f64> = M::equilibrium_state().as_slice().to_vec();
    let tick = move |h: *mut Controller| -> Box<dyn FnMut() -> (i32, bool) + 'a> {
        let state = state.clone();
        Box::new(move || {
            let (mut torque, mut confidence) = (Out::new(N), Out::new(1));
            let code =
                unsafe { (e.controller_tick)(h, state.as_ptr(), torque.ptr(), confidence.ptr()) };
            (code, torque.as_wanted(code) && confidence.as_wanted(code))
        })
    };
    let destroy = move |h: *mut Controller| -> Box<dyn FnMut() -> (i32, bool) + 'a> {
        Box::new(move || (unsafe { (e.controller_destroy)(h) }, true))
    };
    let pi = move |h: *mut Controller| -> Box<dyn FnMut() -> (i32, bool) + 'a> {
        Box::new(move || {
            let mut out = Out::new(N * N);
            let code = unsafe { (e.controller_pi_u)(h, out.ptr()) };
            (code, out.as_wanted(code))
        })
    };
    let bad = "is not a live controller";
    let cases: Vec<(&str, Box<dyn FnMut() -> (i32, bool) + 'a>, i32, &str)> = vec![
        (
            "create: learning rate 1e300",
            made(1e300, 0.1, rate),
            status::INVALID_OPTION,
            "learning rate = 1e300: must be a number in (0, 1e6]",
        ),
        (
            "create: learning rate 1e-300",
            made(1e-300, 0.1, rate),
            status::INVALID_OPTION,
            "learning rate (too small",
        ),
        (
            "create: learning rate NaN",
            made(f64::NAN, 0.1, rate),
            status::NOT_FINITE,
            "learning_rate = NaN",
        ),
        (
            "create: initial torque 1e300",
            made(1.0, 1e300, rate),
            status::INVALID_OPTION,
            "initial torque U0 = 1e300",
        ),
        (
            "create: control rate 0",
            made(1.0, 0.1, 0.0),
            status::INVALID_OPTION,
            "control rate [Hz] = 0",
        ),
        (
            "create: control rate 1e300",
            made(1.0, 0.1, 1e300),
            status::INVALID_OPTION,
            "control rate [Hz] = 1e300",
        ),
        (
            "tick: a destroyed handle",
            tick(destroyed),
            status::BAD_HANDLE,
            bad,
        ),
        (
            "destroy: a destroyed handle (a double destroy)",
            destroy(destroyed),
            status::BAD_HANDLE,
            bad,
        ),
        (
            "tick: the controller created after it",
            tick(reborn),
            status::OK,
            "",
        ),
        (
            "tick: another library's or model's controller",
            tick(other),
            status::BAD_HANDLE,
            "another",
        ),
        (
            "controller_pi_u: another library's or model's controller",
            pi(other),
            status::BAD_HANDLE,
            "another",
        ),
        (
            "destroy: another library's or model's controller",
            destroy(other),
            status::BAD_HANDLE,
            "another",
        ),
        (
            "controller_pi_u: the integer 0x1000",
            pi(0x1000 as *mut Controller),
            status::BAD_HANDLE,
            bad,
        ),
        (
            "tick: a misaligned address of other memory",
            tick(misaligned),
            status::BAD_HANDLE,
            bad,
        ),
        (
            "destroy: NULL",
            destroy(core::ptr::null_mut()),
            status::OK,
            "",
        ),
        (
            "destroy: the controller created after it",
            destroy(reborn),
            status::OK,
            "",
        ),
        (
            "tick: it after its destroy",
            tick(reborn),
            status::BAD_HANDLE,
            bad,
        ),
    ];
    let mut out: Vec<Case<'a>> = cases
        .into_iter()
        .map(|(n, c, s, f)| (n.to_string(), c, s, f.to_string()))
        .collect();
    out.push((
        "destroy: the other controller, by its own library".into(),
        Box::new(move || ((foreign.destroy)(other), true)),
        status::OK,
        String::new(),
    ));
    out
}

/// The cases of the stateless exports: one of each rule, and results that would not be finite.
#[allow(clippy::type_complexity)]
fn function_cases<'a, M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &'a Exports,
) -> Vec<Case<'a>>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let p: Vec<f64> = super::random_tool::<M, N, NX, NP, NZ>(&mut Rng::new(3))
        .as_slice()
        .to_vec();
    let x: Vec<f64> = M::equilibrium_state().as_slice().to_vec();
    let offered = crate::info::generated(M::name()).map_or(&[][..], |g| g.tasks);
    let t = TaskKind::ALL
        .iter()
        .position(|k| offered.contains(k))
        .unwrap_or(0);
    let task = M::paper_task(TaskKind::ALL[t]);
    let (g, pr) = (flat(&task.goal), flat(&task.precision));
    let dynamics = move |x: Vec<f64>, p: Vec<f64>| -> Box<dyn FnMut() -> (i32, bool) + 'a> {
        Box::new(move || {
            let mut out = Out::new(NX);
            let x_ptr = if x.is_empty() {
                core::ptr::null()
            } else {
                x.as_ptr()
            };
            // SAFETY (every call below): the arrays hold the model's sizes.
            let code = unsafe { (e.dynamics)(x_ptr, [0.0; N].as_ptr(), p.as_ptr(), out.ptr()) };
            (code, out.as_wanted(code))
        })
    };
    let confidence = move |t: u32,
                           g: Vec<f64>,
                           pr: Vec<f64>,
                           p: Vec<f64>|
          -> Box<dyn FnMut() -> (i32, bool) + 'a> {
        Box::new(move || {
            let (mut pi, mut logdet) = (Out::new(N * N), Out::new(1));
            let code = unsafe {
                (e.control_confidence)(
                    t,
                    p.as_ptr(),
                    g.as_ptr(),
                    pr.as_ptr(),
                    pi.ptr(),
                    logdet.ptr(),
                )
            };
            (code, pi.as_wanted(code) && logdet.as_wanted(code))
        })
    };
    let with = |v: &[f64], i: usize, value: f64| {
        let mut v = v.to_vec();
        v[i] = value;
        v
    };
    // Velocities of 1e300 (q̇² overflows), and a tool of zeros (a mass matrix of zeros): the
    // rules' statuses are what the direct results make of them.
    let fast = with(&x, NX - 1, 1e300);
    let zeros = vec![0.0; NP];
    let direct = |x: &[f64], p: &[f64]| {
        let f = M::dynamics(
            &SVector::from_column_slice(x),
            &SVector::zeros(),
            &SVector::from_column_slice(p),
        );
        f.iter().all(|v| v.is_finite())
    };
    let (fast_status, fast_fragment) = match direct(&fast, &p) {
        true => (status::OK, ""),
        false => (
            status::NOT_FINITE,
            "is not finite: the inputs are too large",
        ),
    };
    let (zeros_status, zeros_fragment) = match direct(&x, &zeros) {
        true => (status::OK, ""),
        false => (status::INVALID_TOOL, "is not finite: invalid"),
    };
    let mut bad_domain = p.clone();
    let d = M::tool_rule().domains[0];
    bad_domain[0] = if d.lo.is_finite() {
        d.lo - 1.0
    } else {
        d.hi + 1.0
    };
    let cases: Vec<(&str, Box<dyn FnMut() -> (i32, bool) + 'a>, i32, &str)> = vec![
        (
            "dynamics: x NULL",
            dynamics(Vec::new(), p.clone()),
            status::NULL_POINTER,
            "x is a null pointer",
        ),
        (
            "dynamics: the last velocity NaN",
            dynamics(with(&x, NX - 1, f64::NAN), p.clone()),
            status::NOT_FINITE,
            &*format!("x[{}] = NaN", NX - 1).leak(),
        ),
        (
            "dynamics: a velocity of 1e300",
            dynamics(fast, p.clone()),
            fast_status,
            fast_fragment,
        ),
        (
            "dynamics: a tool of zeros",
            dynamics(x.clone(), zeros),
            zeros_status,
            zeros_fragment,
        ),
        (
            "control_confidence: task u32::MAX",
            confidence(u32::MAX, g.clone(), pr.clone(), p.clone()),
            status::UNKNOWN_TASK,
            "task 4294967295 is not",
        ),
        (
            "control_confidence: all precisions zero",
            confidence(t as u32, g.clone(), vec![0.0; TERMS * N * N], p.clone()),
            status::INVALID_TASK,
            "",
        ),
        (
            "control_confidence: a goal of 1e300",
            confidence(t as u32, with(&g, 0, 1e300), pr.clone(), p.clone()),
            status::INVALID_TASK,
            "goal",
        ),
        (
            "control_confidence: a precision of inf",
            confidence(t as u32, g.clone(), with(&pr, 0, f64::INFINITY), p.clone()),
            status::NOT_FINITE,
            "precisions[0] = inf",
        ),
        (
            "control_confidence: the first parameter out of its domain",
            confidence(t as u32, g, pr, bad_domain),
            status::INVALID_TOOL,
            "",
        ),
    ];
    cases
        .into_iter()
        .map(|(n, c, s, f)| (n.to_string(), c, s, f.to_string()))
        .collect()
}

/// Runs `cases`, panicking at the first whose status, message or outputs differ.
fn run(e: &Exports, cases: Vec<Case<'_>>) -> usize {
    let count = cases.len();
    for (name, mut call, want, fragment) in cases {
        let (code, outputs) = call();
        let message = c_str((e.last_error)());
        assert_eq!(
            code,
            want,
            "{name}: status {code} ({}), expected {want} ({}); message: {message}",
            c_str((e.status_name)(code)),
            c_str((e.status_name)(want))
        );
        assert!(
            outputs,
            "{name}: an output was written by a failing call, or is not finite"
        );
        if want != status::OK {
            assert!(
                message.starts_with("toolconf_") && message.contains(&fragment),
                "{name}: the message does not say '{fragment}': {message}"
            );
        }
    }
    count
}

/// Hostile input to every export of model `M`'s library `e`: the table of cases, then
/// [`fuzz`] ([`fuzz_cases`]`(3000)` calls; another model's handles its foreign ones) and
/// [`fuzz_threads`]. Each is a status, never a crash, and leaves its outputs as they were.
/// Returns how many calls were made.
pub fn hostile<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
) -> usize
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let create = || controller_of::<Twin<M>, N, NX, NP, NZ>();
    // SAFETY: any handle value is checked.
    let destroy = |h| unsafe { imp::controller_destroy::<Twin<M>, N, NX, NP, NZ>(h) };
    let other = Foreign {
        create: &create,
        destroy: &destroy,
    };
    let mut calls = run(e, function_cases::<M, N, NX, NP, NZ>(e));
    calls += run(e, controller_cases::<M, N, NX, NP, NZ>(e, &other));
    let (fuzzed, seen) = fuzz::<M, N, NX, NP, NZ>(e, &other, fuzz_cases(3000), 1);
    for code in [
        status::OK,
        status::NULL_POINTER,
        status::BAD_HANDLE,
        status::UNKNOWN_TASK,
        status::NOT_FINITE,
    ] {
        assert!(
            seen[code as usize] > 0 || fuzzed < 1000,
            "the fuzzer never reached {}",
            c_str((e.status_name)(code))
        );
    }
    calls += fuzzed;
    let own = || controller_through::<M, N, NX, NP, NZ>(e);
    let state: Vec<f64> = M::equilibrium_state().as_slice().to_vec();
    calls + fuzz_threads(e, &own, &state, N, 4, fuzz_cases(3000) / 8)
}

/// Model `M` under another type: to a library's registry of handles, a second model exported
/// from the same binary, whose controllers are not `M`'s.
#[derive(Debug, Default, Clone, Copy)]
pub struct Twin<M>(PhantomData<M>);

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> ArmModel<N, NX, NP, NZ>
    for Twin<M>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    type DynamicsCoefficients = M::DynamicsCoefficients;
    type JacobianCoefficients = M::JacobianCoefficients;
    fn name() -> &'static str {
        M::name()
    }
    fn parameter_names() -> &'static [&'static str; NP] {
        M::parameter_names()
    }
    fn equilibrium_state() -> SVector<f64, NX> {
        M::equilibrium_state()
    }
    fn equilibrium_control() -> SVector<f64, N> {
        M::equilibrium_control()
    }
    fn tip_dim() -> usize {
        M::tip_dim()
    }
    fn tool_rule() -> &'static toolconf_core::generated::validity::ToolRule<NP> {
        M::tool_rule()
    }
    fn dynamics_coefficients(p: &SVector<f64, NP>) -> Self::DynamicsCoefficients {
        M::dynamics_coefficients(p)
    }
    fn jacobian_coefficients(p: &SVector<f64, NP>) -> Self::JacobianCoefficients {
        M::jacobian_coefficients(p)
    }
    fn dynamics_with(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        k: &Self::DynamicsCoefficients,
    ) -> SVector<f64, NX> {
        M::dynamics_with(x, u, k)
    }
    fn dynamics_jacobian_with(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        k: &Self::JacobianCoefficients,
    ) -> (SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        M::dynamics_jacobian_with(x, u, k)
    }
    fn rigid_body_dynamics(
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> SVector<f64, NX> {
        M::rigid_body_dynamics(x, u, p)
    }
    fn tip(
        q: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<(SVector<f64, 3>, SMatrix<f64, 3, N>)> {
        M::tip(q, p)
    }
    fn tip_bias(
        q: &SVector<f64, N>,
        q_dot: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<SVector<f64, 3>> {
        M::tip_bias(q, q_dot, p)
    }
    fn state_matrix(p: &SVector<f64, NP>) -> SMatrix<f64, NX, NX> {
        M::state_matrix(p)
    }
    fn input_matrix(p: &SVector<f64, NP>) -> SMatrix<f64, NX, N> {
        M::input_matrix(p)
    }
    fn sensitivities(kind: TaskKind, p: &SVector<f64, NP>) -> SensitivitiesN<N> {
        M::sensitivities(kind, p)
    }
    fn pi_u(task: &TaskN<N>, p: &SVector<f64, NP>) -> SMatrix<f64, N, N> {
        M::pi_u(task, p)
    }
    fn logdet_gradient(task: &TaskN<N>, p: &SVector<f64, NP>) -> SVector<f64, NP> {
        M::logdet_gradient(task, p)
    }
    fn paper_task(kind: TaskKind) -> TaskN<N> {
        M::paper_task(kind)
    }
}

/// The calling thread's last message of library `e`.
pub fn last_error(e: &Exports) -> String {
    c_str((e.last_error)())
}
