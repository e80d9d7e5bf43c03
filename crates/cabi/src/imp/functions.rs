//! The exports of the model's functions: the generated closed forms (unchecked: any finite
//! input), the tool's rule, the task's defaults, and the checked control confidence.

use nalgebra::{SMatrix, SVector};
use toolconf_core::{
    control_confidence as core_confidence, ArmModel, TaskKind, TaskN, Term, ToolN, TERMS,
};

use super::{
    core_error, finite_results, per_term_matrices, per_term_vectors, present, task, vector, write,
};
use crate::status::{self, fail, Failure};

/// `toolconf_check_tool`.
pub unsafe fn check_tool<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: *const f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_check_tool";
    super::guard(F, || {
        present(F, &[(params.cast(), "params")])?;
        let p = vector::<NP>(params, F, "params")?;
        ToolN::<M, N, NX, NP, NZ>::new(p.into())
            .map(drop)
            .map_err(|e| core_error(&e, F))
    })
}

/// X, U and p: the inputs of the dynamics.
type Xup<const N: usize, const NX: usize, const NP: usize> =
    (SVector<f64, NX>, SVector<f64, N>, SVector<f64, NP>);

/// (X, U, p) from C: the inputs of the dynamics.
unsafe fn x_u_p<const N: usize, const NX: usize, const NP: usize>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    function: &str,
) -> Result<Xup<N, NX, NP>, Failure> {
    Ok((
        vector::<NX>(x, function, "x")?,
        vector::<N>(u, function, "u")?,
        vector::<NP>(params, function, "params")?,
    ))
}

/// `toolconf_dynamics`.
pub unsafe fn dynamics<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    x_dot: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_dynamics";
    super::guard(F, || {
        let pointers = [(x.cast(), "x"), (u.cast(), "u"), (params.cast(), "params")];
        present(F, &pointers)?;
        present(F, &[(x_dot.cast_const().cast(), "x_dot")])?;
        let (x, u, p) = x_u_p::<N, NX, NP>(x, u, params, F)?;
        let f = M::dynamics(&x, &u, &p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("x_dot", f.as_slice())])?;
        write(x_dot, f.as_slice());
        Ok(())
    })
}

/// `toolconf_dynamics_jacobian`.
pub unsafe fn dynamics_jacobian<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    f_x: *mut f64,
    f_u: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_dynamics_jacobian";
    super::guard(F, || {
        let pointers = [(x.cast(), "x"), (u.cast(), "u"), (params.cast(), "params")];
        present(F, &pointers)?;
        present(
            F,
            &[
                (f_x.cast_const().cast(), "f_x"),
                (f_u.cast_const().cast(), "f_u"),
            ],
        )?;
        let (x, u, p) = x_u_p::<N, NX, NP>(x, u, params, F)?;
        let (a, b) = M::dynamics_jacobian(&x, &u, &p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("f_x", a.as_slice()), ("f_u", b.as_slice())])?;
        write(f_x, a.as_slice());
        write(f_u, b.as_slice());
        Ok(())
    })
}

/// `toolconf_rigid_body_dynamics`.
pub unsafe fn rigid_body_dynamics<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    x: *const f64,
    u: *const f64,
    params: *const f64,
    x_dot: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_rigid_body_dynamics";
    super::guard(F, || {
        let pointers = [(x.cast(), "x"), (u.cast(), "u"), (params.cast(), "params")];
        present(F, &pointers)?;
        present(F, &[(x_dot.cast_const().cast(), "x_dot")])?;
        let (x, u, p) = x_u_p::<N, NX, NP>(x, u, params, F)?;
        let f = M::rigid_body_dynamics(&x, &u, &p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("x_dot", f.as_slice())])?;
        write(x_dot, f.as_slice());
        Ok(())
    })
}

fn no_tip<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    function: &str,
) -> Failure
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fail(
        status::NO_TIP,
        format_args!(
            "{function}: model {} has no tip (its description gives no [tip])",
            M::name()
        ),
    )
}

