//! MPC baseline: the paper's cost J (no confidence term) minimised over a receding horizon on
//! a linear(ised) arm model, solved as a sparse QP with Clarabel.
//!
//! The controller ([`MpcN`]) and its episode ([`simulate_mpc_on`]) are generic over the arm
//! model ([`toolconf_model::model::ArmModel`]), like the active-inference runtime; [`Mpc`] is the
//! controller of the paper's arm, and [`simulate_mpc`] (the paper's plant) and
//! [`toolconf_model::closed_loop::Plant::simulate_mpc`] run its episode, the tool named `arm m1=…`.
//! The sizes quoted below (6×6 stage blocks, four x_0 rows, the 7×7 exponential) are the 2-link
//! arm's; for an arm with n joints (state 2n) they are 3n×3n, 2n and 3n + 1.
//!
//! # Models ([`MpcModel`])
//!
//! - [`MpcModel::Equilibrium`], the baseline as first specified: the paper's linearisation
//!   ẋ = A(x − X^e) + Bu at the hanging equilibrium (appendix "Generative model"), fixed.
//! - [`MpcModel::Local`], successive linearisation: at every control step the generative
//!   process f is linearised at the measured state x̄ and the torque ū the plant is believed to
//!   receive (the control returned at the previous call plus the disturbance estimate d̂; 0 at
//!   the first call): A_k = ∂f/∂X, B_k = ∂f/∂U from the generated `dynamics_jacobian`,
//!   c_k = f(x̄, ū) − A_k x̄ − B_k ū, so ẋ = A_k x + B_k u + c_k is exact to first order around
//!   (x̄, ū). The model is frozen over the horizon (LTI within one solve, LTV across solves).
//!   At (X^e, 0) it is the equilibrium model (c = −A X^e, f(X^e, 0) = 0).
//!
//! Either affine model ẋ = Ax + Bu + c is discretised exactly with a zero-order hold at the
//! control period (the paper samples at dt = 0.05 s): x_{k+1} = Ad x_k + Bd u_k + cd
//! ([`discretise`], one 7×7 matrix exponential). The offset cd keeps the model in absolute
//! coordinates, so goals and the measured state are used as is.
//!
//! # Disturbance observer (offset-free MPC)
//!
//! With `disturbance_observer`, the controller estimates a constant input disturbance d̂
//! (N m, on the torque channels, where the perturbation ΔT enters the plant f(X, U + ΔT)).
//! At each call, with the previous call's state x⁻, control u⁻ and discrete model:
//!
//! e = x − (Ad x⁻ + Bd (u⁻ + d̂) + cd),   d̂ ← d̂ + L (BdᵀBd)⁻¹Bdᵀ e,
//!
//! the least-squares input that explains the one-step prediction error through Bd, filtered by
//! the gain L = `observer_gain` ∈ (0, 1]. For a plant that is the model plus a constant ΔT the
//! error after one update is (1 − L)ᵏ times the first; on the nonlinear plant d̂ also absorbs
//! the model's own one-step error (for the equilibrium model: the gravity mismatch). The plan
//! then uses the model with input u + d̂: cd + Bd d̂ in the dynamics and c + B d̂ in the
//! acceleration θ̈ the cost penalises. (The estimate must enter θ̈ as well as the dynamics: the
//! plant's θ̈ carries ΔT, and task 3, which weights only θ̈, would otherwise keep an offset of
//! B₃₄ΔT.)
//!
//! # Formulation
//!
//! Decision variables are z = (x_0, …, x_N, u_0, …, u_{N−1}), N = round(horizon / period). Keeping
//! x_0 as a variable pinned by the equality x_0 = x puts the measured state in the right-hand
//! side b only. The states are kept as variables (sparse, "simultaneous" form) rather than
//! eliminated, so P and A stay banded with O(N) non-zeros instead of a dense N×N condensed
//! Hessian.
//!
//! Cost: Σ_{k<N} T·J(x_k, u_k) + T·J_f(x_N), with J the paper's
//! ½[(θ−θ^g)ᵀP^θ(θ−θ^g) + (θ̇−θ̇^g)ᵀP^θ̇(θ̇−θ̇^g) + (θ̈−θ̈^g)ᵀP^θ̈(θ̈−θ̈^g) + UᵀP^U U] and
//! θ̈ = rows 3–4 of A x_k + B(u_k + d̂) + c, the model's acceleration during stage k. That makes
//! J a quadratic in (x_k, u_k) with cross terms. Weighting by T makes the sum a Riemann sum
//! of the paper's integral cost. The terminal cost J_f is the state-only part of J (the θ and
//! θ̇ terms): θ̈ depends on a control, and there is no u_N. Task 3 therefore has no terminal
//! cost, and its P^U = 0 leaves P only positive semi-definite; the θ̈ term still makes the
//! reduced Hessian in u (B₃₄ᵀP^θ̈B₃₄) definite, so the optimum is unique and Clarabel solves it.
//!
//! Constraints: the dynamics as equalities (Clarabel's zero cone) and, if the torque limit is
//! finite, |u_k,j| ≤ L as 4N rows (2nN for n joints) in the non-negative cone.
//!
//! # One solver, updated in place
//!
//! Clarabel is set up once in [`Mpc::new`] (with the equilibrium model) and never rebuilt. The
//! sparsity pattern is fixed there: every entry a model can fill (each stage's whole 6×6
//! upper-triangular Hessian block, the whole −Ad and −Bd blocks) is stored even when its
//! value is 0. Per call, Clarabel 0.11's data-update API overwrites values only:
//!
//! - always: `update_b` at the four x_0 rows;
//! - [`MpcModel::Local`]: `update_P` and `update_A` with (index, value) pairs at the stage
//!   Hessian and dynamics-block positions (precomputed non-zero positions in the CSC arrays),
//!   `update_q` with the whole q, `update_b` at the cd rows;
//! - equilibrium model with observer: `update_q` and `update_b` (cd rows) only.
//!
//! `presolve_enable = false` and `input_sparse_dropzeros = false` keep updates allowed.
//! Clarabel re-applies the equilibration (scaling) it computed at setup to updated data, so
//! after an update it solves a differently scaled copy of the QP a fresh setup would solve:
//! the same optimum to the solver's accuracy (plans agree to ≈ 2e-9 at the default
//! tolerances, to 1e-10 at tight ones, and bit for bit with equilibration off; tested).
//!
//! Clarabel runs with default tolerances otherwise. Each solve starts from Clarabel's default
//! point, so the original linear MPC's answer depends only on the state; with the local model
//! or the observer it also depends on the previous call (state, control, d̂) until
//! [`MpcN::reset`]. Without the torque bound the QP has only equalities and Clarabel solves it
//! in one KKT solve (0 iterations).
//!
//! Speed: Clarabel's solver is generic, so it is compiled into this crate at this crate's
//! optimisation level. A bounded solve (N = 20, 6–10 iterations) takes ≈ 0.3–0.5 ms in the
//! release profile but ≈ 6–12 ms in the dev profile; time experiments in release. The local
//! model adds ≈ 10 µs (Jacobian and matrix exponential) and the in-place update ≈ 15 µs.
//!
//! # Choice of the defaults (measured)
//!
//! The paper's three tasks on `select::draw_tools(30, 1)`, default episode (5 s, X0 = X^e),
//! ΔT = 0 and −0.8 N m, default timing and 5 N m bound; success = the episode ran without
//! error; medians of task error and ∫J over the successful episodes; time = median over
//! episodes of the median wall time of a control step (release, 2 shared cores, so ±30 %).
//! Reproduce with `cargo test --release --test mpc_episode -- --ignored --nocapture`.
//!
//! | model | observer (L) | ΔT | task | success | median task error | median ∫J | median time per step (µs) |
//! |---|---|---|---|---|---|---|---|
//! | Equilibrium | no | 0 | 1 | 20/30 | 4.9349e9 | 9.4586e10 | 488 |
//! | Equilibrium | no | 0 | 2 | 19/30 | 2.3780e9 | 7.0537e10 | 461 |
//! | Equilibrium | no | 0 | 3 | 30/30 | 6.6633e2 | 1.4370e1 | 347 |
//! | Equilibrium | no | -0.8 | 1 | 18/30 | 4.3423e9 | 3.2113e11 | 512 |
//! | Equilibrium | no | -0.8 | 2 | 16/30 | 4.8144e9 | 4.4278e11 | 516 |
//! | Equilibrium | no | -0.8 | 3 | 12/30 | 1.9418e15 | 3.9906e13 | 474 |
//! | Equilibrium | yes (1) | 0 | 1 | 30/30 | 1.2545e4 | 4.8502e2 | 434 |
//! | Equilibrium | yes (1) | 0 | 2 | 30/30 | 1.1780e4 | 3.2994e2 | 364 |
//! | Equilibrium | yes (1) | 0 | 3 | 30/30 | 1.1311e-2 | 2.7344e-4 | 351 |
//! | Equilibrium | yes (1) | -0.8 | 1 | 30/30 | 1.6435e4 | 8.5557e2 | 557 |
//! | Equilibrium | yes (1) | -0.8 | 2 | 30/30 | 1.3619e4 | 4.5757e2 | 403 |
//! | Equilibrium | yes (1) | -0.8 | 3 | 30/30 | 3.4138e8 | 8.5034e6 | 466 |
//! | Local | no | 0 | 1 | 30/30 | 1.2963e4 | 4.8189e2 | 398 |
//! | Local | no | 0 | 2 | 30/30 | 4.2254e2 | 2.2728e1 | 426 |
//! | Local | no | 0 | 3 | 30/30 | 3.9841e-10 | 9.9601e-12 | 473 |
//! | Local | no | -0.8 | 1 | 28/30 | 9.7920e5 | 2.5760e4 | 609 |
//! | Local | no | -0.8 | 2 | 22/30 | 2.9290e5 | 7.4998e3 | 369 |
//! | Local | no | -0.8 | 3 | 4/30 | 5.4800e7 | 1.3635e6 | 467 |
//! | Local | yes (1) | 0 | 1 | 30/30 | 1.2978e4 | 4.8204e2 | 394 |
//! | Local | yes (1) | 0 | 2 | 30/30 | 4.2291e2 | 2.2622e1 | 351 |
//! | Local | yes (1) | 0 | 3 | 30/30 | 1.1210e-6 | 2.7449e-8 | 349 |
//! | Local | yes (1) | -0.8 | 1 | 30/30 | 1.5400e4 | 7.3639e2 | 418 |
//! | Local | yes (1) | -0.8 | 2 | 30/30 | 3.0658e3 | 1.8939e2 | 399 |
//! | Local | yes (1) | -0.8 | 3 | 30/30 | 6.5955e4 | 8.2475e2 | 428 |
//! | Local | yes (0.5) | 0 | 1 | 30/30 | 1.2977e4 | 4.8203e2 | 387 |
//! | Local | yes (0.5) | 0 | 2 | 30/30 | 4.2286e2 | 2.2627e1 | 346 |
//! | Local | yes (0.5) | 0 | 3 | 30/30 | 1.0752e-6 | 2.6320e-8 | 344 |
//! | Local | yes (0.5) | -0.8 | 1 | 30/30 | 1.7922e4 | 8.7086e2 | 403 |
//! | Local | yes (0.5) | -0.8 | 2 | 30/30 | 6.4339e3 | 2.6611e2 | 393 |
//! | Local | yes (0.5) | -0.8 | 3 | 30/30 | 9.0615e4 | 1.4412e3 | 439 |
//!
//! - The original linear MPC (equilibrium, no observer) fails on a third of the tools on
//!   tasks 1–2 even unperturbed (θ^g is 150° from X^e, where the linear gravity "spring" is
//!   nothing like cos gravity; task 2 rotates joint 2 continuously) and the successful ones
//!   have medians of 1e9 task error: it swings the arm around, not to the goal. With ΔT = −0.8
//!   it fails on 12–18 of 30 on every task.
//! - The observer alone already stabilises the equilibrium model (d̂ absorbs the gravity
//!   mismatch as a disturbance), but its θ̈ predictions stay wrong: 30× the local model's
//!   error on task 2 and 1e8 on task 3 under ΔT.
//! - The local model alone is the best unperturbed (task 3 to 1e-10: f is affine in U, so
//!   the local model's θ̈ is exact at the measured state) but has no integral action: with
//!   ΔT = −0.8 it loses 2–26 tools and spins the light distal links.
//! - Local + observer succeeds on 90/90 in both cases, matches the local model unperturbed
//!   (task 3 to 1e-6 instead of 1e-10: the observer picks up integration and linearisation
//!   error) and has the lowest error under ΔT on every task. Its task-3 error under ΔT is
//!   dominated by the first samples, before any controller can know ΔT (at t = 0 the plant's
//!   θ̈ is off by B₃₄ΔT, e.g. 150 rad/s² on the distal link of 0.3,0.4,0.5,0.2).
//! - L = 1 beats L = 0.5 under ΔT (the state is measured exactly, so there is no noise to
//!   filter, and a slower estimate means a longer uncompensated transient).
//!
//! Hence the default: [`MpcModel::Local`], observer on, L = 1 ([`MpcOptions::default`]); the
//! original linear MPC baseline stays available as [`MpcOptions::original_linear`]
//! (`--mpc-model equilibrium --disturbance-observer false` on the command line). On task 1 the
//! default settles ≈ 0.03–0.05 rad from θ^g: that is J's own optimum (P^U = I prices the
//! torque that holds the arm against gravity), not an offset.

mod controller;
mod discretise;
mod episode;
#[cfg(test)]
mod lqr;
mod options;
mod qp;
#[cfg(test)]
mod tests;

pub use controller::{Mpc, MpcN};
pub use discretise::{discretise, Discretised};
pub use episode::{
    simulate_mpc, simulate_mpc_on, MpcEpisode, MpcEpisodeError, MpcEpisodeN, MpcMetrics,
    MpcMetricsN, MpcSimulationError, SimulateMpc,
};
pub use options::{MpcError, MpcModel, MpcOptions, SolveInfo};

/// The tasks the MPC baseline takes: the joint-space ones. It minimises J over the linearised
/// joint state, which does not hold the tool's tip (a task that reads the tip,
/// [`toolconf_core::reads_tip`], is refused with a message).
pub fn tasks() -> impl Iterator<Item = toolconf_model::TaskKind> {
    toolconf_model::TaskKind::ALL
        .into_iter()
        .filter(|k| !toolconf_core::reads_tip(*k))
}
