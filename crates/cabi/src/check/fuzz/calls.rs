//! The fuzzer's calls of the stateless exports: each generates its arguments, calls the
//! export, and says what the rules want of it.

use nalgebra::{SMatrix, SVector};
use toolconf_core::{control_confidence, ArmModel, TaskKind, TaskN, ToolN, TERMS};

use super::{results, rules, Array, Fuzz};
use crate::bodies::status_of;
use crate::check::c_str;
use crate::status;

fn vector<const K: usize>(a: &Array) -> SVector<f64, K> {
    SVector::from_column_slice(&a.values())
}

fn blocks<const N: usize>(a: &Array) -> [SMatrix<f64, N, N>; TERMS] {
    let v = a.values();
    core::array::from_fn(|t| SMatrix::from_column_slice(&v[t * N * N..(t + 1) * N * N]))
}

fn goal_blocks<const N: usize>(a: &Array) -> [SVector<f64, N>; TERMS] {
    let v = a.values();
    core::array::from_fn(|t| SVector::from_column_slice(&v[t * N..(t + 1) * N]))
}

/// The task the arrays describe: task `t`, the goals (zero for an export that takes none) and
/// the precisions, block by block as the C ABI lays them out.
pub(super) fn task_of<const N: usize>(
    t: u32,
    goals: Option<&Array>,
    precisions: &Array,
) -> TaskN<N> {
    TaskN {
        kind: TaskKind::ALL[t as usize],
        goal: goals.map_or([SVector::zeros(); TERMS], goal_blocks::<N>),
        precision: blocks::<N>(precisions),
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    Fuzz<'_, M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ> + 'static,
{
    /// Export number `which` (0 to 23, the controllers' more often) with generated arguments.
    pub(super) fn call(&mut self, which: usize) {
        match which {
            0 => self.check_tool(),
            1 | 2 => self.dynamics(which == 2),
            3 => self.dynamics_jacobian(),
            4 | 5 => self.tip(which == 5),
            6 | 7 => self.matrix(which == 7),
            8 => self.task_defaults(),
            9 => self.sensitivities(),
            10 | 11 => self.pi_u(which == 11),
            12 => self.control_confidence(),
            13 => self.getters(),
            _ => self.controller_call(which - 14),
        }
    }

    fn check_tool(&mut self) {
        let tool = self.tool();
        let p = self.array(&tool);
        // SAFETY (every call of an export here): each non-NULL pointer points to the
        // documented number of values; the sizes are the model's.
        let code = unsafe { (self.e.check_tool)(p.ptr()) };
        let want = match rules(&[p.arg("params")], None, &[p.input("params")]) {
            Some(w) => Err(w),
            None => ToolN::<M, N, NX, NP, NZ>::new(vector::<NP>(&p).into())
                .map(|_| vec![])
                .map_err(|e| (status_of(&e), String::new())),
        };
        self.check("toolconf_check_tool", code, want, &[]);
    }

    fn dynamics(&mut self, rigid: bool) {
        let (state, torque, tool) = (self.state(), self.small(N), self.tool());
        let (x, u, p) = (self.array(&state), self.array(&torque), self.array(&tool));
        let mut out = self.out(NX);
        let (export, name) = match rigid {
            true => (self.e.rigid_body_dynamics, "toolconf_rigid_body_dynamics"),
            false => (self.e.dynamics, "toolconf_dynamics"),
        };
        let code = unsafe { export(x.ptr(), u.ptr(), p.ptr(), out.ptr_mut()) };
        let pointers = [x.arg("x"), u.arg("u"), p.arg("params"), out.arg("x_dot")];
        let inputs = [x.input("x"), u.input("u"), p.input("params")];
        let want = match rules(&pointers, None, &inputs) {
            Some(w) => Err(w),
            None => {
                let (x, u, p) = (vector::<NX>(&x), vector::<N>(&u), vector::<NP>(&p));
                let f = match rigid {
                    true => M::rigid_body_dynamics(&x, &u, &p),
                    false => M::dynamics(&x, &u, &p),
                };
                results::<M, N, NX, NP, NZ>(&p, vec![f.as_slice().to_vec()])
            }
        };
        self.check(name, code, want, &[&out]);
    }

    fn dynamics_jacobian(&mut self) {
        let (state, torque, tool) = (self.state(), self.small(N), self.tool());
        let (x, u, p) = (self.array(&state), self.array(&torque), self.array(&tool));
        let (mut a, mut b) = (self.out(NX * NX), self.out(NX * N));
        let code = unsafe {
            (self.e.dynamics_jacobian)(x.ptr(), u.ptr(), p.ptr(), a.ptr_mut(), b.ptr_mut())
        };
        let pointers = [
            x.arg("x"),
            u.arg("u"),
            p.arg("params"),
            a.arg("f_x"),
            b.arg("f_u"),
        ];
        let inputs = [x.input("x"), u.input("u"), p.input("params")];
        let want = match rules(&pointers, None, &inputs) {
            Some(w) => Err(w),
            None => {
                let (x, u, p) = (vector::<NX>(&x), vector::<N>(&u), vector::<NP>(&p));
                let (fx, fu) = M::dynamics_jacobian(&x, &u, &p);
                let outputs = vec![fx.as_slice().to_vec(), fu.as_slice().to_vec()];
                results::<M, N, NX, NP, NZ>(&p, outputs)
            }
        };
        self.check("toolconf_dynamics_jacobian", code, want, &[&a, &b]);
    }

    /// `toolconf_tip` (`bias` false) or `toolconf_tip_bias`.
    fn tip(&mut self, bias: bool) {
        let (q0, qd0, tool) = (self.small(N), self.small(N), self.tool());
        let (q, q_dot, p) = (self.array(&q0), self.array(&qd0), self.array(&tool));
        let (mut y, mut j) = (self.out(3), self.out(3 * N));
        let (code, name) = match bias {
            false => (
                unsafe { (self.e.tip)(q.ptr(), p.ptr(), y.ptr_mut(), j.ptr_mut()) },
                "toolconf_tip",
            ),
            true => (
                unsafe { (self.e.tip_bias)(q.ptr(), q_dot.ptr(), p.ptr(), y.ptr_mut()) },
                "toolconf_tip_bias",
            ),
        };
        let (pointers, inputs) = match bias {
            false => (
                vec![
                    q.arg("q"),
                    p.arg("params"),
                    y.arg("position"),
                    j.arg("jacobian"),
                ],
                vec![q.input("q"), p.input("params")],
            ),
            true => (
                vec![
                    q.arg("q"),
                    q_dot.arg("q_dot"),
                    p.arg("params"),
                    y.arg("bias"),
                ],
                vec![q.input("q"), q_dot.input("q_dot"), p.input("params")],
            ),
        };
        let want = rules(&pointers, None, &inputs).map_or_else(
            || {
                let (qv, qdv, pv) = (vector::<N>(&q), vector::<N>(&q_dot), vector::<NP>(&p));
                let outputs = match bias {
                    false => M::tip(&qv, &pv)
                        .map(|(y, j)| vec![y.as_slice().to_vec(), j.as_slice().to_vec()]),
                    true => M::tip_bias(&qv, &qdv, &pv).map(|b| vec![b.as_slice().to_vec()]),
                };
                match outputs {
                    Some(o) => results::<M, N, NX, NP, NZ>(&pv, o),
                    None => Err((status::NO_TIP, "has no tip".into())),
                }
            },
            Err,
        );
        let outputs: Vec<&Array> = if bias { vec![&y] } else { vec![&y, &j] };
        self.check(name, code, want, &outputs);
    }

    /// `toolconf_state_matrix` (`input` false) or `toolconf_input_matrix`.
    fn matrix(&mut self, input: bool) {
        let tool = self.tool();
        let p = self.array(&tool);
        let mut out = self.out(if input { NX * N } else { NX * NX });
        let (code, name, out_name) = match input {
            false => (
                unsafe { (self.e.state_matrix)(p.ptr(), out.ptr_mut()) },
                "toolconf_state_matrix",
                "a",
            ),
            true => (
                unsafe { (self.e.input_matrix)(p.ptr(), out.ptr_mut()) },
                "toolconf_input_matrix",
                "b",
            ),
        };
        let want = match rules(
            &[p.arg("params"), out.arg(out_name)],
            None,
            &[p.input("params")],
        ) {
            Some(w) => Err(w),
            None => {
                let pv = vector::<NP>(&p);
                let m = match input {
                    false => M::state_matrix(&pv).as_slice().to_vec(),
                    true => M::input_matrix(&pv).as_slice().to_vec(),
                };
                results::<M, N, NX, NP, NZ>(&pv, vec![m])
            }
        };
        self.check(name, code, want, &[&out]);
    }

    fn task_defaults(&mut self) {
        let t = self.task();
        let (mut goals, mut precisions) = (self.out(TERMS * N), self.out(TERMS * N * N));
        let code = unsafe { (self.e.task_defaults)(t, goals.ptr_mut(), precisions.ptr_mut()) };
        let pointers = [goals.arg("goals"), precisions.arg("precisions")];
        let want = match rules(&pointers, Some((t, self.offered)), &[]) {
            Some(w) => Err(w),
            None => {
                let paper = M::paper_task(TaskKind::ALL[t as usize]);
                Ok(vec![
                    Some(super::super::flat(&paper.goal)),
                    Some(super::super::flat(&paper.precision)),
                ])
            }
        };
        self.check("toolconf_task_defaults", code, want, &[&goals, &precisions]);
    }

    fn sensitivities(&mut self) {
        let (t, tool) = (self.task(), self.tool());
        let p = self.array(&tool);
        let mut s = self.out(TERMS * N * N);
        let mut used = [0x5a5a_5a5a_i32; TERMS + 1];
        let used_ptr = match self.rng.one_in(3) {
            true => core::ptr::null_mut(),
            false => used.as_mut_ptr(),
        };
        let code = unsafe { (self.e.sensitivities)(t, p.ptr(), s.ptr_mut(), used_ptr) };
        let pointers = [p.arg("params"), s.arg("sensitivities")];
        let want = match rules(&pointers, Some((t, self.offered)), &[p.input("params")]) {
            Some(w) => Err(w),
            None => {
                let pv = vector::<NP>(&p);
                let d = M::sensitivities(TaskKind::ALL[t as usize], &pv);
                let flat = d
                    .d_du
                    .iter()
                    .flat_map(|b| b.unwrap_or_else(SMatrix::zeros).as_slice().to_vec())
                    .collect();
                let want = results::<M, N, NX, NP, NZ>(&pv, vec![flat]);
                if want.is_ok() && !used_ptr.is_null() {
                    let flags: Vec<i32> = d.d_du.iter().map(|b| i32::from(b.is_some())).collect();
                    assert_eq!(&used[..TERMS], &flags[..], "toolconf_sensitivities: used");
                }
                want
            }
        };
        if want.is_err() || used_ptr.is_null() {
            assert!(
                used[..TERMS].iter().all(|u| *u == 0x5a5a_5a5a),
                "toolconf_sensitivities: used written"
            );
        }
        assert_eq!(
            used[TERMS], 0x5a5a_5a5a,
            "toolconf_sensitivities: used written past its end"
        );
        self.check("toolconf_sensitivities", code, want, &[&s]);
    }

    /// `toolconf_pi_u` (`gradient` false) or `toolconf_logdet_gradient`.
    fn pi_u(&mut self, gradient: bool) {
        let (t, tool) = (self.task(), self.tool());
        let (_, precision) = self.goals_and_precisions(t);
        let (p, pr) = (self.array(&tool), self.array(&precision));
        let mut out = self.out(if gradient { NP } else { N * N });
        let (code, name, out_name) = match gradient {
            false => (
                unsafe { (self.e.pi_u)(t, p.ptr(), pr.ptr(), out.ptr_mut()) },
                "toolconf_pi_u",
                "pi_u",
            ),
            true => (
                unsafe { (self.e.logdet_gradient)(t, p.ptr(), pr.ptr(), out.ptr_mut()) },
                "toolconf_logdet_gradient",
                "gradient",
            ),
        };
        let pointers = [p.arg("params"), pr.arg("precisions"), out.arg(out_name)];
        let inputs = [p.input("params"), pr.input("precisions")];
        let want = match rules(&pointers, Some((t, self.offered)), &inputs) {
            Some(w) => Err(w),
            None => {
                let pv = vector::<NP>(&p);
                let task = task_of::<N>(t, None, &pr);
                let v = match gradient {
                    false => M::pi_u(&task, &pv).as_slice().to_vec(),
                    true => M::logdet_gradient(&task, &pv).as_slice().to_vec(),
                };
                results::<M, N, NX, NP, NZ>(&pv, vec![v])
            }
        };
        self.check(name, code, want, &[&out]);
    }

    fn control_confidence(&mut self) {
        let (t, tool) = (self.task(), self.tool());
        let (goal, precision) = self.goals_and_precisions(t);
        let (p, g, pr) = (self.array(&tool), self.array(&goal), self.array(&precision));
        let (mut pi, mut logdet) = (self.out(N * N), self.out(1));
        let code = unsafe {
            (self.e.control_confidence)(
                t,
                p.ptr(),
                g.ptr(),
                pr.ptr(),
                pi.ptr_mut(),
                logdet.ptr_mut(),
            )
        };
        let pointers = [
            p.arg("params"),
            g.arg("goals"),
            pr.arg("precisions"),
            pi.arg("pi_u"),
            logdet.arg("logdet"),
        ];
        let inputs = [p.input("params"), g.input("goals"), pr.input("precisions")];
        let want = match rules(&pointers, Some((t, self.offered)), &inputs) {
            Some(w) => Err(w),
            None => {
                let pv = vector::<NP>(&p);
                let task = task_of::<N>(t, Some(&g), &pr);
                ToolN::<M, N, NX, NP, NZ>::new(pv.into())
                    .and_then(|tool| control_confidence(&tool, &task))
                    .map_err(|e| (status_of(&e), String::new()))
                    .and_then(|c| {
                        results::<M, N, NX, NP, NZ>(
                            &pv,
                            vec![c.pi_u.as_slice().to_vec(), vec![c.logdet]],
                        )
                    })
                    // ln|Π^U| is the library's libm's: finite, its bits not compared.
                    .map(|mut o| {
                        o[1] = None;
                        o
                    })
            }
        };
        self.check("toolconf_control_confidence", code, want, &[&pi, &logdet]);
    }

    /// The five getters: any status code has a name; the strings and metadata are there.
    fn getters(&mut self) {
        let e = self.e;
        assert_eq!((e.abi_version)(), crate::ABI_VERSION);
        assert_eq!(c_str((e.tasks_fingerprint)()), crate::fingerprint::hex());
        assert!(!(e.model_info)().is_null() && !(e.last_error)().is_null());
        let code = match self.rng.below(3) {
            0 => self.rng.next_u64() as i32,
            _ => self.rng.below(status::NAMES.len() + 2) as i32 - 1,
        };
        let want = status::name(code).to_str().unwrap_or("");
        assert_eq!(
            c_str((e.status_name)(code)),
            want,
            "toolconf_status_name({code})"
        );
        self.calls += 1;
    }
}
