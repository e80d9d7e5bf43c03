//! [`Generated`]: the [`Model`] of every generated model, one generic struct over
//! [`ArmModel`]. Each method dispatches once, then runs the const-generic runtime.

use std::marker::PhantomData;
use std::sync::Arc;

use nalgebra::SVector;
use rayon::prelude::*;

use super::results::{components, push_c_order, room, rows, BatchError};
use super::{
    AnyEpisode, BoundTask, Confidences, Linearisation, Model, ModelInfo, Rows, TaskTrace,
    TrajectoryTable,
};
use crate::closed_loop::EpisodeOptions;
use crate::inputs::task_file::{TaskFileError, TaskSpec};
use crate::model::{
    control_confidence, episode, simulate, ArmModel, EpisodeOptionsN, Metrics,
    ModelSimulationError, TaskN, ToolN, ValidatedTaskN,
};
use crate::prediction::{self, LinearSystem, Prediction, PredictionError};
use crate::validate::finite_output;
use crate::{Error, TaskKind, Term};
use toolconf_generated as generated;
use toolconf_generated::TERMS;

/// Below this many tools a batch of confidences runs on one thread: spreading it costs more
/// than it saves.
const MIN_TOOLS_PER_THREAD: usize = 256;
/// Below this many states a batch of rigid-body dynamics runs on one thread.
const MIN_STATES_PER_THREAD: usize = 512;

/// Model `M` as a [`Model`], with its metadata: a generated model's entry of
/// `generated::MODELS`, or a loaded model library's (`crate::loaded`).
pub(crate) struct Generated<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> {
    info: &'static ModelInfo,
    model: PhantomData<M>,
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>
    Generated<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    pub(crate) const fn new(info: &'static ModelInfo) -> Self {
        Self {
            info,
            model: PhantomData,
        }
    }
}

