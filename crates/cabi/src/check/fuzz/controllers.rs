//! The fuzzer's calls of the controller's exports, with handles of every kind: live (each
//! mirrored by a controller made directly), destroyed, another library's or model's, forged
//! (random and small integers, addresses of other memory, a live handle's neighbours) and
//! NULL.

use std::sync::atomic::{AtomicUsize, Ordering};

use toolconf_core::{ArmController, ArmModel, ToolN};

use super::calls::task_of;
use super::{rules, Fuzz, Handle, Want};
use crate::bodies::{status_of, Controller};
use crate::{status, Exports};

/// What a handle that is not live gives (rule 2).
fn bad() -> (i32, String) {
    (status::BAD_HANDLE, "is not a live controller".into())
}

/// What `toolconf_controller_create` writes nowhere: a failed create leaves it.
const UNWRITTEN: usize = 0x5a5a_5a58;

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    Fuzz<'_, M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    /// Controller export `k` (0 to 9): create, tick, tick with acceleration, Π^U, destroy.
    pub(super) fn controller_call(&mut self, k: usize) {
        match k {
            0 | 1 => self.create(),
            2..=4 => self.tick(false),
            5 | 6 => self.tick(true),
            7 => self.controller_pi_u(),
            _ => self.destroy(),
        }
    }

    /// A handle of a kind chosen at random, live ones the most often.
    fn handle(&mut self) -> (Handle, *mut Controller) {
        match self.rng.below(10) {
            0 => (Handle::Null, core::ptr::null_mut()),
            1 if !self.destroyed.is_empty() => (Handle::Destroyed, self.rng.pick(&self.destroyed)),
            2 => (Handle::Foreign, self.rng.pick(&self.foreign)),
            3 => (Handle::Forged, self.forged()),
            _ if !self.live.is_empty() => {
                let i = self.rng.below(self.live.len());
                (Handle::Live(i), self.live[i].0)
            }
            _ => (Handle::Forged, self.forged()),
        }
    }

    /// A value that was never a handle of this library: random and small integers, all ones,
    /// addresses of other memory (aligned or not), a live handle's neighbours.
    fn forged(&mut self) -> *mut Controller {
        let here = &self.calls as *const usize as usize;
        let live = self.live.first().map_or(1, |(h, _)| *h as usize);
        let value = match self.rng.below(6) {
            0 => self.rng.next_u64() as usize,
            1 => 1 + self.rng.below(4096),
            2 => usize::MAX,
            3 => here + self.rng.below(2),
            4 => self.foreign.as_ptr() as usize + 1,
            _ => live ^ (1 << self.rng.below(usize::BITS as usize)),
        };
        let value = value.max(1);
        // A forged value equal to a live handle would be one: vanishingly rare, skipped.
        match self.live.iter().any(|(h, _)| *h as usize == value) {
            true => 1 as *mut Controller,
            false => value as *mut Controller,
        }
    }

    /// Rule 2 for `kind`, after rule 1.
    fn handle_rule(kind: Handle) -> Option<(i32, String)> {
        match kind {
            Handle::Live(_) | Handle::Null => None,
            _ => Some(bad()),
        }
    }

    fn create(&mut self) {
        if self.live.len() >= 6 {
            self.destroy_live(0);
        }
        let (t, tool) = (self.task(), self.tool());
        let (goal, precision) = self.goals_and_precisions(t);
        let (p, g, pr) = (self.array(&tool), self.array(&goal), self.array(&precision));
        let u0 = self.array(&[0.1; N]);
        let gamma = self.scalar(1.0);
        let typical = self.rng.pick(&[1000.0, 1e4, 1e5]);
        let rate = self.scalar(typical);
        let out_null = self.rng.one_in(25);
        let mut h = UNWRITTEN as *mut Controller;
        let dst = if out_null {
            core::ptr::null_mut()
        } else {
            &mut h as *mut _
        };
        // SAFETY: as the stateless calls'.
        let code = unsafe {
            (self.e.controller_create)(p.ptr(), t, g.ptr(), pr.ptr(), gamma, u0.ptr(), rate, dst)
        };
        let pointers = [
            p.arg("params"),
            g.arg("goals"),
            pr.arg("precisions"),
            u0.arg("initial_torque"),
            (out_null, "controller"),
        ];
        let inputs = [
            p.input("params"),
            g.input("goals"),
            pr.input("precisions"),
            ("learning_rate", vec![gamma], true),
            u0.input("initial_torque"),
            ("rate_hz", vec![rate], true),
        ];
        let direct = match rules(&pointers, Some((t, self.offered)), &inputs) {
            Some(w) => Err(w),
            None => {
                let task = task_of::<N>(t, Some(&g), &pr);
                let u0: [f64; N] = core::array::from_fn(|k| u0.values()[k]);
                ToolN::<M, N, NX, NP, NZ>::new(core::array::from_fn(|k| p.values()[k]))
                    .and_then(|tool| ArmController::new(&tool, &task, gamma, u0, rate))
                    .map_err(|e| (status_of(&e), String::new()))
            }
        };
        let want: Want = direct.as_ref().map(|_| vec![]).map_err(Clone::clone);
        self.check("toolconf_controller_create", code, want, &[]);
        match direct {
            Ok(c) => {
                assert!(h as usize != UNWRITTEN && !h.is_null(), "no handle written");
                self.live.push((h, c));
            }
            Err(_) => assert_eq!(h as usize, UNWRITTEN, "a failed create wrote a handle"),
        }
    }

    /// `toolconf_controller_tick` or, with `acceleration`, `..._tick_with_acceleration`.
    fn tick(&mut self, acceleration: bool) {
        let (kind, h) = self.handle();
        let (state, measured) = (self.state(), self.small(N));
        let (x, a) = (self.array(&state), self.array(&measured));
        let (mut torque, mut confidence) = (self.out(N), self.out(1));
        let (code, name) = match acceleration {
            // SAFETY: as the stateless calls'; any handle value is checked.
            false => (
                unsafe {
                    (self.e.controller_tick)(h, x.ptr(), torque.ptr_mut(), confidence.ptr_mut())
                },
                "toolconf_controller_tick",
            ),
            true => (
                unsafe {
                    (self.e.controller_tick_with_acceleration)(
                        h,
                        x.ptr(),
                        a.ptr(),
                        torque.ptr_mut(),
                        confidence.ptr_mut(),
                    )
                },
                "toolconf_controller_tick_with_acceleration",
            ),
        };
        let mut pointers = vec![(kind == Handle::Null, "controller"), x.arg("state")];
        let mut inputs = vec![x.input("state")];
        if acceleration {
            pointers.push(a.arg("acceleration"));
            inputs.push(a.input("acceleration"));
        }
        pointers.extend([torque.arg("torque"), confidence.arg("confidence")]);
        let early = rules(&pointers, None, &[])
            .or_else(|| Self::handle_rule(kind))
            .or_else(|| rules(&[], None, &inputs));
        let want = match (early, kind) {
            (Some(w), _) => Err(w),
            (None, Handle::Live(i)) => {
                let s: [f64; NX] = core::array::from_fn(|k| x.values()[k]);
                let m: [f64; N] = core::array::from_fn(|k| a.values()[k]);
                let c = &mut self.live[i].1;
                match acceleration {
                    false => c.tick(&s),
                    true => c.tick_with_acceleration(&s, &m),
                }
                .map(|cmd| vec![Some(cmd.torque.to_vec()), None])
                .map_err(|e| (status_of(&e), String::new()))
            }
            (None, _) => unreachable!("rule 2 refuses every handle but a live one"),
        };
        self.check(name, code, want, &[&torque, &confidence]);
    }

    fn controller_pi_u(&mut self) {
        let (kind, h) = self.handle();
        let mut pi = self.out(N * N);
        // SAFETY: as the stateless calls'; any handle value is checked.
        let code = unsafe { (self.e.controller_pi_u)(h, pi.ptr_mut()) };
        let early = rules(
            &[(kind == Handle::Null, "controller"), pi.arg("pi_u")],
            None,
            &[],
        )
        .or_else(|| Self::handle_rule(kind));
        let want = match (early, kind) {
            (Some(w), _) => Err(w),
            (None, Handle::Live(i)) => {
                let c = &self.live[i].1;
                Ok(vec![Some(c.control_confidence().pi_u.as_slice().to_vec())])
            }
            (None, _) => unreachable!("rule 2 refuses every handle but a live one"),
        };
        self.check("toolconf_controller_pi_u", code, want, &[&pi]);
    }

    fn destroy(&mut self) {
        let (kind, h) = self.handle();
        match kind {
            Handle::Live(i) => self.destroy_live(i),
            _ => {
                // SAFETY: any handle value is checked; NULL is nothing to do.
                let code = unsafe { (self.e.controller_destroy)(h) };
                let want = match kind {
                    Handle::Null => Ok(vec![]),
                    _ => Err(bad()),
                };
                self.check("toolconf_controller_destroy", code, want, &[]);
            }
        }
    }

    /// Destroys live controller `i`, which then joins the destroyed handles.
    fn destroy_live(&mut self, i: usize) {
        let (h, _) = self.live.swap_remove(i);
        // SAFETY: a live handle of this library.
        let code = unsafe { (self.e.controller_destroy)(h) };
        self.check("toolconf_controller_destroy", code, Ok(vec![]), &[]);
        self.destroyed.push(h);
    }

    /// Destroys every live controller, then every destroyed one again: a double destroy is a
    /// status too.
    pub(super) fn finish(&mut self) {
        while !self.live.is_empty() {
            self.destroy_live(0);
        }
        for h in self.destroyed.clone() {
            // SAFETY: any handle value is checked.
            let code = unsafe { (self.e.controller_destroy)(h) };
            self.check("toolconf_controller_destroy", code, Err(bad()), &[]);
        }
    }
}

