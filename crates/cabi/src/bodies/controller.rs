//! The exports of the on-robot controller: toolconf-core's [`ArmController`] behind a handle
//! of this library's registry ([`crate::handles`]).

use toolconf_core::{ArmController, ArmModel};

use super::{call, core_error, named, scalar, vector, write, Bodies, Controller};
use crate::handles;
use crate::status::{self, fail, Failure};

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Bodies<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    /// `toolconf_controller_create`: [`ArmController::new`] under a new handle.
    #[allow(clippy::too_many_arguments)]
    pub unsafe fn controller_create(
        params: *const f64,
        task_index: u32,
        goals: *const f64,
        precisions: *const f64,
        learning_rate: f64,
        initial_torque: *const f64,
        rate_hz: f64,
        controller: *mut *mut Controller,
    ) -> i32 {
        const F: &str = "toolconf_controller_create";
        let pointers = named!(params, goals, precisions, initial_torque, controller);
        call(F, &pointers, || {
            let (p, task) = Self::task_inputs(task_index, params, goals, precisions, F)?;
            let learning_rate = scalar(learning_rate, F, "learning_rate")?;
            let u0 = vector::<N>(initial_torque, F, "initial_torque")?;
            let rate_hz = scalar(rate_hz, F, "rate_hz")?;
            let tool = Self::checked_tool(&p, F)?;
            let c = ArmController::<M, N, NX, NP, NZ>::new(
                &tool,
                &task,
                learning_rate,
                u0.into(),
                rate_hz,
            )
            .map_err(|e| core_error(&e, F))?;
            let handle = handles::create(c, F)?;
            controller.write_unaligned(handle);
            Ok(())
        })
    }

    /// `toolconf_controller_destroy`: NULL is nothing to do.
    pub unsafe fn controller_destroy(controller: *mut Controller) -> i32 {
        const F: &str = "toolconf_controller_destroy";
        call(F, &[], || {
            handles::destroy::<ArmController<M, N, NX, NP, NZ>>(controller, F)
        })
    }

    /// `toolconf_controller_tick`: [`ArmController::tick`]. A failed tick leaves the
    /// controller's torque as it was.
    pub unsafe fn controller_tick(
        controller: *mut Controller,
        state: *const f64,
        torque: *mut f64,
        confidence: *mut f64,
    ) -> i32 {
        const F: &str = "toolconf_controller_tick";
        let pointers = named!(controller, state, torque, confidence);
        call(F, &pointers, || {
            Self::tick(F, controller, state, None, torque, confidence)
        })
    }

    /// `toolconf_controller_tick_with_acceleration`: [`ArmController::tick_with_acceleration`].
    pub unsafe fn controller_tick_with_acceleration(
        controller: *mut Controller,
        state: *const f64,
        acceleration: *const f64,
        torque: *mut f64,
        confidence: *mut f64,
    ) -> i32 {
        const F: &str = "toolconf_controller_tick_with_acceleration";
        let pointers = named!(controller, state, acceleration, torque, confidence);
        call(F, &pointers, || {
            Self::tick(F, controller, state, Some(acceleration), torque, confidence)
        })
    }

    /// One tick of either kind, its pointers checked: the handle, the measurements'
    /// finiteness, the tick.
    unsafe fn tick(
        f: &str,
        controller: *mut Controller,
        state: *const f64,
        acceleration: Option<*const f64>,
        torque: *mut f64,
        confidence: *mut f64,
    ) -> Result<(), Failure> {
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
            let results = [
                (torque, "torque", &command.torque[..]),
                (
                    confidence,
                    "confidence",
                    core::slice::from_ref(&command.confidence),
                ),
            ];
            copy_kept(f, &results)
        })
    }

    /// `toolconf_controller_pi_u`: the controller's Π^U.
    pub unsafe fn controller_pi_u(controller: *const Controller, pi_u: *mut f64) -> i32 {
        const F: &str = "toolconf_controller_pi_u";
        call(F, &named!(controller, pi_u), || {
            handles::with(controller, F, |c: &mut ArmController<M, N, NX, NP, NZ>| {
                let pi = c.control_confidence().pi_u;
                copy_kept(F, &[(pi_u, "pi_u", pi.as_slice())])
            })
        })
    }
}

/// Step 6 and the copy for what a controller keeps: finite by its construction, so a value
/// that is not is a bug ([`status::INTERNAL`]), never written.
unsafe fn copy_kept(function: &str, results: &[super::Output]) -> Result<(), Failure> {
    for (_, what, values) in results {
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(fail(
                status::INTERNAL,
                format_args!("{function}: {what}[{i}] = {v}: the controller holds a number that is not finite"),
            ));
        }
    }
    for (ptr, _, values) in results {
        write(*ptr, values);
    }
    Ok(())
}