/// `params` as a tool of `M`: the count first, then the model's rule ([`ToolN::new`]).
fn tool<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    params: &[f64],
) -> Result<ToolN<M, N, NX, NP, NZ>, Error>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let params: [f64; NP] = params.try_into().map_err(|_| Error::ParameterCount {
        model: M::name(),
        expected: NP,
        names: M::parameter_names().join(","),
        found: params.len(),
    })?;
    Ok(ToolN::new(params)?)
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Model
    for Generated<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn info(&self) -> &'static ModelInfo {
        self.info
    }

    fn check_tool(&self, params: &[f64]) -> Result<(), Error> {
        tool::<M, N, NX, NP, NZ>(params).map(|_| ())
    }

    fn bind(&self, spec: &TaskSpec) -> Result<Arc<dyn BoundTask>, TaskFileError> {
        let (task, offset) = spec.task_and_offset::<M, N, NX, NP, NZ>()?;
        Ok(Arc::new(TaskOn::<M, N, NX, NP, NZ> {
            kind: spec.kind,
            validated: task.validated().map_err(Error::from),
            task,
            offset,
            options: spec.episode::<M, N, NX, NP, NZ>(),
            model: PhantomData,
        }))
    }

    fn paper_evaluation(
        &self,
        params: &[f64],
        kind: TaskKind,
        common: &EpisodeOptions,
    ) -> (Result<f64, Error>, Result<Metrics, ModelSimulationError>) {
        let tool = match tool::<M, N, NX, NP, NZ>(params) {
            Ok(tool) => tool,
            Err(e) => return (Err(e.clone()), Err(e.into())),
        };
        let task = M::paper_task(kind);
        let options = paper_options::<M, N, NX, NP, NZ>(common);
        (
            control_confidence(&tool, &task)
                .map(|c| c.logdet)
                .map_err(Error::from),
            simulate(&tool, &task, &options),
        )
    }

    fn rigid_body_dynamics(
        &self,
        k: usize,
        params: &Rows,
        x: &Rows,
        u: &Rows,
        out: &mut [f64],
    ) -> Result<(), BatchError> {
        let tools = tool_rows::<M, N, NX, NP, NZ>(k, params)?;
        for (i, v) in x.data.iter().chain(u.data).enumerate() {
            if !v.is_finite() {
                let what = if i < x.data.len() { "state" } else { "control" };
                return Err(BatchError::Input(format!("{what} entry {v} is not finite")));
            }
        }
        out.par_chunks_exact_mut(NX)
            .with_min_len(MIN_STATES_PER_THREAD)
            .enumerate()
            .try_for_each(|(i, row)| {
                let tool = &tools[if params.shared { 0 } else { i }];
                let xi = SVector::<f64, NX>::from_column_slice(x.row(i));
                let ui = SVector::<f64, N>::from_column_slice(u.row(i));
                let f = tool.rigid_body_dynamics(&xi, &ui);
                if !f.iter().all(|v| v.is_finite()) {
                    return Err(BatchError::Input(format!(
                        "state {i}: the dynamics are not finite there (|X| or |U| too large)"
                    )));
                }
                row.copy_from_slice(f.as_slice());
                Ok(())
            })
    }

    fn tip(
        &self,
        k: usize,
        params: &Rows,
        q: &Rows,
        position: &mut [f64],
        jacobian: &mut [f64],
    ) -> Result<(), BatchError> {
        let tools = tool_rows::<M, N, NX, NP, NZ>(k, params)?;
        if let Some(v) = q.data.iter().find(|v| !v.is_finite()) {
            return Err(BatchError::Input(format!(
                "joint position {v} is not finite"
            )));
        }
        position
            .par_chunks_exact_mut(3)
            .zip(jacobian.par_chunks_exact_mut(3 * N))
            .with_min_len(MIN_STATES_PER_THREAD)
            .enumerate()
            .try_for_each(|(i, (y_row, j_row))| {
                let tool = &tools[if params.shared { 0 } else { i }];
                let qi = SVector::<f64, N>::from_column_slice(q.row(i));
                let Some((y, j)) = tool.tip(&qi) else {
                    return Err(BatchError::Input(format!(
                        "model {} has no tip (its description gives none)",
                        M::name()
                    )));
                };
                if !(y.iter().chain(j.iter()).all(|v| v.is_finite())) {
                    return Err(BatchError::Input(format!(
                        "state {i}: the tip is not finite there (|q| too large)"
                    )));
                }
                y_row.copy_from_slice(y.as_slice());
                // Row major, as the batch's other arrays: J[r][c] at r·N + c.
                for r in 0..3 {
                    for c in 0..N {
                        j_row[r * N + c] = j[(r, c)];
                    }
                }
                Ok(())
            })
    }

    fn tip_bias(
        &self,
        k: usize,
        params: &Rows,
        q: &Rows,
        q_dot: &Rows,
        bias: &mut [f64],
    ) -> Result<(), BatchError> {
        let tools = tool_rows::<M, N, NX, NP, NZ>(k, params)?;
        let named = [("joint position", q), ("joint velocity", q_dot)];
        for (what, rows) in named {
            if let Some(v) = rows.data.iter().find(|v| !v.is_finite()) {
                return Err(BatchError::Input(format!("{what} {v} is not finite")));
            }
        }
        bias.par_chunks_exact_mut(3)
            .with_min_len(MIN_STATES_PER_THREAD)
            .enumerate()
            .try_for_each(|(i, row)| {
                let tool = &tools[if params.shared { 0 } else { i }];
                let qi = SVector::<f64, N>::from_column_slice(q.row(i));
                let vi = SVector::<f64, N>::from_column_slice(q_dot.row(i));
                let Some(b) = M::tip_bias(&qi, &vi, &tool.params()) else {
                    return Err(BatchError::Input(format!(
                        "model {} has no tip (its description gives none)",
                        M::name()
                    )));
                };
                if !b.iter().all(|v| v.is_finite()) {
                    return Err(BatchError::Input(format!(
                        "state {i}: the tip's acceleration is not finite there (|q| or |q_dot| too large)"
                    )));
                }
                row.copy_from_slice(b.as_slice());
                Ok(())
            })
    }
}

/// The tools of a batch's `params` rows (one shared by every row, or one per row), each checked
/// by the model's rule; the error names the row.
fn tool_rows<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    k: usize,
    params: &Rows,
) -> Result<Vec<ToolN<M, N, NX, NP, NZ>>, BatchError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let count = if params.shared { 1 } else { k };
    let mut tools = room(count, count)?;
    for i in 0..count {
        let tool = tool::<M, N, NX, NP, NZ>(params.row(i)).map_err(|e| {
            BatchError::Input(if params.shared || k == 1 {
                e.to_string()
            } else {
                format!("tool {i}: {e}")
            })
        })?;
        tools.push(tool);
    }
    Ok(tools)
}

