//! [`hostile`]: a table of named cases, each class of bad input once (the regressions of the
//! C ABI among them: a destroyed, doubly destroyed, foreign or forged handle, a learning rate
//! of 1e300 or 1e-300, an initial torque of 1e300, a result that would be NaN), then the
//! fuzzer ([`super::fuzz`]) and controllers ticked from several threads
//! ([`super::fuzz_threads`]).

use core::marker::PhantomData;

use nalgebra::{SMatrix, SVector};
use toolconf_core::{ArmController, ArmModel, SensitivitiesN, TaskKind, TaskN, ToolN};

use super::bad_inputs::{Call, Target, Want, CASES};
use super::fuzz::{fuzz, fuzz_cases, fuzz_threads, Foreign};
use super::{c_str, flat, flat_paper_task, try_create_controller, Create, Rng};
use crate::bodies::{Bodies, Controller};
use crate::{status, Exports};

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

/// A new controller of `M` made through [`Bodies`] directly (another model's, when `M` is not the
/// library's): NULL if the model has none to make.
pub fn controller_of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
) -> *mut Controller
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    // SAFETY: the arrays hold M's sizes.
    controller_made::<M, N, NX, NP, NZ>(|c| unsafe {
        Bodies::<M, N, NX, NP, NZ>::controller_create(
            c.params,
            c.task,
            c.goals,
            c.precisions,
            c.learning_rate,
            c.initial_torque,
            c.rate_hz,
            c.controller,
        )
    })
}

/// A new controller of model `M` made through library `e`'s `toolconf_controller_create` (NULL
/// if the model has none to make).
pub fn controller_through<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
) -> *mut Controller
where
    M: ArmModel<N, NX, NP, NZ>,
{
    // SAFETY: the arrays hold the model's sizes.
    controller_made::<M, N, NX, NP, NZ>(|c| unsafe { c.through(e) })
}

/// A controller of `M` made by `create` for a tool and task it can control (NULL if there is
/// none, or if `create` refuses).
fn controller_made<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    create: impl FnOnce(Create) -> i32,
) -> *mut Controller
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let Some((p, t, rate)) = controllable::<M, N, NX, NP, NZ>() else {
        return core::ptr::null_mut();
    };
    let task = flat_paper_task::<M, N, NX, NP, NZ>(TaskKind::ALL[t as usize]);
    try_create_controller(create, &p, &task, rate).1
}

/// What the cases call with: model `M`'s library, a controllable tool and its task (goals
/// and precisions), and the handles the table names.
struct Context<'a> {
    e: &'a Exports,
    tool: Vec<f64>,
    task: u32,
    rate: f64,
    goals: Vec<f64>,
    precisions: Vec<f64>,
    state: Vec<f64>,
    /// The tool's first parameter just outside its domain.
    outside: f64,
    destroyed: *mut Controller,
    reborn: *mut Controller,
    foreign: *mut Controller,
}

/// Memory that is no controller: its address, plus one, is a misaligned forged handle.
static MEMORY: [f64; 2] = [0.0; 2];

impl Context<'_> {
    fn target(&self, t: Target) -> *mut Controller {
        match t {
            Target::Null => core::ptr::null_mut(),
            Target::Destroyed => self.destroyed,
            Target::Reborn => self.reborn,
            Target::Foreign => self.foreign,
            Target::Integer(v) => v as *mut Controller,
            Target::Misaligned => (MEMORY.as_ptr() as usize + 1) as *mut Controller,
        }
    }

    /// `toolconf_controller_create` with the context's tool and task: (status, handle).
    fn create<const N: usize>(&self, gamma: f64, u0: f64, rate: f64) -> (i32, *mut Controller) {
        let mut h = core::ptr::null_mut();
        // SAFETY (every call of an export here): the arrays hold the model's sizes; any
        // handle value is checked.
        let code = unsafe {
            (self.e.controller_create)(
                self.tool.as_ptr(),
                self.task,
                self.goals.as_ptr(),
                self.precisions.as_ptr(),
                gamma,
                [u0; N].as_ptr(),
                rate,
                &mut h,
            )
        };
        (code, h)
    }

    /// Performs `call`: its status, and whether its outputs are as the rules want (untouched
    /// on a failure, finite on success).
    fn perform<const N: usize, const NX: usize>(&self, call: Call) -> (i32, bool) {
        let e = self.e;
        match call {
            Call::Create { gamma, u0, rate } => {
                let (code, h) = self.create::<N>(gamma, u0, rate.unwrap_or(self.rate));
                (code, (code == status::OK) != h.is_null())
            }
            Call::Tick(t) => {
                let (mut torque, mut c) = (Out::new(N), Out::new(1));
                let (h, x) = (self.target(t), self.state.as_ptr());
                let code = unsafe { (e.controller_tick)(h, x, torque.ptr(), c.ptr()) };
                (code, torque.as_wanted(code) && c.as_wanted(code))
            }
            Call::PiU(t) => {
                let mut out = Out::new(N * N);
                let code = unsafe { (e.controller_pi_u)(self.target(t), out.ptr()) };
                (code, out.as_wanted(code))
            }
            Call::Destroy(t) => (unsafe { (e.controller_destroy)(self.target(t)) }, true),
            Call::Dynamics { x, tool } => {
                let (x, p) = (
                    x.applied(&self.state, 0.0),
                    tool.applied(&self.tool, self.outside),
                );
                let mut out = Out::new(NX);
                let x_ptr = if x.is_empty() {
                    core::ptr::null()
                } else {
                    x.as_ptr()
                };
                let code = unsafe { (e.dynamics)(x_ptr, [0.0; N].as_ptr(), p.as_ptr(), out.ptr()) };
                (code, out.as_wanted(code))
            }
            Call::Confidence {
                task,
                goals,
                precisions,
                tool,
            } => {
                let (g, pr) = (
                    goals.applied(&self.goals, 0.0),
                    precisions.applied(&self.precisions, 0.0),
                );
                let p = tool.applied(&self.tool, self.outside);
                let (mut pi, mut logdet) = (Out::new(N * N), Out::new(1));
                let t = task.unwrap_or(self.task);
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
            }
        }
    }
}