/// `toolconf_tip`.
pub unsafe fn tip<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    q: *const f64,
    params: *const f64,
    position: *mut f64,
    jacobian: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_tip";
    super::guard(F, || {
        present(F, &[(q.cast(), "q"), (params.cast(), "params")])?;
        let outputs = [
            (position.cast_const().cast(), "position"),
            (jacobian.cast_const().cast(), "jacobian"),
        ];
        present(F, &outputs)?;
        let q = vector::<N>(q, F, "q")?;
        let p = vector::<NP>(params, F, "params")?;
        let (y, j) = M::tip(&q, &p).ok_or_else(|| no_tip::<M, N, NX, NP, NZ>(F))?;
        finite_results::<M, N, NX, NP, NZ>(
            F,
            &p,
            &[("position", y.as_slice()), ("jacobian", j.as_slice())],
        )?;
        write(position, y.as_slice());
        write(jacobian, j.as_slice());
        Ok(())
    })
}

/// `toolconf_tip_bias`: J̇(q, q̇) q̇, the tip's acceleration at q̈ = 0 (ÿ = J q̈ + J̇ q̇).
pub unsafe fn tip_bias<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    q: *const f64,
    q_dot: *const f64,
    params: *const f64,
    bias: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_tip_bias";
    super::guard(F, || {
        let pointers = [
            (q.cast(), "q"),
            (q_dot.cast(), "q_dot"),
            (params.cast(), "params"),
        ];
        present(F, &pointers)?;
        present(F, &[(bias.cast_const().cast(), "bias")])?;
        let q = vector::<N>(q, F, "q")?;
        let q_dot = vector::<N>(q_dot, F, "q_dot")?;
        let p = vector::<NP>(params, F, "params")?;
        let b = M::tip_bias(&q, &q_dot, &p).ok_or_else(|| no_tip::<M, N, NX, NP, NZ>(F))?;
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("bias", b.as_slice())])?;
        write(bias, b.as_slice());
        Ok(())
    })
}

/// `toolconf_state_matrix`.
pub unsafe fn state_matrix<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: *const f64,
    a: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_state_matrix";
    super::guard(F, || {
        present(
            F,
            &[(params.cast(), "params"), (a.cast_const().cast(), "a")],
        )?;
        let p = vector::<NP>(params, F, "params")?;
        let m = M::state_matrix(&p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("a", m.as_slice())])?;
        write(a, m.as_slice());
        Ok(())
    })
}

/// `toolconf_input_matrix`.
pub unsafe fn input_matrix<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: *const f64,
    b: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_input_matrix";
    super::guard(F, || {
        present(
            F,
            &[(params.cast(), "params"), (b.cast_const().cast(), "b")],
        )?;
        let p = vector::<NP>(params, F, "params")?;
        let m = M::input_matrix(&p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("b", m.as_slice())])?;
        write(b, m.as_slice());
        Ok(())
    })
}

/// `toolconf_task_defaults`: [`ArmModel::paper_task`]'s goals and (padded) precisions.
pub unsafe fn task_defaults<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    goals: *mut f64,
    precisions: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_task_defaults";
    super::guard(F, || {
        let outputs = [
            (goals.cast_const().cast(), "goals"),
            (precisions.cast_const().cast(), "precisions"),
        ];
        present(F, &outputs)?;
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let t = M::paper_task(kind);
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

/// `toolconf_sensitivities`: TERMS blocks of N × N, zero for a term the task does not use (and
/// `used[t]` = 0 there, 1 elsewhere, when `used` is not NULL).
pub unsafe fn sensitivities<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    params: *const f64,
    sensitivities: *mut f64,
    used: *mut i32,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_sensitivities";
    super::guard(F, || {
        let pointers = [
            (params.cast(), "params"),
            (sensitivities.cast_const().cast(), "sensitivities"),
        ];
        present(F, &pointers)?;
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let p = vector::<NP>(params, F, "params")?;
        let s = M::sensitivities(kind, &p);
        let blocks: [SMatrix<f64, N, N>; TERMS] =
            core::array::from_fn(|i| s.d_du[i].unwrap_or_else(SMatrix::zeros));
        // SAFETY: TERMS matrices of N × N are TERMS·N·N contiguous doubles (nalgebra's
        // column-major array storage), the ABI's layout of the output.
        let flat = core::slice::from_raw_parts(blocks.as_ptr().cast::<f64>(), TERMS * N * N);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("sensitivities", flat)])?;
        write(sensitivities, flat);
        if !used.is_null() {
            for (i, block) in s.d_du.iter().enumerate() {
                used.add(i).write_unaligned(i32::from(block.is_some()));
            }
        }
        Ok(())
    })
}

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