/// `common`'s horizon, grid, perturbation, learning rate, integrator and recording, with model
/// `M`'s equilibrium as X0 and U0 = `common.u0[0]` on every joint (0.1 by default).
/// `common.x0` and `common.plant` are not used.
pub fn paper_options<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    common: &EpisodeOptions,
) -> EpisodeOptionsN<N, NX>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    EpisodeOptionsN {
        t_end: common.t_end,
        dt: common.dt,
        x0: M::equilibrium_state(),
        u0: SVector::repeat(common.u0[0]),
        perturbation: common.perturbation,
        joint_perturbation: SVector::zeros(),
        learning_rate: common.learning_rate,
        integrator: common.integrator,
        record_trajectory: common.record_trajectory,
    }
}

/// A task spec bound to model `M` ([`Model::bind`]).
#[derive(Debug)]
struct TaskOn<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> {
    kind: TaskKind,
    task: TaskN<N>,
    /// A tip goal relative to each tool's tip where the episode starts
    /// ([`crate::inputs::task_file::TipGoal::Offset`]); `task`'s tip goal is then resolved per tool.
    offset: Option<SVector<f64, N>>,
    validated: Result<ValidatedTaskN<N>, Error>,
    options: Result<EpisodeOptionsN<N, NX>, TaskFileError>,
    model: PhantomData<M>,
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> TaskOn<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn validated(&self) -> Result<&ValidatedTaskN<N>, Error> {
        self.validated.as_ref().map_err(Clone::clone)
    }

    fn options(&self) -> Result<&EpisodeOptionsN<N, NX>, ModelSimulationError> {
        self.options
            .as_ref()
            .map_err(|e| ModelSimulationError::Input(Error::Unsupported(e.to_string())))
    }

    /// The task `tool` runs: with a relative tip goal, resolved at the tool's own initial tip.
    fn task_for(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> Result<std::borrow::Cow<'_, TaskN<N>>, ModelSimulationError> {
        let Some(offset) = &self.offset else {
            return Ok(std::borrow::Cow::Borrowed(&self.task));
        };
        let q0 = self.options()?.x0.fixed_rows::<N>(0).into_owned();
        let task = crate::inputs::task_file::at_initial_tip(&self.task, offset, tool, &q0)?;
        Ok(std::borrow::Cow::Owned(task))
    }

    /// The task (goals resolved for `tool`) and options a prediction of its episode takes.
    fn prediction_inputs(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> Result<(TaskN<N>, &EpisodeOptionsN<N, NX>), PredictionError> {
        let input = |e: ModelSimulationError| match e {
            ModelSimulationError::Input(e) => PredictionError::Input(e),
            other => PredictionError::Input(Error::Unsupported(other.to_string())),
        };
        self.validated()?;
        let task = self.task_for(tool).map_err(input)?.into_owned();
        Ok((task, self.options().map_err(input)?))
    }

    fn recorded(&self) -> Result<EpisodeOptionsN<N, NX>, ModelSimulationError> {
        Ok(EpisodeOptionsN {
            record_trajectory: true,
            ..*self.options()?
        })
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> BoundTask
    for TaskOn<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn kind(&self) -> TaskKind {
        self.kind
    }

    fn episode_error(&self) -> Option<&TaskFileError> {
        self.options.as_ref().err()
    }

    fn validation_error(&self) -> Option<&Error> {
        self.validated.as_ref().err()
    }

    fn logdet(&self, params: &[f64]) -> Result<f64, Error> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        Ok(self.validated()?.control_confidence(&tool)?.logdet)
    }

    fn logdet_and_gradient(&self, params: &[f64]) -> Result<(f64, Vec<f64>), Error> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        let task = self.validated()?;
        let logdet = task.control_confidence(&tool)?.logdet;
        Ok((logdet, task.logdet_gradient(&tool).as_slice().to_vec()))
    }

