//! The MPC baseline on the same nonlinear plant as the active-inference loop: the controller
//! sees the state every control period and holds its torque (zero-order hold) while the plant
//! Ẋ = f(X, U + ΔT) is integrated; metrics are those of the active-inference episode.
//!
//! [`simulate_mpc_on`] is the implementation for any [`ArmModel`]; [`simulate_mpc`] and
//! [`SimulateMpc::simulate_mpc`] run it for the paper's arm on the plant chosen at run time, the errors
//! naming `arm m1=…`.

use std::time::Duration;

use nalgebra::SVector;

use super::{MpcError, MpcN, MpcOptions};
use toolconf_integrators::{solve_grid, IntegrationError};
use toolconf_model::closed_loop::{EpisodeOptions, Plant};
use toolconf_model::model::budget::{diagnosis, episode_budget};
use toolconf_model::model::{
    ActiveInferenceN, Arm2, Arm2Exact, ArmModel, EpisodeOptionsN, TaskN, ToolN, TrajectoryN,
};
use toolconf_model::{Arm, Error, Task};

/// What an MPC episode measures: the active-inference episode's metrics where they apply.
#[derive(Debug, Clone, PartialEq)]
pub struct MpcMetricsN<const N: usize> {
    /// Σ over the output grid of the task's weighted error (as for the active-inference loop).
    pub task_error: f64,
    /// ∫J dt, trapezoidal on the output grid: the cost the MPC achieves (objective J*).
    pub cost_j: f64,
    /// ∫J dt − ½ T ln|Π^U|: the free energy the same trajectory would have for the tool's
    /// control confidence (Π^U is a property of the tool and task, not of the controller).
    pub free_energy: f64,
    /// ∫|U|² dt, trapezoidal on the output grid.
    pub control_effort: f64,
    /// ln|Π^U| of the tool for the task.
    pub logdet: f64,
    /// Right-hand-side evaluations of the plant.
    pub rhs_evals: usize,
    /// One QP per control period, plus one at the final time.
    pub qp_solves: usize,
    pub qp_iterations: u64,
    pub median_solve_time: Duration,
    pub max_solve_time: Duration,
    /// `Solved`, or the first other accepted status (`AlmostSolved`).
    pub worst_status: String,
    /// The disturbance observer's final estimate d̂ [N m] (zero without the observer).
    pub disturbance_estimate: SVector<f64, N>,
}

/// The 2-link MPC metrics.
pub type MpcMetrics = MpcMetricsN<2>;

#[derive(Debug, Clone, PartialEq)]
pub struct MpcEpisodeN<const N: usize> {
    pub metrics: MpcMetricsN<N>,
    pub trajectory: Option<TrajectoryN<N>>,
}

/// The 2-link MPC episode.
pub type MpcEpisode = MpcEpisodeN<2>;

/// Why an MPC episode failed, before the tool is named (each public error names it its own
/// way, with the same time and reason).
enum MpcFailure {
    Input(Error),
    Setup(MpcError),
    Controller { t: f64, source: MpcError },
    Integration(IntegrationError),
}

impl From<Error> for MpcFailure {
    fn from(e: Error) -> Self {
        MpcFailure::Input(e)
    }
}

/// Why an MPC episode of the paper's arm failed ([`MpcSimulationError`], the tool named
/// `arm m1=…`).
pub type MpcEpisodeError = MpcSimulationError;

/// Why an MPC episode failed: bad input, or the MPC or the simulation of the named tool failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MpcSimulationError {
    #[error(transparent)]
    Input(#[from] Error),
    #[error("MPC for {tool}: {source}")]
    Setup { tool: String, source: MpcError },
    #[error("MPC for {tool} failed at t = {} s: {source}", toolconf_messages::Short(*t))]
    Controller {
        tool: String,
        t: f64,
        source: MpcError,
    },
    #[error("simulation of {tool} under MPC failed: {source}")]
    Integration {
        tool: String,
        source: IntegrationError,
    },
}

