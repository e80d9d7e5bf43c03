//! [`Loaded`]: the [`ArmModel`] of a model library, one marker per size and slot, whose
//! functions call the library's exports through the [`Table`] its slot holds.
//!
//! The runtime is const-generic in the model's sizes, so a library can only be run by a marker
//! compiled for its sizes: [`SIZES`] lists them (every model of the repository's, and URDF arms
//! of 3 to 8 joints, each with two slots). Inside a call, nothing but the library's functions
//! differs from a built-in model: the same runtime code, the same generated code (compiled into
//! the library), so the same bits.

use std::sync::OnceLock;

use nalgebra::{SMatrix, SVector};
use toolconf_cabi::{status, Exports};

use super::Library;
use crate::registry::entry::Generated;
use crate::registry::{Model, ModelInfo};

use crate::model::{ArmModel, SensitivitiesN, TaskN};
use crate::TaskKind;
use toolconf_generated::validity::{LinearRule, ToolRule};
use toolconf_generated::TERMS;

/// What a loaded model's functions read: the library's exports and its metadata as the types
/// the runtime keeps for a built-in model.
pub(crate) struct Table<const N: usize, const NX: usize, const NP: usize> {
    pub exports: Exports,
    pub name: &'static str,
    pub parameter_names: [&'static str; NP],
    pub equilibrium_state: SVector<f64, NX>,
    pub equilibrium_control: SVector<f64, N>,
    pub tip_dim: usize,
    pub rule: ToolRule<NP>,
    /// [`ArmModel::paper_task`] per task (`TaskKind::ALL` order): the library's defaults.
    pub paper_tasks: [TaskN<N>; TaskKind::ALL.len()],
}

/// A model library loaded into slot `S` of the models with N joints and NP tool parameters
/// (one of [`SIZES`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Loaded<const N: usize, const NP: usize, const S: usize>;

/// `toolconf_dynamics` and `toolconf_rigid_body_dynamics`: (X, U, params) in, Ẋ out.
type XDot = unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64) -> i32;

/// `toolconf_pi_u` and `toolconf_logdet_gradient`: (task, params, the task's precisions) in.
type OfTask = unsafe extern "C" fn(u32, *const f64, *const f64, *mut f64) -> i32;

/// The index of `kind` in the C ABI (`TaskKind::ALL`, the same list by the fingerprint).
fn task_index(kind: TaskKind) -> u32 {
    TaskKind::ALL
        .iter()
        .position(|k| *k == kind)
        .unwrap_or(usize::MAX) as u32
}

/// `values` where the call succeeded, NaN where it did not: the library refuses a non-finite
/// input, where a built-in model's arithmetic would have carried it on; the runtime then
/// stops on the NaN as it would on the built-in model's result.
fn checked<const R: usize, const C: usize>(
    code: i32,
    values: SMatrix<f64, R, C>,
) -> SMatrix<f64, R, C> {
    if code == status::OK {
        values
    } else {
        SMatrix::repeat(f64::NAN)
    }
}

impl<const N: usize, const NX: usize, const NP: usize> Table<N, NX, NP> {
    /// The table of `library`, whose checked metadata is `info` (of these sizes).
    fn build(library: &Library, info: &'static ModelInfo) -> Result<Self, String> {
        let sized = |what: &str| format!("its metadata's {what} does not have the model's size");
        let rule = ToolRule {
            domains: info.domains.try_into().map_err(|_| sized("domains"))?,
            constraints: info
                .constraints
                .iter()
                .map(|c| {
                    Ok(LinearRule {
                        coefficients: c
                            .coefficients
                            .try_into()
                            .map_err(|_| sized("constraints"))?,
                        rule: c.rule,
                    })
                })
                .collect::<Result<Vec<_>, String>>()?
                .leak(),
            sample: info.sample.try_into().map_err(|_| sized("sample box"))?,
            defaults: info.defaults.try_into().map_err(|_| sized("defaults"))?,
            inertia: info.inertia,
        };
        let mut table = Table {
            exports: library.exports,
            name: info.name,
            parameter_names: info
                .parameter_names
                .try_into()
                .map_err(|_| sized("parameters"))?,
            equilibrium_state: SVector::from_column_slice(info.equilibrium_state),
            equilibrium_control: SVector::from_column_slice(info.equilibrium_control),
            tip_dim: info.tip_dim,
            rule,
            paper_tasks: TaskKind::ALL.map(|kind| TaskN {
                kind,
                goal: [SVector::zeros(); TERMS],
                precision: [SMatrix::zeros(); TERMS],
            }),
        };
        for kind in info.tasks {
            table.paper_tasks[task_index(*kind) as usize] = table.task_defaults(*kind)?;
        }
        Ok(table)
    }