/// `toolconf_pi_u`: the generated closed form Π^U, as [`ArmModel::pi_u`] (no checks of the task).
pub unsafe fn pi_u<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task_index: u32,
    params: *const f64,
    precisions: *const f64,
    pi_u: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_pi_u";
    super::guard(F, || {
        let pointers = [(params.cast(), "params"), (precisions.cast(), "precisions")];
        present(F, &pointers)?;
        present(F, &[(pi_u.cast_const().cast(), "pi_u")])?;
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let p = vector::<NP>(params, F, "params")?;
        let precision = per_term_matrices::<N>(precisions, F, "precisions")?;
        let pi = M::pi_u(&precision_task(kind, precision), &p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("pi_u", pi.as_slice())])?;
        write(pi_u, pi.as_slice());
        Ok(())
    })
}

/// `toolconf_logdet_gradient`: ∂ln|Π^U|/∂p, as [`ArmModel::logdet_gradient`].
pub unsafe fn logdet_gradient<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    task_index: u32,
    params: *const f64,
    precisions: *const f64,
    gradient: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_logdet_gradient";
    super::guard(F, || {
        let pointers = [(params.cast(), "params"), (precisions.cast(), "precisions")];
        present(F, &pointers)?;
        present(F, &[(gradient.cast_const().cast(), "gradient")])?;
        let kind = task::<M, N, NX, NP, NZ>(task_index, F)?;
        let p = vector::<NP>(params, F, "params")?;
        let precision = per_term_matrices::<N>(precisions, F, "precisions")?;
        let g = M::logdet_gradient(&precision_task(kind, precision), &p);
        finite_results::<M, N, NX, NP, NZ>(F, &p, &[("gradient", g.as_slice())])?;
        write(gradient, g.as_slice());
        Ok(())
    })
}

/// Steps 3 and 4 for a task and a tool from C arrays (their pointers checked already): the
/// task, then the parameters, goals and precisions read and checked finite.
pub(super) unsafe fn task_inputs<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    task_index: u32,
    params: *const f64,
    goals: *const f64,
    precisions: *const f64,
    function: &str,
) -> Result<(SVector<f64, NP>, TaskN<N>), Failure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let kind = task::<M, N, NX, NP, NZ>(task_index, function)?;
    let p = vector::<NP>(params, function, "params")?;
    let goal = per_term_vectors::<N>(goals, function, "goals")?;
    let precision = per_term_matrices::<N>(precisions, function, "precisions")?;
    let task = TaskN {
        kind,
        goal,
        precision,
    };
    Ok((p, task))
}

/// Step 5 for a tool: the model's rule.
pub(super) fn checked_tool<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    p: &SVector<f64, NP>,
    function: &str,
) -> Result<ToolN<M, N, NX, NP, NZ>, Failure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    ToolN::<M, N, NX, NP, NZ>::new((*p).into()).map_err(|e| core_error(&e, function))
}

/// `toolconf_control_confidence`: toolconf-core's `control_confidence` (tool and task checked).
pub unsafe fn control_confidence<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    task_index: u32,
    params: *const f64,
    goals: *const f64,
    precisions: *const f64,
    pi_u: *mut f64,
    logdet: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ>,
{
    const F: &str = "toolconf_control_confidence";
    super::guard(F, || {
        let inputs = [
            (params.cast(), "params"),
            (goals.cast(), "goals"),
            (precisions.cast(), "precisions"),
        ];
        present(F, &inputs)?;
        present(
            F,
            &[
                (pi_u.cast_const().cast(), "pi_u"),
                (logdet.cast_const().cast(), "logdet"),
            ],
        )?;
        let (p, task) = task_inputs::<M, N, NX, NP, NZ>(task_index, params, goals, precisions, F)?;
        let tool = checked_tool::<M, N, NX, NP, NZ>(&p, F)?;
        let c = core_confidence(&tool, &task).map_err(|e| core_error(&e, F))?;
        let results = [
            ("pi_u", c.pi_u.as_slice()),
            ("logdet", core::slice::from_ref(&c.logdet)),
        ];
        finite_results::<M, N, NX, NP, NZ>(F, &tool.params(), &results)?;
        write(pi_u, c.pi_u.as_slice());
        logdet.write_unaligned(c.logdet);
        Ok(())
    })
}