/// The context of model `M`'s library `e`, its handles made: one destroyed, one made after it
/// (most allocators would give it the destroyed one's memory), one of `foreign`.
fn context<'a, M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &'a Exports,
    foreign: &Foreign<'_>,
) -> Option<Context<'a>>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let (p, t, rate) = controllable::<M, N, NX, NP, NZ>()?;
    let task = M::paper_task(TaskKind::ALL[t as usize]);
    let mut c = Context {
        e,
        tool: p.to_vec(),
        task: t,
        rate,
        goals: flat(&task.goal),
        precisions: flat(&task.precision),
        state: M::equilibrium_state().as_slice().to_vec(),
        outside: {
            let d = M::tool_rule().domains[0];
            if d.lo.is_finite() {
                d.lo - 1.0
            } else {
                d.hi + 1.0
            }
        },
        destroyed: core::ptr::null_mut(),
        reborn: core::ptr::null_mut(),
        foreign: (foreign.create)(),
    };
    c.destroyed = c.create::<N>(1.0, 0.1, rate).1;
    // SAFETY: a live handle of this library.
    assert_eq!(unsafe { (e.controller_destroy)(c.destroyed) }, status::OK);
    c.reborn = c.create::<N>(1.0, 0.1, rate).1;
    Some(c)
}

/// What `want` says of the status, for the dynamics at `call`'s state and tool.
fn wanted<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    c: &Context<'_>,
    call: Call,
    want: Want,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    match (want, call) {
        (Want::Is(code), _) => code,
        (Want::IfNotFinite(code), Call::Dynamics { x, tool }) => {
            let (x, p) = (x.applied(&c.state, 0.0), tool.applied(&c.tool, c.outside));
            let x = SVector::<f64, NX>::from_column_slice(&x);
            let f = M::dynamics(&x, &SVector::zeros(), &SVector::from_column_slice(&p));
            match f.iter().all(|v| v.is_finite()) {
                true => status::OK,
                false => code,
            }
        }
        (Want::IfNotFinite(code), _) => code,
    }
}

/// Runs the table of cases ([`CASES`]) on model `M`'s library `e`, panicking at the first
/// whose status, message or outputs differ; then destroys the foreign handle by its own
/// library. Returns how many cases ran.
fn run<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
    foreign: &Foreign<'_>,
) -> usize
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let Some(c) = context::<M, N, NX, NP, NZ>(e, foreign) else {
        return 0;
    };
    for (name, call, want, fragment) in CASES {
        let want = wanted::<M, N, NX, NP, NZ>(&c, *call, *want);
        let (code, outputs) = c.perform::<N, NX>(*call);
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
        let named = message.starts_with("toolconf_") && message.contains(fragment);
        assert!(
            want == status::OK || named,
            "{name}: the message does not say '{fragment}': {message}"
        );
    }
    assert_eq!(
        (foreign.destroy)(c.foreign),
        status::OK,
        "the foreign library's destroy"
    );
    CASES.len()
}

/// Hostile input to every export of model `M`'s library `e`: the table of cases ([`CASES`]),
/// then [`fuzz`] ([`fuzz_cases`]`(3000)` calls) with another model's controllers as the
/// foreign handles, and [`fuzz_threads`]. Each is a status, never a crash, and leaves its
/// outputs as they were. Returns how many calls were made.
pub fn hostile<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    e: &Exports,
) -> usize
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let create = || controller_of::<Twin<M>, N, NX, NP, NZ>();
    // SAFETY: any handle value is checked.
    let destroy = |h| unsafe { Bodies::<Twin<M>, N, NX, NP, NZ>::controller_destroy(h) };
    let other = Foreign {
        create: &create,
        destroy: &destroy,
    };
    let mut calls = run::<M, N, NX, NP, NZ>(e, &other);
    let (fuzzed, seen) = fuzz::<M, N, NX, NP, NZ>(e, &other, fuzz_cases(3000), 1);
    let reached = [
        status::OK,
        status::NULL_POINTER,
        status::BAD_HANDLE,
        status::NOT_FINITE,
    ];
    for code in reached {
        let never = c_str((e.status_name)(code));
        assert!(
            seen[code as usize] > 0 || fuzzed < 1000,
            "the fuzzer never reached {never}"
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
