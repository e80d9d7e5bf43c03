//! What the caller chooses ([`Method`], [`Options`]) and what comes back ([`Stats`],
//! [`IntegrationError`]).

/// Which integration method runs (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// Dormand–Prince 5(4), `ode45`.
    Explicit,
    /// Rodas5P, a Rosenbrock (linearly implicit) method, using the Jacobian.
    Stiff,
    /// DP5 until its stiffness detection fires, Rodas5P from there on.
    #[default]
    Auto,
    /// Throughput on populations of tools: DP5 with a quicker stiffness test
    /// (10 steps at the stability boundary instead of `DOPRI5`'s 15), then Rodas5P with less
    /// work per step (the `rodas_lean` module, the same method as [`Method::Stiff`] up to
    /// rounding). Not `ode45`'s numbers once the test fires: [`Method::Explicit`] keeps those.
    Fast,
}

impl Method {
    /// Every method, in the order the command line lists them.
    pub const ALL: [Method; 4] = [Method::Fast, Method::Explicit, Method::Auto, Method::Stiff];

    /// The method's name on the command line (`--method`) and in Python (`method=`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Explicit => "explicit",
            Method::Stiff => "stiff",
            Method::Auto => "auto",
            Method::Fast => "fast",
        }
    }

    /// The method in words, for reports and command-line output.
    pub fn describe(self) -> &'static str {
        match self {
            Method::Explicit => "explicit: Dormand-Prince 5(4) exactly as MATLAB ode45 (the paper's numerics)",
            Method::Stiff => "stiff: Rodas5P throughout",
            Method::Auto => "auto: ode45 on tasks 1-2, ode45 then Rodas5P after Hairer's stiffness test on task 3",
            Method::Fast => "fast: ode45's steps until a 10-step stiffness test fires, then a lean Rodas5P",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;

    /// A method by [`Method::name`].
    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
                format!("'{s}': expected {}", names.join(", "))
            })
    }
}

/// Error control, step-size limits and method. The tolerances and limits default to `ode45`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Relative tolerance (`RelTol`), finite and > 0.
    pub rtol: f64,
    /// Absolute tolerance (`AbsTol`), finite and > 0, the same for every component.
    pub atol: f64,
    /// First step to try (`InitialStep`); `None` uses `ode45`'s heuristic.
    pub initial_step: Option<f64>,
    /// Largest step (`MaxStep`); `None` means `0.1·|tf − t0|`.
    pub max_step: Option<f64>,
    /// Most step attempts (accepted + rejected) before giving up, ≥ 1.
    pub max_steps: usize,
    /// The method, [`Method::Auto`] by default.
    pub method: Method,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: 1e-3,
            atol: 1e-6,
            initial_step: None,
            max_step: None,
            max_steps: 1_000_000,
            method: Method::default(),
        }
    }
}

/// Work done by one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Right-hand-side evaluations, `f(t0, y0)` included. DP5: `6·(steps + rejected) + 1`
    /// thanks to FSAL; Rodas5P from `t0`: `steps + 7·(steps + rejected)` (an attempt with a
    /// singular iteration matrix costs none), plus `D + 1` per Jacobian formed by finite
    /// differences.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts.
    pub rejected: usize,
    /// Jacobian evaluations, one per Rodas5P step (0 for DP5).
    pub jacobian_evals: usize,
    /// LU factorisations of the iteration matrix, one per Rodas5P attempt (0 for DP5).
    pub factorisations: usize,
}

/// Why an integration stopped early or could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrationError {
    /// The state or its derivative became NaN or infinite; `t` is the end of the step in which
    /// that happened (or `grid[0]` when `y0` or `f(t0, y0)` is not finite).
    #[error("integration failed at t = {} s: state became non-finite", toolconf_core::display::Short(*t))]
    NonFinite { t: f64 },
    /// The step size fell to `16·eps(t)` and the tolerances still could not be met, typically
    /// a singularity (finite-time blow-up) near `t`.
    #[error(
        "integration failed at t = {} s: step size {h:e} s reached the minimum 16·eps(t) without meeting the tolerances", toolconf_core::display::Short(*t)
    )]
    StepSizeTooSmall { t: f64, h: f64 },
    /// More than `max_steps` step attempts; `h` is the step size about to be tried at `t`,
    /// `state` the solution there (what the dynamics were doing when the work ran out).
    #[error("integration failed at t = {} s: exceeded the limit of {max_steps} step attempts (step size {h:e} s)", toolconf_core::display::Short(*t))]
    TooManySteps {
        t: f64,
        max_steps: usize,
        h: f64,
        state: Vec<f64>,
    },
    /// An episode's work budget (the runtime's `toolconf_model::model::budget`) ran out: the integrator's
    /// [`IntegrationError::TooManySteps`] at the episode's own limit, with the episode's
    /// reading of why (the state or the step size there).
    #[error("episode stopped after {attempts} step attempts at t = {t:.3e} s: {why}")]
    OutOfWork {
        t: f64,
        attempts: usize,
        why: String,
    },
    /// The output grid is unusable.
    #[error("invalid time grid: {reason}")]
    InvalidGrid { reason: String },
    /// An option is out of its domain.
    #[error("invalid integrator options: {reason}")]
    InvalidOptions { reason: String },
}

impl IntegrationError {
    /// The time the integration failed at, for failures during the integration.
    pub fn time(&self) -> Option<f64> {
        match self {
            IntegrationError::NonFinite { t }
            | IntegrationError::StepSizeTooSmall { t, .. }
            | IntegrationError::TooManySteps { t, .. }
            | IntegrationError::OutOfWork { t, .. } => Some(*t),
            IntegrationError::InvalidGrid { .. } | IntegrationError::InvalidOptions { .. } => None,
        }
    }
}