    /// The library's default goals and precisions of `kind` ([`ArmModel::paper_task`]).
    fn task_defaults(&self, kind: TaskKind) -> Result<TaskN<N>, String> {
        let mut task = TaskN {
            kind,
            goal: [SVector::<f64, N>::zeros(); TERMS],
            precision: [SMatrix::<f64, N, N>::zeros(); TERMS],
        };
        // SAFETY: TERMS contiguous N-vectors and N × N matrices: the ABI's layout.
        let code = unsafe {
            (self.exports.task_defaults)(
                task_index(kind),
                task.goal.as_mut_ptr().cast::<f64>(),
                task.precision.as_mut_ptr().cast::<f64>(),
            )
        };
        let finite = task
            .goal
            .iter()
            .flatten()
            .chain(task.precision.iter().flatten());
        match code {
            status::OK if finite.into_iter().all(|v| v.is_finite()) => Ok(task),
            _ => Err(format!(
                "toolconf_task_defaults gave no finite defaults for the task {} it offers",
                kind.name()
            )),
        }
    }

    /// Ẋ by one of the two exports of that shape (the plant's dynamics, or the rigid body's).
    fn x_dot(
        &self,
        export: XDot,
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> SVector<f64, NX> {
        let mut out = SVector::<f64, NX>::zeros();
        // SAFETY: every pointer points to as many doubles as the ABI says (the sizes are the
        // library's, checked at loading); the library stays loaded for the process's life.
        let code = unsafe { export(x.as_ptr(), u.as_ptr(), p.as_ptr(), out.as_mut_ptr()) };
        checked(code, out)
    }

    fn dynamics_jacobian(
        &self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> (SMatrix<f64, NX, NX>, SMatrix<f64, NX, N>) {
        let (mut a, mut b) = (
            SMatrix::<f64, NX, NX>::zeros(),
            SMatrix::<f64, NX, N>::zeros(),
        );
        // SAFETY: as in `x_dot`.
        let code = unsafe {
            (self.exports.dynamics_jacobian)(
                x.as_ptr(),
                u.as_ptr(),
                p.as_ptr(),
                a.as_mut_ptr(),
                b.as_mut_ptr(),
            )
        };
        (checked(code, a), checked(code, b))
    }

    fn tip(
        &self,
        q: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<(SVector<f64, 3>, SMatrix<f64, 3, N>)> {
        let (mut y, mut j) = (SVector::<f64, 3>::zeros(), SMatrix::<f64, 3, N>::zeros());
        // SAFETY: as in `x_dot`.
        let code =
            unsafe { (self.exports.tip)(q.as_ptr(), p.as_ptr(), y.as_mut_ptr(), j.as_mut_ptr()) };
        match code {
            status::NO_TIP => None,
            _ => Some((checked(code, y), checked(code, j))),
        }
    }

    fn tip_bias(
        &self,
        q: &SVector<f64, N>,
        q_dot: &SVector<f64, N>,
        p: &SVector<f64, NP>,
    ) -> Option<SVector<f64, 3>> {
        let mut b = SVector::<f64, 3>::zeros();
        // SAFETY: as in `x_dot`.
        let code = unsafe {
            (self.exports.tip_bias)(q.as_ptr(), q_dot.as_ptr(), p.as_ptr(), b.as_mut_ptr())
        };
        match code {
            status::NO_TIP => None,
            _ => Some(checked(code, b)),
        }
    }

    fn state_matrix(&self, p: &SVector<f64, NP>) -> SMatrix<f64, NX, NX> {
        let mut a = SMatrix::<f64, NX, NX>::zeros();
        // SAFETY: as in `x_dot`.
        let code = unsafe { (self.exports.state_matrix)(p.as_ptr(), a.as_mut_ptr()) };
        checked(code, a)
    }

    fn input_matrix(&self, p: &SVector<f64, NP>) -> SMatrix<f64, NX, N> {
        let mut b = SMatrix::<f64, NX, N>::zeros();
        // SAFETY: as in `x_dot`.
        let code = unsafe { (self.exports.input_matrix)(p.as_ptr(), b.as_mut_ptr()) };
        checked(code, b)
    }

    fn sensitivities(&self, kind: TaskKind, p: &SVector<f64, NP>) -> SensitivitiesN<N> {
        let mut blocks = [SMatrix::<f64, N, N>::zeros(); TERMS];
        let mut used = [0i32; TERMS];
        // SAFETY: as in `dynamics`; an array of TERMS N × N matrices is TERMS·N·N contiguous
        // doubles, column-major each, the ABI's layout.
        let code = unsafe {
            (self.exports.sensitivities)(
                task_index(kind),
                p.as_ptr(),
                blocks.as_mut_ptr().cast::<f64>(),
                used.as_mut_ptr(),
            )
        };
        let d_du = core::array::from_fn(|t| match code {
            status::OK => (used[t] != 0).then_some(blocks[t]),
            _ => Some(SMatrix::repeat(f64::NAN)),
        });
        SensitivitiesN { d_du }
    }

    fn pi_u(&self, task: &TaskN<N>, p: &SVector<f64, NP>) -> SMatrix<f64, N, N> {
        self.of_task(self.exports.pi_u, task, p)
    }

    fn logdet_gradient(&self, task: &TaskN<N>, p: &SVector<f64, NP>) -> SVector<f64, NP> {
        self.of_task(self.exports.logdet_gradient, task, p)
    }

    /// What `export` (`toolconf_pi_u` or `toolconf_logdet_gradient`) gives for `task`'s kind
    /// and precisions and the tool's parameters `p`: an R × C matrix, NaN if the call failed.
    fn of_task<const R: usize, const C: usize>(
        &self,
        export: OfTask,
        task: &TaskN<N>,
        p: &SVector<f64, NP>,
    ) -> SMatrix<f64, R, C> {
        let mut out = SMatrix::<f64, R, C>::zeros();
        // SAFETY: as in `sensitivities`, for the precisions; `out` is the export's output size
        // (N × N for Π^U, NP for the gradient), as the callers' types say.
        let code = unsafe {
            export(
                task_index(task.kind),
                p.as_ptr(),
                task.precision.as_ptr().cast::<f64>(),
                out.as_mut_ptr(),
            )
        };
        checked(code, out)
    }
}

/// Implements [`ArmModel`] for `Loaded<N, S>` of one size, every slot: each function reads the
/// slot's table (filled before any model of the slot is handed out) and forwards.
macro_rules! loaded_model {
    ($n:literal, $nx:literal, $np:literal, $nz:literal, $slots:ident) => {
        static $slots: [OnceLock<Table<$n, $nx, $np>>; SLOTS] = [const { OnceLock::new() }; SLOTS];

        impl<const S: usize> Loaded<$n, $np, S> {
            #[inline]
            fn table() -> &'static Table<$n, $nx, $np> {
                $slots[S]
                    .get()
                    .expect("a loaded model's marker is used only once its slot is filled")
            }
        }

        impl<const S: usize> ArmModel<$n, $nx, $np, $nz> for Loaded<$n, $np, S> {
            type DynamicsCoefficients = SVector<f64, $np>;
            type JacobianCoefficients = SVector<f64, $np>;

            fn name() -> &'static str {
                Self::table().name
            }
            fn parameter_names() -> &'static [&'static str; $np] {
                &Self::table().parameter_names
            }
            fn equilibrium_state() -> SVector<f64, $nx> {
                Self::table().equilibrium_state
            }
            fn equilibrium_control() -> SVector<f64, $n> {
                Self::table().equilibrium_control
            }
            fn tip_dim() -> usize {
                Self::table().tip_dim
            }
            fn tool_rule() -> &'static ToolRule<$np> {
                &Self::table().rule
            }
            #[inline]
            fn dynamics_coefficients(p: &SVector<f64, $np>) -> Self::DynamicsCoefficients {
                *p
            }
            #[inline]
            fn jacobian_coefficients(p: &SVector<f64, $np>) -> Self::JacobianCoefficients {
                *p
            }
            #[inline]
            fn dynamics_with(
                x: &SVector<f64, $nx>,
                u: &SVector<f64, $n>,
                p: &Self::DynamicsCoefficients,
            ) -> SVector<f64, $nx> {
                let t = Self::table();
                t.x_dot(t.exports.dynamics, x, u, p)
            }
            #[inline]
            fn dynamics_jacobian_with(
                x: &SVector<f64, $nx>,
                u: &SVector<f64, $n>,
                p: &Self::JacobianCoefficients,
            ) -> (SMatrix<f64, $nx, $nx>, SMatrix<f64, $nx, $n>) {
                Self::table().dynamics_jacobian(x, u, p)
            }
            fn rigid_body_dynamics(
                x: &SVector<f64, $nx>,
                u: &SVector<f64, $n>,
                p: &SVector<f64, $np>,
            ) -> SVector<f64, $nx> {
                let t = Self::table();
                t.x_dot(t.exports.rigid_body_dynamics, x, u, p)
            }
            fn tip(
                q: &SVector<f64, $n>,
                p: &SVector<f64, $np>,
            ) -> Option<(SVector<f64, 3>, SMatrix<f64, 3, $n>)> {
                Self::table().tip(q, p)
            }
            fn tip_bias(
                q: &SVector<f64, $n>,
                q_dot: &SVector<f64, $n>,
                p: &SVector<f64, $np>,
            ) -> Option<SVector<f64, 3>> {
                Self::table().tip_bias(q, q_dot, p)
            }
            fn state_matrix(p: &SVector<f64, $np>) -> SMatrix<f64, $nx, $nx> {
                Self::table().state_matrix(p)
            }
            fn input_matrix(p: &SVector<f64, $np>) -> SMatrix<f64, $nx, $n> {
                Self::table().input_matrix(p)
            }
            fn sensitivities(kind: TaskKind, p: &SVector<f64, $np>) -> SensitivitiesN<$n> {
                Self::table().sensitivities(kind, p)
            }
            fn pi_u(task: &TaskN<$n>, p: &SVector<f64, $np>) -> SMatrix<f64, $n, $n> {
                Self::table().pi_u(task, p)
            }
            fn logdet_gradient(task: &TaskN<$n>, p: &SVector<f64, $np>) -> SVector<f64, $np> {
                Self::table().logdet_gradient(task, p)
            }
            fn paper_task(kind: TaskKind) -> TaskN<$n> {
                Self::table().paper_tasks[task_index(kind) as usize]
            }
        }
    };
}