impl MpcSimulationError {
    fn named(failure: MpcFailure, tool: impl FnOnce() -> String) -> Self {
        match failure {
            MpcFailure::Input(e) => MpcSimulationError::Input(e),
            MpcFailure::Setup(source) => MpcSimulationError::Setup {
                tool: tool(),
                source,
            },
            MpcFailure::Controller { t, source } => MpcSimulationError::Controller {
                tool: tool(),
                t,
                source,
            },
            MpcFailure::Integration(source) => MpcSimulationError::Integration {
                tool: tool(),
                source,
            },
        }
    }
}

/// Runs the MPC baseline for one episode of the paper's 2-DOF arm on the paper's plant
/// ([`SimulateMpc::simulate_mpc`]).
pub fn simulate_mpc(
    arm: &Arm,
    task: &Task,
    options: &EpisodeOptions,
    mpc_options: &MpcOptions,
) -> Result<MpcEpisode, MpcEpisodeError> {
    Plant::Paper.simulate_mpc(arm, task, options, mpc_options)
}

/// The MPC baseline on a [`Plant`] chosen at run time (the plant is the model layer's; the MPC
/// is this crate's, hence a trait).
pub trait SimulateMpc {
    /// The MPC baseline for one episode of the paper's 2-DOF arm on this plant (matched once
    /// here), with the same options (horizon, grid, initial state, perturbation, integrator) as
    /// the active-inference episode. The output grid spacing must be a whole number of control
    /// periods. The paper's U0 is not used: the MPC chooses U at t = 0.
    fn simulate_mpc(
        self,
        arm: &Arm,
        task: &Task,
        options: &EpisodeOptions,
        mpc_options: &MpcOptions,
    ) -> Result<MpcEpisode, MpcEpisodeError>;
}

impl SimulateMpc for Plant {
    fn simulate_mpc(
        self,
        arm: &Arm,
        task: &Task,
        options: &EpisodeOptions,
        mpc_options: &MpcOptions,
    ) -> Result<MpcEpisode, MpcEpisodeError> {
        match self {
            Plant::Paper => run::<Arm2, Arm2, 2, 4, 4, 6>(arm, task, options, mpc_options),
            Plant::Exact => run::<Arm2, Arm2Exact, 2, 4, 4, 6>(arm, task, options, mpc_options),
        }
        .map_err(|failure| MpcSimulationError::named(failure, || format!("arm {arm}")))
    }
}

/// The MPC episode of `tool` (prediction model `M`) on `task`, simulated on plant model `P`
/// (`P = M` normally), with the same options as the active-inference episode
/// ([`toolconf_model::model::episode_on`]); as [`simulate_mpc`], U0 is not used.
pub fn simulate_mpc_on<M, P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
    mpc_options: &MpcOptions,
) -> Result<MpcEpisodeN<N>, MpcSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
    P: ArmModel<N, NX, NP, NZ>,
{
    run::<M, P, N, NX, NP, NZ>(tool, task, options, mpc_options)
        .map_err(|f| MpcSimulationError::named(f, || format!("{}({tool})", M::name())))
}

