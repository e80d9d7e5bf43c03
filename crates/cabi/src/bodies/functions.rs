//! The exports of the model's functions: the generated closed forms (unchecked: any finite
//! input), the tool's rule, the task's defaults, and the checked control confidence.

use nalgebra::{SMatrix, SVector};
use toolconf_core::{
    control_confidence as core_confidence, ArmModel, TaskKind, TaskN, Term, TERMS,
};

use super::{call, core_error, named, per_term_matrices, vector, write, Bodies};
use crate::status::{self, fail, Failure};

/// The task `kind` with `precision` and zero goals: what Π^U and its gradient read.
fn precision_task<const N: usize>(
    kind: TaskKind,
    precision: [SMatrix<f64, N, N>; TERMS],
) -> TaskN<N> {
    TaskN {
        kind,
        goal: [SVector::zeros(); TERMS],
        precision,
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Bodies<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// `toolconf_check_tool`.
    pub unsafe fn check_tool(params: *const f64) -> i32 {
        const F: &str = "toolconf_check_tool";
        call(F, &named!(params), || {
            let p = vector::<NP>(params, F, "params")?;
            Self::checked_tool(&p, F).map(drop)
        })
    }

    /// `toolconf_dynamics`.
    pub unsafe fn dynamics(
        x: *const f64,
        u: *const f64,
        params: *const f64,
        x_dot: *mut f64,
    ) -> i32 {
        Self::of_state("toolconf_dynamics", M::dynamics, x, u, params, x_dot)
    }

    /// `toolconf_rigid_body_dynamics`.
    pub unsafe fn rigid_body_dynamics(
        x: *const f64,
        u: *const f64,
        params: *const f64,
        x_dot: *mut f64,
    ) -> i32 {
        Self::of_state(
            "toolconf_rigid_body_dynamics",
            M::rigid_body_dynamics,
            x,
            u,
            params,
            x_dot,
        )
    }

    /// Ẋ of (X, U, p) by `f`: the dynamics, or the rigid-body dynamics alone.
    unsafe fn of_state(
        function: &str,
        f: impl FnOnce(&SVector<f64, NX>, &SVector<f64, N>, &SVector<f64, NP>) -> SVector<f64, NX>,
        x: *const f64,
        u: *const f64,
        params: *const f64,
        x_dot: *mut f64,
    ) -> i32 {
        call(function, &named!(x, u, params, x_dot), || {
            let (x, u, p) = Self::x_u_p(x, u, params, function)?;
            let v = f(&x, &u, &p);
            Self::finish(function, &p, &[(x_dot, "x_dot", v.as_slice())])
        })
    }

    /// (X, U, p) from C: the inputs of the dynamics.
    #[allow(clippy::type_complexity)]
    unsafe fn x_u_p(
        x: *const f64,
        u: *const f64,
        params: *const f64,
        function: &str,
    ) -> Result<(SVector<f64, NX>, SVector<f64, N>, SVector<f64, NP>), Failure> {
        Ok((
            vector::<NX>(x, function, "x")?,
            vector::<N>(u, function, "u")?,
            vector::<NP>(params, function, "params")?,
        ))
    }

    /// `toolconf_dynamics_jacobian`.
    pub unsafe fn dynamics_jacobian(
        x: *const f64,
        u: *const f64,
        params: *const f64,
        f_x: *mut f64,
        f_u: *mut f64,
    ) -> i32 {
        const F: &str = "toolconf_dynamics_jacobian";
        call(F, &named!(x, u, params, f_x, f_u), || {
            let (x, u, p) = Self::x_u_p(x, u, params, F)?;
            let (a, b) = M::dynamics_jacobian(&x, &u, &p);
            Self::finish(
                F,
                &p,
                &[(f_x, "f_x", a.as_slice()), (f_u, "f_u", b.as_slice())],
            )
        })
    }

    fn no_tip(function: &str) -> Failure {
        fail(
            status::NO_TIP,
            format_args!(
                "{function}: model {} has no tip (its description gives no [tip])",
                M::name()
            ),
        )
    }

    /// `toolconf_tip`.
    pub unsafe fn tip(
        q: *const f64,
        params: *const f64,
        position: *mut f64,
        jacobian: *mut f64,
    ) -> i32 {
        const F: &str = "toolconf_tip";
        call(F, &named!(q, params, position, jacobian), || {
            let q = vector::<N>(q, F, "q")?;
            let p = vector::<NP>(params, F, "params")?;
            let (y, j) = M::tip(&q, &p).ok_or_else(|| Self::no_tip(F))?;
            let results = [
                (position, "position", y.as_slice()),
                (jacobian, "jacobian", j.as_slice()),
            ];
            Self::finish(F, &p, &results)
        })
    }

    /// `toolconf_tip_bias`: J̇(q, q̇) q̇, the tip's acceleration at q̈ = 0 (ÿ = J q̈ + J̇ q̇).
    pub unsafe fn tip_bias(
        q: *const f64,
        q_dot: *const f64,
        params: *const f64,
        bias: *mut f64,
    ) -> i32 {
        const F: &str = "toolconf_tip_bias";
        call(F, &named!(q, q_dot, params, bias), || {
            let q = vector::<N>(q, F, "q")?;
            let q_dot = vector::<N>(q_dot, F, "q_dot")?;
            let p = vector::<NP>(params, F, "params")?;
            let b = M::tip_bias(&q, &q_dot, &p).ok_or_else(|| Self::no_tip(F))?;
            Self::finish(F, &p, &[(bias, "bias", b.as_slice())])
        })
    }

    /// `toolconf_state_matrix`.
    pub unsafe fn state_matrix(params: *const f64, a: *mut f64) -> i32 {
        const F: &str = "toolconf_state_matrix";
        call(F, &named!(params, a), || {
            let p = vector::<NP>(params, F, "params")?;
            Self::finish(F, &p, &[(a, "a", M::state_matrix(&p).as_slice())])
        })
    }

    /// `toolconf_input_matrix`.
    pub unsafe fn input_matrix(params: *const f64, b: *mut f64) -> i32 {
        const F: &str = "toolconf_input_matrix";
        call(F, &named!(params, b), || {
            let p = vector::<NP>(params, F, "params")?;
            Self::finish(F, &p, &[(b, "b", M::input_matrix(&p).as_slice())])
        })
    }

    /// `toolconf_task_defaults`: [`ArmModel::paper_task`]'s goals and (padded) precisions.
    pub unsafe fn task_defaults(task_index: u32, goals: *mut f64, precisions: *mut f64) -> i32 {
        const F: &str = "toolconf_task_defaults";
        call(F, &named!(goals, precisions), || {
            let t = M::paper_task(Self::task(task_index, F)?);
            let values = t.goal.iter().flatten().chain(t.precision.iter().flatten());
            if let Some(v) = values.into_iter().find(|v| !v.is_finite()) {
                return Err(fail(
                    status::INTERNAL,
                    format_args!("{F}: model {}'s default task holds {v}", M::name()),
                ));
            }
            for term in Term::ALL {
                let i = term.index();
                write(goals.add(i * N), t.goal[i].as_slice());
                write(precisions.add(i * N * N), t.precision[i].as_slice());
            }
            Ok(())
        })
    }

    /// `toolconf_sensitivities`: TERMS blocks of N × N, zero for a term the task does not use
    /// (and `used[t]` = 0 there, 1 elsewhere, when `used` is not NULL).
    pub unsafe fn sensitivities(
        task_index: u32,
        params: *const f64,
        sensitivities: *mut f64,
        used: *mut i32,
    ) -> i32 {
        const F: &str = "toolconf_sensitivities";
        call(F, &named!(params, sensitivities), || {
            let kind = Self::task(task_index, F)?;
            let p = vector::<NP>(params, F, "params")?;
            let s = M::sensitivities(kind, &p);
            let blocks: [SMatrix<f64, N, N>; TERMS] =
                core::array::from_fn(|i| s.d_du[i].unwrap_or_else(SMatrix::zeros));
            // SAFETY: TERMS matrices of N × N are TERMS·N·N contiguous doubles (nalgebra's
            // column-major array storage), the ABI's layout of the output.
            let flat = core::slice::from_raw_parts(blocks.as_ptr().cast::<f64>(), TERMS * N * N);
            Self::finish(F, &p, &[(sensitivities, "sensitivities", flat)])?;
            if !used.is_null() {
                for (i, block) in s.d_du.iter().enumerate() {
                    used.add(i).write_unaligned(i32::from(block.is_some()));
                }
            }
            Ok(())
        })
    }

    /// `toolconf_pi_u`: the generated closed form Π^U, as [`ArmModel::pi_u`] (no checks of the
    /// task).
    pub unsafe fn pi_u(
        task_index: u32,
        params: *const f64,
        precisions: *const f64,
        pi_u: *mut f64,
    ) -> i32 {
        let out = (pi_u, "pi_u");
        Self::of_precisions(
            "toolconf_pi_u",
            M::pi_u,
            task_index,
            params,
            precisions,
            out,
        )
    }

    /// `toolconf_logdet_gradient`: ∂ln|Π^U|/∂p, as [`ArmModel::logdet_gradient`].
    pub unsafe fn logdet_gradient(
        task_index: u32,
        params: *const f64,
        precisions: *const f64,
        gradient: *mut f64,
    ) -> i32 {
        let (f, out) = (M::logdet_gradient, (gradient, "gradient"));
        Self::of_precisions(
            "toolconf_logdet_gradient",
            f,
            task_index,
            params,
            precisions,
            out,
        )
    }

    /// A closed form `f` of a task's precisions and a tool, into `out` (named).
    unsafe fn of_precisions<const R: usize, const C: usize>(
        function: &str,
        f: impl FnOnce(&TaskN<N>, &SVector<f64, NP>) -> SMatrix<f64, R, C>,
        task_index: u32,
        params: *const f64,
        precisions: *const f64,
        out: (*mut f64, &str),
    ) -> i32 {
        let (ptr, what) = out;
        let pointers = [
            (params as *const (), "params"),
            (precisions as *const (), "precisions"),
            (ptr as *const (), what),
        ];
        call(function, &pointers, || {
            let kind = Self::task(task_index, function)?;
            let p = vector::<NP>(params, function, "params")?;
            let precision = per_term_matrices::<N>(precisions, function, "precisions")?;
            let v = f(&precision_task(kind, precision), &p);
            Self::finish(function, &p, &[(ptr, what, v.as_slice())])
        })
    }

    /// `toolconf_control_confidence`: toolconf-core's `control_confidence` (tool and task
    /// checked).
    pub unsafe fn control_confidence(
        task_index: u32,
        params: *const f64,
        goals: *const f64,
        precisions: *const f64,
        pi_u: *mut f64,
        logdet: *mut f64,
    ) -> i32 {
        const F: &str = "toolconf_control_confidence";
        call(F, &named!(params, goals, precisions, pi_u, logdet), || {
            let (p, task) = Self::task_inputs(task_index, params, goals, precisions, F)?;
            let tool = Self::checked_tool(&p, F)?;
            let c = core_confidence(&tool, &task).map_err(|e| core_error(&e, F))?;
            let results = [
                (pi_u, "pi_u", c.pi_u.as_slice()),
                (logdet, "logdet", core::slice::from_ref(&c.logdet)),
            ];
            Self::finish(F, &tool.params(), &results)
        })
    }
}
