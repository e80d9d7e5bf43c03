//! The model's metadata as C structs (`toolconf_model_info()`): everything in the generated
//! `ModelInfo`, with counts, C strings and flat arrays, built once from it on first use and
//! kept for the life of the library.

use core::ffi::c_char;
use std::ffi::CString;
use std::sync::OnceLock;

use toolconf_core::generated::{ModelInfo as Generated, MODELS};
use toolconf_core::{ArmModel, TaskKind, Term};

/// One tool parameter's domain: finite, between `lo` and `hi`, each end open (nonzero) or
/// closed; an infinite end is no bound. `toolconf_domain`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct Domain {
    pub lo: f64,
    pub hi: f64,
    pub lo_open: i32,
    pub hi_open: i32,
    /// The domain in words.
    pub rule: *const c_char,
}

/// A constraint c · p ≤ 0 across the tool parameters (`parameter_count` coefficients).
/// `toolconf_constraint`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct Constraint {
    pub coefficients: *const f64,
    pub rule: *const c_char,
}

/// The parameters that are a rigid body's inertia tensor (indices of the moments xx, yy, zz
/// and the products xy, xz, yz), whose second moment ½ tr(I)·1 − I must be positive
/// semi-definite to the relative `slack`. `toolconf_inertia_rule`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct InertiaRule {
    pub moments: [u32; 3],
    pub products: [u32; 3],
    pub slack: f64,
    pub rule: *const c_char,
}

/// Everything the generated `ModelInfo` holds, for C. Arrays have the count named beside them;
/// every pointer stays valid while the library is loaded. `toolconf_metadata`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ModelInfo {
    /// [`crate::ABI_VERSION`] again, for a reader of the struct alone.
    pub abi_version: u32,
    pub name: *const c_char,
    pub title: *const c_char,
    /// The model description it was derived from.
    pub description: *const c_char,
    /// N, the joints (torques).
    pub dof: usize,
    /// NX = 2N, the state X = [q; q̇].
    pub state_dim: usize,
    /// NP, the tool parameters.
    pub parameter_count: usize,
    /// The tip's components a tip task uses (≤ 3); its rows of the N slots.
    pub tip_dim: usize,
    /// Nonzero if the model's tools have a tip (`toolconf_tip` succeeds).
    pub has_tip: i32,
    /// `parameter_count` names and units, in the order every function takes them.
    pub parameter_names: *const *const c_char,
    pub parameter_units: *const *const c_char,
    /// `state_dim` names.
    pub state_names: *const *const c_char,
    /// `dof` names.
    pub control_names: *const *const c_char,
    /// `parameter_count` domains.
    pub domains: *const Domain,
    pub constraint_count: usize,
    pub constraints: *const Constraint,
    /// `parameter_count` each: the box random tools are drawn from.
    pub sample_lo: *const f64,
    pub sample_hi: *const f64,
    /// `parameter_count` each: nonzero where a tools file may leave the parameter out, and
    /// then its value (NaN where it is required).
    pub has_default: *const i32,
    pub defaults: *const f64,
    /// Nonzero if `inertia` holds.
    pub has_inertia: i32,
    pub inertia: InertiaRule,
    /// X^e (`state_dim`) and U^e (`dof`).
    pub equilibrium_state: *const f64,
    pub equilibrium_control: *const f64,
    /// Every task of the task list, by index (the `task` argument of the task functions).
    pub task_count: usize,
    pub task_names: *const *const c_char,
    /// `task_count`: nonzero where the model offers the task.
    pub task_offered: *const i32,
    /// The free-energy terms, by index (the blocks of goals, precisions, sensitivities).
    pub term_count: usize,
    pub term_names: *const *const c_char,
    /// `toolconf_tasks_fingerprint()`.
    pub tasks_fingerprint: *const c_char,
}

/// The owned storage behind one [`ModelInfo`]: its pointers point into these.
#[derive(Debug)]
pub struct InfoStorage {
    info: ModelInfo,
    _strings: Vec<CString>,
    _lists: Vec<Vec<*const c_char>>,
    _numbers: Vec<Vec<f64>>,
    _flags: Vec<Vec<i32>>,
    _domains: Vec<Domain>,
    _constraints: Vec<Constraint>,
}

// SAFETY: the storage is built once and never changed; its raw pointers point into its own heap
// allocations (or at 'static data), which do not move when the storage does.
unsafe impl Send for InfoStorage {}
unsafe impl Sync for InfoStorage {}

/// The generated `ModelInfo` of the model named `name`.
pub fn generated(name: &str) -> Option<&'static Generated> {
    MODELS.iter().find(|m| m.name == name)
}

struct Builder {
    strings: Vec<CString>,
    lists: Vec<Vec<*const c_char>>,
    numbers: Vec<Vec<f64>>,
    flags: Vec<Vec<i32>>,
}

impl Builder {
    fn string(&mut self, s: &str) -> *const c_char {
        // A NUL cannot be in a C string: shown as a space (a name never has one).
        let c = CString::new(s.replace('\0', " ")).unwrap_or_default();
        let p = c.as_ptr();
        self.strings.push(c);
        p
    }