    fn linearisation(&self, params: &[f64]) -> Result<Linearisation, Error> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        let c = self.validated()?.control_confidence(&tool)?;
        let s = tool.sensitivities(self.kind);
        let sensitivities = Term::ALL
            .into_iter()
            .filter_map(|term| {
                // A tip term's sensitivity J ∂θ/∂U: its first TIP_DIM rows (the rest are padding).
                let own = toolconf_core::term_components(term, N, M::tip_dim());
                s.of(term).map(|m| {
                    (
                        term.sensitivity_name(),
                        rows(&m).into_iter().take(own).collect(),
                    )
                })
            })
            .collect();
        Ok(Linearisation {
            a: rows(&tool.state_matrix()),
            b: rows(&tool.input_matrix()),
            sensitivities,
            pi_u: rows(&c.pi_u),
            logdet: c.logdet,
        })
    }

    fn predict(&self, params: &[f64]) -> Result<Prediction, PredictionError> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        let (task, options) = self.prediction_inputs(&tool)?;
        prediction::predict(&tool, &task, options)
    }

    fn linear_system(&self, params: &[f64]) -> Result<LinearSystem, PredictionError> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        let (task, options) = self.prediction_inputs(&tool)?;
        let linear = prediction::linearise(&tool, &task, options)?;
        Ok(LinearSystem::new(&linear, &task, options))
    }

    fn confidences(&self, params: &[f64]) -> Result<Confidences, BatchError> {
        let task = self.validated().map_err(|e| BatchError::Tool(0, e))?;
        confidences::<M, N, NX, NP, NZ>(task, params)
    }

    fn simulate(&self, params: &[f64]) -> Result<Metrics, ModelSimulationError> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        simulate(&tool, &*self.task_for(&tool)?, self.options()?)
    }

    fn episode(&self, params: &[f64], record: bool) -> Result<AnyEpisode, ModelSimulationError> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        let options = EpisodeOptionsN {
            record_trajectory: record,
            ..*self.options()?
        };
        let e = episode(&tool, &*self.task_for(&tool)?, &options)?;
        Ok(AnyEpisode {
            metrics: e.metrics,
            perturbation: options.total_perturbation().iter().copied().collect(),
            trajectory: e.trajectory.as_ref().map(TrajectoryTable::from_trajectory),
        })
    }

    fn trace(&self, params: &[f64]) -> Result<TaskTrace, ModelSimulationError> {
        let tool = tool::<M, N, NX, NP, NZ>(params)?;
        let task = &*self.task_for(&tool)?;
        let tr = episode(&tool, task, &self.recorded()?)?
            .trajectory
            .expect("a recorded episode has a trajectory");
        let term = self.kind.error_term();
        let (series, goal, count) = (tr.of(term), task.goal(term), tr.components(term));
        let tip = Term::ALL
            .into_iter()
            .find(|t| matches!(t.read(), generated::Read::Tip { order: 0 }));
        let tip_path = tip
            .filter(|&t| tr.components(t) > 0)
            .map(|t| components(tr.of(t), tr.components(t)));
        Ok(TaskTrace {
            t: tr.t.clone(),
            value: components(series, count),
            goal: goal.iter().take(count).copied().collect(),
            tip_path,
            joints: components(tr.of(Term::Theta), N),
        })
    }
}

/// One tool's matrices (on the stack: a batch allocates only its output arrays).
struct One<const N: usize, const NX: usize> {
    a: nalgebra::SMatrix<f64, NX, NX>,
    b: nalgebra::SMatrix<f64, NX, N>,
    sensitivities: crate::model::SensitivitiesN<N>,
    pi_u: nalgebra::SMatrix<f64, N, N>,
    logdet: f64,
}

impl<const N: usize, const NX: usize> One<N, NX> {
    /// Every number finite ([`finite_output`]), naming the tool only when one is not: a batch
    /// checks millions.
    fn check_finite<M, const NP: usize, const NZ: usize>(
        &self,
        tool: &ToolN<M, N, NX, NP, NZ>,
    ) -> Result<(), Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let s = &self.sensitivities;
        let sensitivities = s.d_du;
        let finite = |m: &[f64]| m.iter().all(|v| v.is_finite());
        if finite(self.a.as_slice())
            && finite(self.b.as_slice())
            && finite(self.pi_u.as_slice())
            && self.logdet.is_finite()
            && sensitivities.iter().flatten().all(|m| finite(m.as_slice()))
        {
            return Ok(());
        }
        let tool = format!("{tool:?}");
        finite_output(&tool, "A", self.a.iter().copied())?;
        finite_output(&tool, "B", self.b.iter().copied())?;
        for m in sensitivities.iter().flatten() {
            finite_output(&tool, "a sensitivity", m.iter().copied())?;
        }
        finite_output(&tool, "Π^U", self.pi_u.iter().copied())?;
        finite_output(&tool, "ln|Π^U|", [self.logdet])
    }
}