fn run<M, P, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
    mpc_options: &MpcOptions,
) -> Result<MpcEpisodeN<N>, MpcFailure>
where
    M: ArmModel<N, NX, NP, NZ>,
    P: ArmModel<N, NX, NP, NZ>,
{
    let (metrics_of, grid) = check_episode(tool, task, options, mpc_options)?;
    let mut mpc = MpcN::new(tool, task, mpc_options).map_err(MpcFailure::Setup)?;
    // The plant's parameter-only factors, once per episode (as the active-inference loop does).
    let plant = P::dynamics_coefficients(&tool.params());
    let mut log = SolveLog::with_capacity(grid.steps + 1);
    let mut sums = Samples::new(options.record_trajectory);
    let sample = |sums: &mut Samples<N>, t: f64, x: &SVector<f64, NX>, u: &SVector<f64, N>| {
        let x_dot = P::dynamics_with(x, &(u + grid.perturbation), &plant);
        sums.add(&metrics_of, t, toolconf_core::observe(x, &x_dot, u), u);
    };

    let mut x = options.x0;
    let mut u = log.control(&mut mpc, &x, 0.0)?;
    sample(&mut sums, 0.0, &x, &u);
    let mut rhs_evals = 0;
    // One work budget for the whole episode (a control period is at most an output step), shared
    // by the periods' integrations: what one period spends, the next may not.
    let mut integrator = options.integrator;
    let cap = integrator.max_steps;
    let budget = episode_budget(grid.steps as f64, integrator.rtol, integrator.atol, cap);
    let mut spent = 0;
    for k in 0..grid.steps {
        let (t0, t1) = (k as f64 * grid.period, (k + 1) as f64 * grid.period);
        let held = u + grid.perturbation;
        let mut next = x;
        integrator.max_steps = budget.saturating_sub(spent).max(1);
        let stats = solve_grid(
            |_, x: &SVector<f64, NX>| P::dynamics_with(x, &held, &plant),
            &x,
            &[t0, t1],
            &integrator,
            |i, _, y| {
                if i == 1 {
                    next = *y;
                }
            },
        )
        .map_err(|e| {
            MpcFailure::Integration(mpc_out_of_work::<N>(e, spent, budget < cap, options.dt))
        })?;
        spent += stats.steps + stats.rejected;
        rhs_evals += stats.rhs_evals;
        x = next;
        u = log.control(&mut mpc, &x, t1)?;
        if (k + 1) % grid.every == 0 {
            sample(&mut sums, t1, &x, &u);
        }
    }
    let metrics = sums.metrics(
        log,
        metrics_of.logdet,
        options.t_end,
        rhs_evals,
        mpc.disturbance_estimate(),
    );
    Ok(MpcEpisodeN {
        metrics,
        trajectory: sums.trajectory,
    })
}

/// The episode's control grid: `steps` control periods of `period` s, an output sample every
/// `every` of them, under the constant perturbation dT.
struct ControlGrid<const N: usize> {
    period: f64,
    steps: usize,
    every: usize,
    perturbation: SVector<f64, N>,
}

/// The refusals an MPC episode makes before it builds the controller, in the order the user
/// meets them (the task, the tool's Π^U, the grids, the perturbation), and what they leave:
/// the metrics' weights (an active-inference controller of the tool) and the control grid.
fn check_episode<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    task: &TaskN<N>,
    options: &EpisodeOptionsN<N, NX>,
    mpc_options: &MpcOptions,
) -> Result<(ActiveInferenceN<N>, ControlGrid<N>), MpcFailure>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    if toolconf_core::reads_tip(task.kind) {
        return Err(Error::Unsupported(format!(
            "the MPC baseline minimises J over the linearised joint state; the {} task reads the tool's tip, whose cost it does not model (run it with the active-inference controller)",
            task.kind
        ))
        .into());
    }
    let metrics_of = ActiveInferenceN::new(tool, task, 1.0).map_err(Error::from)?;
    // The QP log holds one entry per control period: refuse horizons too long to keep.
    for step in [options.dt, mpc_options.period] {
        if step > 0.0 {
            toolconf_model::model::check_grid(options.t_end, step)?;
        }
    }
    let period = mpc_options.period;
    let steps = whole_ratio(options.t_end, period).ok_or(Error::InvalidOption {
        name: "end time t_end (not a whole number of MPC periods)",
        value: options.t_end,
    })?;
    let every = whole_ratio(options.dt, period).ok_or(Error::InvalidOption {
        name: "output step dt (not a whole number of MPC periods)",
        value: options.dt,
    })?;
    let perturbation = options.total_perturbation();
    if let Some(&value) = perturbation.iter().find(|v| !v.is_finite()) {
        return Err(Error::InvalidOption {
            name: "perturbation dT",
            value,
        }
        .into());
    }
    let grid = ControlGrid {
        period,
        steps,
        every,
        perturbation,
    };
    Ok((metrics_of, grid))
}

/// The QP solves of an episode, one per control period and one at the final time: what the
/// metrics report of the solver (times, iterations, the worst accepted status).
struct SolveLog {
    solve_times: Vec<Duration>,
    qp_iterations: u64,
    worst_status: String,
}

impl SolveLog {
    fn with_capacity(solves: usize) -> Self {
        SolveLog {
            solve_times: Vec::with_capacity(solves),
            qp_iterations: 0,
            worst_status: String::from("Solved"),
        }
    }