/// Slots per size: how many libraries of the same sizes one process can load.
pub const SLOTS: usize = 2;

/// `Loaded<N, NP, S>` as a [`Model`] in the first free slot of `slots`, its table built from
/// `library`.
fn install_in<const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    slots: &'static [OnceLock<Table<N, NX, NP>>; SLOTS],
    library: &Library,
    info: &'static ModelInfo,
) -> Result<&'static dyn Model, String>
where
    Loaded<N, NP, 0>: ArmModel<N, NX, NP, NZ>,
    Loaded<N, NP, 1>: ArmModel<N, NX, NP, NZ>,
{
    let slot = slots
        .iter()
        .position(|s| s.get().is_none())
        .ok_or("every slot of its size is taken")?;
    if slots[slot].set(Table::build(library, info)?).is_err() {
        return Err("the slot was filled meanwhile (loads are serialised)".into());
    }
    let model: Box<dyn Model> = match slot {
        0 => Box::new(Generated::<Loaded<N, NP, 0>, N, NX, NP, NZ>::new(info)),
        _ => Box::new(Generated::<Loaded<N, NP, 1>, N, NX, NP, NZ>::new(info)),
    };
    Ok(Box::leak(model))
}

/// The marker types of every size in [`SIZES`], and [`install`] over them.
macro_rules! loaded_sizes {
    ($(($n:literal, $nx:literal, $np:literal, $nz:literal, $slots:ident)),* $(,)?) => {
        $(loaded_model!($n, $nx, $np, $nz, $slots);)*

        /// The sizes (N, NP) a library may have: every model of the repository's (the
        /// mass-spring-damper, the 2- and 3-link arms, the Panda, the UR5) and a URDF arm's
        /// (13 tool parameters) of 3 to 8 joints. Each size costs the runtime one more compiled
        /// copy of its generic code per slot, which is why the list is not longer.
        pub const SIZES: &[(usize, usize)] = &[$(($n, $np)),*];

        /// Whether a slot of the size (N, NP) is free.
        pub(crate) fn slot_free(size: (usize, usize)) -> bool {
            match size {
                $(($n, $np) => $slots.iter().any(|s| s.get().is_none()),)*
                _ => false,
            }
        }

        /// The loaded `library` as a [`Model`], in a free slot of its size (the loader checked
        /// both first: [`slot_free`]).
        pub(crate) fn install(
            library: &Library,
            info: &'static ModelInfo,
        ) -> Result<&'static dyn Model, String> {
            match (info.dof, info.parameter_names.len()) {
                $(($n, $np) => install_in::<$n, $nx, $np, $nz>(&$slots, library, info),)*
                _ => Err("a size this toolconf was not compiled for".into()),
            }
        }
    };
}

loaded_sizes!(
    (1, 2, 3, 3, SLOTS_1_3),
    (2, 4, 4, 6, SLOTS_2_4),
    (2, 4, 5, 6, SLOTS_2_5),
    (3, 6, 6, 9, SLOTS_3_6),
    (3, 6, 13, 9, SLOTS_3_13),
    (4, 8, 13, 12, SLOTS_4_13),
    (5, 10, 13, 15, SLOTS_5_13),
    (6, 12, 13, 18, SLOTS_6_13),
    (7, 14, 13, 21, SLOTS_7_13),
    (8, 16, 13, 24, SLOTS_8_13),
);
