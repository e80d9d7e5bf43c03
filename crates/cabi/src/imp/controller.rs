//! The exports of the on-robot controller: toolconf-core's [`ArmController`] behind a handle
//! of this library's registry ([`crate::handles`]).

use toolconf_core::{ArmController, ArmModel};

use super::functions::{checked_tool, task_inputs};
use super::{core_error, present, scalar, vector, write, Controller};
use crate::handles;
use crate::status::Failure;

/// `toolconf_controller_create`: [`ArmController::new`] under a new handle.
#[allow(clippy::too_many_arguments)]
pub unsafe fn controller_create<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    params: *const f64,
    task_index: u32,
    goals: *const f64,
    precisions: *const f64,
    learning_rate: f64,
    initial_torque: *const f64,
    rate_hz: f64,
    controller: *mut *mut Controller,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    const F: &str = "toolconf_controller_create";
    super::guard(F, || {
        let inputs = [
            (params.cast(), "params"),
            (goals.cast(), "goals"),
            (precisions.cast(), "precisions"),
            (initial_torque.cast(), "initial_torque"),
        ];
        present(F, &inputs)?;
        present(F, &[(controller.cast_const().cast(), "controller")])?;
        let (p, task) = task_inputs::<M, N, NX, NP, NZ>(task_index, params, goals, precisions, F)?;
        let learning_rate = scalar(learning_rate, F, "learning_rate")?;
        let u0 = vector::<N>(initial_torque, F, "initial_torque")?;
        let rate_hz = scalar(rate_hz, F, "rate_hz")?;
        let tool = checked_tool::<M, N, NX, NP, NZ>(&p, F)?;
        let c =
            ArmController::<M, N, NX, NP, NZ>::new(&tool, &task, learning_rate, u0.into(), rate_hz)
                .map_err(|e| core_error(&e, F))?;
        let handle = handles::create(c, F)?;
        controller.write_unaligned(handle);
        Ok(())
    })
}

/// `toolconf_controller_destroy`: NULL is nothing to do.
pub unsafe fn controller_destroy<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *mut Controller,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    const F: &str = "toolconf_controller_destroy";
    super::guard(F, || {
        handles::destroy::<ArmController<M, N, NX, NP, NZ>>(controller, F)
    })
}

/// `toolconf_controller_tick`: [`ArmController::tick`]. A failed tick leaves the controller's
/// torque as it was.
pub unsafe fn controller_tick<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *mut Controller,
    state: *const f64,
    torque: *mut f64,
    confidence: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    const F: &str = "toolconf_controller_tick";
    let measured = [(state.cast(), "state")];
    super::guard(F, || {
        tick::<M, N, NX, NP, NZ>(F, controller, &measured, state, None, torque, confidence)
    })
}

/// `toolconf_controller_tick_with_acceleration`: [`ArmController::tick_with_acceleration`].
pub unsafe fn controller_tick_with_acceleration<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *mut Controller,
    state: *const f64,
    acceleration: *const f64,
    torque: *mut f64,
    confidence: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    const F: &str = "toolconf_controller_tick_with_acceleration";
    let measured = [
        (state.cast(), "state"),
        (acceleration.cast(), "acceleration"),
    ];
    super::guard(F, || {
        let a = Some(acceleration);
        tick::<M, N, NX, NP, NZ>(F, controller, &measured, state, a, torque, confidence)
    })
}

/// One tick of either kind, its steps in order: the pointers (`measured` the inputs), the
/// handle, the measurements' finiteness, the tick.
#[allow(clippy::too_many_arguments)]
unsafe fn tick<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    function: &str,
    controller: *mut Controller,
    measured: &[(*const (), &str)],
    state: *const f64,
    acceleration: Option<*const f64>,
    torque: *mut f64,
    confidence: *mut f64,
) -> Result<(), Failure>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    let f = function;
    present(f, &[(controller.cast_const().cast(), "controller")])?;
    present(f, measured)?;
    present(
        f,
        &[
            (torque.cast_const().cast(), "torque"),
            (confidence.cast_const().cast(), "confidence"),
        ],
    )?;
    handles::with(controller, f, |c: &mut ArmController<M, N, NX, NP, NZ>| {
        let x = vector::<NX>(state, f, "state")?;
        let command = match acceleration {
            None => c.tick(&x.into()),
            Some(a) => {
                c.tick_with_acceleration(&x.into(), &vector::<N>(a, f, "acceleration")?.into())
            }
        }
        .map_err(|e| core_error(&e, f))?;
        // The core refuses a torque that is not finite; ln|Π^U| was checked at creation.
        kept_finite(
            f,
            &[
                ("torque", &command.torque),
                ("confidence", &[command.confidence]),
            ],
        )?;
        write(torque, &command.torque);
        confidence.write_unaligned(command.confidence);
        Ok(())
    })
}

/// `toolconf_controller_pi_u`: the controller's Π^U.
pub unsafe fn controller_pi_u<
    M,
    const N: usize,
    const NX: usize,
    const NP: usize,
    const NZ: usize,
>(
    controller: *const Controller,
    pi_u: *mut f64,
) -> i32
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    const F: &str = "toolconf_controller_pi_u";
    super::guard(F, || {
        present(
            F,
            &[
                (controller.cast(), "controller"),
                (pi_u.cast_const().cast(), "pi_u"),
            ],
        )?;
        handles::with(controller, F, |c: &mut ArmController<M, N, NX, NP, NZ>| {
            let pi = c.control_confidence().pi_u;
            kept_finite(F, &[("pi_u", pi.as_slice())])?;
            write(pi_u, pi.as_slice());
            Ok(())
        })
    })
}

/// Step 6 for what a controller keeps: finite by its construction, so a value that is not is a
/// bug ([`crate::status::INTERNAL`]), never written.
fn kept_finite(function: &str, results: &[(&str, &[f64])]) -> Result<(), Failure> {
    for (what, values) in results {
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(crate::status::fail(
                crate::status::INTERNAL,
                format_args!("{function}: {what}[{i}] = {v}: the controller holds a number that is not finite"),
            ));
        }
    }
    Ok(())
}
