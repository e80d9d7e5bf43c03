//! `import toolconf`: the toolconf runtime over NumPy arrays (the top layer; nothing in the crate
//! imports it).
//!
//! * [`confidence`]: A, B, the task's sensitivities, Π^U and ln|Π^U| of one tool or of many in
//!   one call (rayon, without the GIL).
//! * [`simulate`]: one closed-loop episode's metrics and trajectory, any generated model.
//! * [`rank`]: `toolconf rank` (screen by confidence, simulate, rank) as columns, of a tools
//!   file or of columns in memory ([`tools`]).
//! * [`batch`]: `simulate_batch`, the episodes of many tools under many perturbations.
//! * [`design`]: `toolconf design --json` as a dict.
//! * [`evaluate`]: `toolconf reproduce --model` (the paper's evaluation on any model, task and
//!   population) as tables and verdicts, whole or in the steps `toolconf.dask` spreads.
//! * [`dask_steps`]: the steps of `rank` that `toolconf.dask` spreads over a cluster.
//! * [`dynamics`]: a robot's own rigid-body dynamics Ẋ = [q̇; q̈] for one state or a batch, and
//!   its tool's tip with the tip's Jacobian (`tip`).
//! * [`tool_urdf`]: `toolconf tool --urdf`, a tool's tools-file row from its own URDF, as a dict.
//! * [`task`]: a task given as a built-in name, a task file or a dict with a task file's keys,
//!   all checked by the crate's task-file parser so errors name the key.
//!
//! Bad input raises `ValueError` with the one-line message the command line prints (`TypeError`
//! for a Python value of the wrong type: a bool, a complex or boolean array); an output that
//! does not fit in memory raises `MemoryError`; a failed episode raises
//! `toolconf.SimulationError` with `tool`, `time` and `reason`.

mod arrays;
mod batch;
mod confidence;
mod dask_steps;
mod design;
mod dynamics;
mod errors;
mod evaluate;
mod integers;
mod models;
mod rank;
mod simulate;
mod task;
mod tool_tables;
mod tool_urdf;
mod tools;

use pyo3::prelude::*;

/// Confidence-aware decision-making and control for tool selection (Anil Meera & Lanillos):
/// control confidence Π^U = ∂²F/∂U², closed-loop episodes of the active-inference controller,
/// and ranking of tools, for every model toolconf generates (see `toolconf.models()`).
#[pymodule]
fn _toolconf(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // RAYON_NUM_THREADS=5000 would start 5000 threads; the pool is capped as the command
    // line's is (toolconf::threads), with a warning.
    if let Some(note) = toolconf::threads::cap_pool() {
        let category = m.py().get_type::<pyo3::exceptions::PyRuntimeWarning>();
        PyErr::warn(m.py(), &category, &std::ffi::CString::new(note)?, 1)?;
    }
    m.add_function(wrap_pyfunction!(models::models, m)?)?;
    m.add_function(wrap_pyfunction!(models::load_model, m)?)?;
    m.add_function(wrap_pyfunction!(models::model_path_entries, m)?)?;
    m.add_function(wrap_pyfunction!(models::ranges, m)?)?;
    m.add_function(wrap_pyfunction!(models::terms, m)?)?;
    m.add_function(wrap_pyfunction!(confidence::confidence, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(rank::rank, m)?)?;
    m.add_function(wrap_pyfunction!(batch::simulate_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::simulate_batch_block, m)?)?;
    m.add_function(wrap_pyfunction!(design::design, m)?)?;
    m.add_function(wrap_pyfunction!(dask_steps::portable_task, m)?)?;
    m.add_function(wrap_pyfunction!(dask_steps::screen_block, m)?)?;
    m.add_function(wrap_pyfunction!(dask_steps::merge_screens, m)?)?;
    m.add_function(wrap_pyfunction!(dask_steps::episodes, m)?)?;
    m.add_function(wrap_pyfunction!(dask_steps::rank_table, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::dynamics, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::tip, m)?)?;
    m.add_function(wrap_pyfunction!(tool_urdf::tool_from_urdf, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::reproduce_plan, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::reproduce_population, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::reproduce_block, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::reproduce_finish, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::reproduce, m)?)?;
    m.add(
        "SimulationError",
        m.py().get_type::<errors::SimulationError>(),
    )?;
    Ok(())
}