    fn list<'a>(&mut self, items: impl IntoIterator<Item = &'a str>) -> *const *const c_char {
        let pointers: Vec<*const c_char> = items.into_iter().map(|s| self.string(s)).collect();
        let p = pointers.as_ptr();
        self.lists.push(pointers);
        p
    }

    fn numbers(&mut self, values: impl IntoIterator<Item = f64>) -> *const f64 {
        let v: Vec<f64> = values.into_iter().collect();
        let p = v.as_ptr();
        self.numbers.push(v);
        p
    }

    fn flags(&mut self, values: impl IntoIterator<Item = bool>) -> *const i32 {
        let v: Vec<i32> = values.into_iter().map(i32::from).collect();
        let p = v.as_ptr();
        self.flags.push(v);
        p
    }
}

impl Builder {
    /// The tool's rule of `g` as C sees it: its domains, constraints and inertia rule (zeros
    /// and an empty rule for a model without one).
    fn tool_rule(&mut self, g: &Generated) -> (Vec<Domain>, Vec<Constraint>, InertiaRule) {
        let domains: Vec<Domain> = g
            .domains
            .iter()
            .map(|d| Domain {
                lo: d.lo,
                hi: d.hi,
                lo_open: d.lo_open.into(),
                hi_open: d.hi_open.into(),
                rule: self.string(d.rule),
            })
            .collect();
        let constraints: Vec<Constraint> = g
            .constraints
            .iter()
            .map(|c| Constraint {
                coefficients: self.numbers(c.coefficients.iter().copied()),
                rule: self.string(c.rule),
            })
            .collect();
        let index = |i: usize| u32::try_from(i).unwrap_or(u32::MAX);
        let inertia = match g.inertia {
            Some(r) => InertiaRule {
                moments: r.moments.map(index),
                products: r.products.map(index),
                slack: r.slack,
                rule: self.string(r.rule),
            },
            None => InertiaRule {
                moments: [0; 3],
                products: [0; 3],
                slack: 0.0,
                rule: self.string(""),
            },
        };
        (domains, constraints, inertia)
    }
}

/// Builds the metadata of model `M` from its generated `ModelInfo` (the one named `M::name()`).
pub fn build<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>() -> InfoStorage
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let g = generated(M::name())
        .unwrap_or_else(|| panic!("no generated ModelInfo named {}", M::name()));
    let mut b = Builder {
        strings: Vec::new(),
        lists: Vec::new(),
        numbers: Vec::new(),
        flags: Vec::new(),
    };
    let (domains, constraints, inertia) = b.tool_rule(g);
    let info = ModelInfo {
        abi_version: crate::ABI_VERSION,
        name: b.string(g.name),
        title: b.string(g.title),
        description: b.string(g.description),
        dof: g.dof,
        state_dim: g.state_dim,
        parameter_count: g.parameter_names.len(),
        tip_dim: g.tip_dim,
        has_tip: g.has_tip.into(),
        parameter_names: b.list(g.parameter_names.iter().copied()),
        parameter_units: b.list(g.parameter_units.iter().copied()),
        state_names: b.list(g.state_names.iter().copied()),
        control_names: b.list(g.control_names.iter().copied()),
        domains: domains.as_ptr(),
        constraint_count: constraints.len(),
        constraints: constraints.as_ptr(),
        sample_lo: b.numbers(g.sample.iter().map(|s| s.0)),
        sample_hi: b.numbers(g.sample.iter().map(|s| s.1)),
        has_default: b.flags(g.defaults.iter().map(Option::is_some)),
        defaults: b.numbers(g.defaults.iter().map(|d| d.unwrap_or(f64::NAN))),
        has_inertia: g.inertia.is_some().into(),
        inertia,
        equilibrium_state: b.numbers(g.equilibrium_state.iter().copied()),
        equilibrium_control: b.numbers(g.equilibrium_control.iter().copied()),
        task_count: TaskKind::ALL.len(),
        task_names: b.list(TaskKind::ALL.iter().map(|k| k.name())),
        task_offered: b.flags(TaskKind::ALL.iter().map(|k| g.tasks.contains(k))),
        term_count: Term::ALL.len(),
        term_names: b.list(Term::ALL.iter().map(|t| t.name())),
        tasks_fingerprint: crate::fingerprint::c_hex().as_ptr(),
    };
    InfoStorage {
        info,
        _strings: b.strings,
        _lists: b.lists,
        _numbers: b.numbers,
        _flags: b.flags,
        _domains: domains,
        _constraints: constraints,
    }
}

/// `toolconf_model_info()` of model `M`, built into `cell` on first use; NULL (with the
/// message) if building it failed, which it does not for a generated model.
pub fn model_info<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    cell: &'static OnceLock<InfoStorage>,
) -> *const ModelInfo
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let built = std::panic::catch_unwind(|| {
        let storage = cell.get_or_init(build::<M, N, NX, NP, NZ>);
        &storage.info as *const ModelInfo
    });
    built.unwrap_or_else(|_| {
        crate::status::fail(
            crate::status::INTERNAL,
            format_args!("toolconf_model_info: the metadata could not be built"),
        );
        core::ptr::null()
    })
}