/// Π^U = Σ Sᵀ P S + P^U (eq. control_conf), ln|Π^U|, A, B and the sensitivities of every tool in
/// `params` (k × NP, row major); rayon's threads share the tools, and the first bad tool in
/// order is the error. Bad tools are found before anything is allocated; the output is then
/// reserved whole, fallibly ([`BatchError::OutOfMemory`], never an abort), and the tools are
/// computed in chunks of [`CHUNK_BYTES`], so nothing else grows with k.
fn confidences<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    task: &ValidatedTaskN<N>,
    params: &[f64],
) -> Result<Confidences, BatchError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let kind = task.task().kind;
    let k = params.len() / NP;
    for (i, p) in params.chunks_exact(NP).enumerate() {
        tool::<M, N, NX, NP, NZ>(p).map_err(|e| BatchError::Tool(i, e))?;
    }
    // A term the task does not use has no sensitivity (the command line leaves it out too).
    let used = Term::ALL.map(|t| t.has_sensitivity() && kind.uses(t));
    let mut out = allocate(k, N, NX, used, M::tip_dim())?;
    let chunk = (CHUNK_BYTES / std::mem::size_of::<Result<One<N, NX>, Error>>()).max(1);
    for (c, tools) in params.chunks(chunk * NP).enumerate() {
        let mut results: Vec<Result<One<N, NX>, Error>> = room(tools.len() / NP, tools.len() / NP)?;
        tools
            .par_chunks_exact(NP)
            .with_min_len(MIN_TOOLS_PER_THREAD)
            .map(|p| {
                let tool = tool::<M, N, NX, NP, NZ>(p)?;
                let c = task.control_confidence(&tool)?;
                let one = One {
                    a: tool.state_matrix(),
                    b: tool.input_matrix(),
                    sensitivities: tool.sensitivities(kind),
                    pi_u: c.pi_u,
                    logdet: c.logdet,
                };
                one.check_finite(&tool)?;
                Ok(one)
            })
            .collect_into_vec(&mut results);
        for (j, r) in results.into_iter().enumerate() {
            let one = r.map_err(|e| BatchError::Tool(c * chunk + j, e))?;
            push(&mut out, &one);
        }
    }
    Ok(out)
}

/// The results of one chunk of tools, before they are copied into the output arrays.
const CHUNK_BYTES: usize = 8 << 20;

/// Room for k tools' results (the sensitivities of the `used` terms only, a tip term's its
/// `tip_dim` rows).
fn allocate(
    k: usize,
    n: usize,
    nx: usize,
    used: [bool; TERMS],
    tip_dim: usize,
) -> Result<Confidences, BatchError> {
    let rows = |term: Term| toolconf_core::term_components(term, n, tip_dim);
    let used_rows: usize = Term::ALL
        .into_iter()
        .zip(used)
        .filter(|(_, u)| *u)
        .map(|(t, _)| rows(t))
        .sum();
    // The error says what all the arrays need, not the one that failed.
    let per_tool = nx * nx + nx * n + (used_rows + n) * n + 1;
    let total = k.saturating_mul(per_tool);
    let part = |per_tool: usize| room(k.saturating_mul(per_tool), total);
    let mut sensitivities = Vec::new();
    for (term, used) in Term::ALL.into_iter().zip(used) {
        if used {
            sensitivities.push((term.sensitivity_name(), rows(term), part(rows(term) * n)?));
        }
    }
    Ok(Confidences {
        k,
        n,
        nx,
        a: part(nx * nx)?,
        b: part(nx * n)?,
        sensitivities,
        pi_u: part(n * n)?,
        logdet: part(1)?,
    })
}

/// Appends one tool's results (within the room [`allocate`] made).
fn push<const N: usize, const NX: usize>(out: &mut Confidences, one: &One<N, NX>) {
    push_c_order(&mut out.a, &one.a);
    push_c_order(&mut out.b, &one.b);
    push_c_order(&mut out.pi_u, &one.pi_u);
    out.logdet.push(one.logdet);
    let s = &one.sensitivities;
    let present = s.d_du.into_iter().flatten();
    for ((_, rows, all), m) in out.sensitivities.iter_mut().zip(present) {
        // A tip term's first rows: the rest are its padding (toolconf_core::TaskN).
        all.extend((0..*rows).flat_map(|i| (0..N).map(move |j| m[(i, j)])));
    }
}