/// One call of [`super::fuzz_threads`] on `slot`: a tick or Π^U of whatever handle it holds
/// (another thread may be destroying it), or its destruction and replacement. Returns the
/// number of calls made.
pub(super) fn contend(
    e: &Exports,
    create: &(dyn Fn() -> *mut Controller + Sync),
    slot: &AtomicUsize,
    state: &[f64],
    dof: usize,
    rng: &mut crate::check::Rng,
) -> usize {
    let h = slot.load(Ordering::Acquire) as *mut Controller;
    let allowed = |code: i32| {
        code == status::OK
            || code == status::BAD_HANDLE
            || (h.is_null() && code == status::NULL_POINTER)
    };
    // SAFETY (every call): the arrays hold the model's sizes; any handle value is checked.
    match rng.below(4) {
        0 | 1 => {
            let (mut torque, mut confidence) = (vec![0.0; dof], 0.0);
            let code = unsafe {
                (e.controller_tick)(h, state.as_ptr(), torque.as_mut_ptr(), &mut confidence)
            };
            assert!(allowed(code), "tick from several threads: status {code}");
            assert!(
                code != status::OK || torque.iter().chain([&confidence]).all(|v| v.is_finite())
            );
            1
        }
        2 => {
            let mut pi = vec![0.0; dof * dof];
            let code = unsafe { (e.controller_pi_u)(h, pi.as_mut_ptr()) };
            assert!(allowed(code), "Π^U from several threads: status {code}");
            1
        }
        _ => {
            let mine = slot.swap(0, Ordering::AcqRel) as *mut Controller;
            let mut calls = 0;
            if !mine.is_null() {
                assert_eq!(
                    unsafe { (e.controller_destroy)(mine) },
                    status::OK,
                    "destroy of a handle this thread took"
                );
                assert_eq!(
                    unsafe { (e.controller_destroy)(mine) },
                    status::BAD_HANDLE,
                    "a second destroy"
                );
                calls += 2;
            }
            let old = slot.swap(create() as usize, Ordering::AcqRel) as *mut Controller;
            if !old.is_null() {
                assert_eq!(
                    unsafe { (e.controller_destroy)(old) },
                    status::OK,
                    "destroy of a replaced handle"
                );
                calls += 1;
            }
            calls + 1
        }
    }
}