    /// The MPC's control at state `x`, time `t`, logging its solve (a failure names `t`).
    fn control<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
        &mut self,
        mpc: &mut MpcN<M, N, NX, NP, NZ>,
        x: &SVector<f64, NX>,
        t: f64,
    ) -> Result<SVector<f64, N>, MpcFailure>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let u = mpc
            .control(x)
            .map_err(|source| MpcFailure::Controller { t, source })?;
        let info = mpc.last_solve();
        self.solve_times.push(info.solve_time);
        self.qp_iterations += u64::from(info.iterations);
        if info.status != "Solved" && self.worst_status == "Solved" {
            self.worst_status = info.status;
        }
        Ok(u)
    }
}

/// The sums over the output grid the metrics are made of: Σ task error, and ∫J dt and ∫|U|² dt
/// by the trapezoidal rule (hence the previous sample), with the trajectory when recorded.
struct Samples<const N: usize> {
    task_error: f64,
    int_j: f64,
    effort: f64,
    previous: Option<(f64, f64, f64)>,
    trajectory: Option<TrajectoryN<N>>,
}

impl<const N: usize> Samples<N> {
    fn new(record_trajectory: bool) -> Self {
        Samples {
            task_error: 0.0,
            int_j: 0.0,
            effort: 0.0,
            previous: None,
            trajectory: record_trajectory.then(TrajectoryN::default),
        }
    }

    /// Adds the output sample at `t` (what is observed, under control `u`).
    fn add(
        &mut self,
        metrics_of: &ActiveInferenceN<N>,
        t: f64,
        observed: toolconf_core::ObservationN<N>,
        u: &SVector<f64, N>,
    ) {
        self.task_error += metrics_of.task_error(&observed);
        let j = metrics_of.cost_j(&observed);
        let e = u.norm_squared();
        if let Some((t0, j0, e0)) = self.previous {
            self.int_j += 0.5 * (t - t0) * (j + j0);
            self.effort += 0.5 * (t - t0) * (e + e0);
        }
        self.previous = Some((t, j, e));
        if let Some(tr) = self.trajectory.as_mut() {
            tr.push(t, observed);
        }
    }

    /// The episode's metrics from these sums and the solve log (F = ∫J dt − ½ T ln|Π^U|), with
    /// the disturbance observer's final estimate d̂.
    fn metrics(
        &self,
        mut log: SolveLog,
        logdet: f64,
        t_end: f64,
        rhs_evals: usize,
        disturbance_estimate: SVector<f64, N>,
    ) -> MpcMetricsN<N> {
        log.solve_times.sort_unstable();
        let solve_times = log.solve_times;
        MpcMetricsN {
            task_error: self.task_error,
            cost_j: self.int_j,
            free_energy: self.int_j - 0.5 * t_end * logdet,
            control_effort: self.effort,
            logdet,
            rhs_evals,
            qp_solves: solve_times.len(),
            qp_iterations: log.qp_iterations,
            median_solve_time: solve_times[solve_times.len() / 2],
            max_solve_time: *solve_times.last().expect("at least one solve"),
            worst_status: log.worst_status,
            disturbance_estimate,
        }
    }
}

/// A period's [`IntegrationError::TooManySteps`] as the episode's
/// [`IntegrationError::OutOfWork`] when the shared budget (`binding`: below the integrator's own
/// limit) ran out, counting the attempts of the periods before it (`spent`).
fn mpc_out_of_work<const N: usize>(
    e: IntegrationError,
    spent: usize,
    binding: bool,
    dt: f64,
) -> IntegrationError {
    match e {
        IntegrationError::TooManySteps {
            t,
            max_steps,
            h,
            state,
        } if binding => IntegrationError::OutOfWork {
            t,
            attempts: spent + max_steps,
            why: diagnosis::<N>(&state, h, dt),
        },
        e => e,
    }
}

/// n when `total` = n · `step` for a whole n ≥ 1 (to 1e-9 relative), else `None`.
pub(super) fn whole_ratio(total: f64, step: f64) -> Option<usize> {
    let n = (total / step).round();
    (total.is_finite() && step > 0.0 && n >= 1.0 && (n * step - total).abs() <= 1e-9 * total.abs())
        .then_some(n as usize)
}
