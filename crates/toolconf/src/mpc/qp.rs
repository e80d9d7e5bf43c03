//! The MPC quadratic programme in Clarabel's form, min ½zᵀPz + qᵀz s.t. Az + s = b, s ∈ K,
//! for any arm with N joints and state dimension NX = 2N (NZ = NX + N entries per stage).
//!
//! The sparsity pattern of P and A is fixed when the solver is built: every entry a model
//! could ever fill (the whole NZ×NZ upper triangle of each stage's Hessian, the whole Ad and Bd
//! blocks) is stored, even when its value is 0, so that a new model only overwrites values
//! ([`QpSolver::update`]) and never needs a new factorisation pattern.

use std::iter::zip;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT,
    SupportedConeT, ZeroConeT,
};
use nalgebra::{SMatrix, SVector};

use super::discretise::Discretised;
use toolconf_generated::{Read, Term};
use toolconf_model::model::TaskN;
// The 2-link names the unit tests below use (through `use super::*`).
#[cfg(test)]
use toolconf_model::{State, Task, Vector2};

/// The paper's J per stage, times the period, as a quadratic in w = [x; u]:
/// ½wᵀ hessian w + linearᵀw (+ a constant that does not move the optimum).
///
/// The terminal cost keeps the state-only terms (θ and θ̇); θ̈ needs a control, and there is
/// no u_N. The defaults are the 2-link sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StageCost<const N: usize = 2, const NX: usize = 4, const NZ: usize = 6> {
    pub hessian: SMatrix<f64, NZ, NZ>,
    pub linear: SVector<f64, NZ>,
    pub terminal_hessian: SMatrix<f64, NX, NX>,
    pub terminal_linear: SVector<f64, NX>,
}

impl<const N: usize, const NX: usize, const NZ: usize> StageCost<N, NX, NZ> {
    /// For the affine model ẋ = a x + b u + c, θ̈ = a_θ̈ x + b_θ̈ u + c_θ̈ (the last N rows), so
    /// every term of J is a residual M w − r with M = [C D] and the cost is
    /// ½ T (Mw − r)ᵀW(Mw − r) + ½ T uᵀPᵁu. The paper's linearisation at X^e is c = −A X^e.
    pub fn of(
        a: &SMatrix<f64, NX, NX>,
        b: &SMatrix<f64, NX, N>,
        c: &SVector<f64, NX>,
        task: &TaskN<N>,
        period: f64,
    ) -> Self {
        let mut m = SMatrix::<f64, NZ, NZ>::zeros();
        m.fixed_view_mut::<NX, NX>(0, 0).fill_with_identity();
        let mut r = SVector::<f64, NZ>::zeros();
        let mut w = SMatrix::<f64, NZ, NZ>::zeros();
        // Residual rows: X's own (the terms read from X), then N rows for the one term read
        // from Ẋ (θ̈), whose row of the affine model is [a b] there.
        for term in Term::ALL {
            let (goal, p) = (task.goal(term), task.precision(term));
            let rows = match term.read() {
                Read::State { block } => {
                    r.fixed_rows_mut::<N>(block * N).copy_from(goal);
                    block * N
                }
                Read::StateRate { block } => {
                    m.fixed_view_mut::<N, NX>(NX, 0)
                        .copy_from(&a.fixed_view::<N, NX>(block * N, 0));
                    m.fixed_view_mut::<N, N>(NX, NX)
                        .copy_from(&b.fixed_view::<N, N>(block * N, 0));
                    r.fixed_rows_mut::<N>(NX)
                        .copy_from(&(goal - c.fixed_rows::<N>(block * N)));
                    NX
                }
                // Refused before any QP is built (mpc::episode): the tip is not in the QP's state.
                Read::Control | Read::Tip { .. } => continue,
            };
            w.fixed_view_mut::<N, N>(rows, rows).copy_from(p);
        }

        let mut hessian = m.transpose() * w * m;
        let mut uu = hessian.fixed_view_mut::<N, N>(NX, NX);
        uu += task.precision(Term::CONTROL);
        // Clarabel reads only the upper triangle, the Riccati reference the whole matrix:
        // make them the same matrix.
        let hessian = (hessian + hessian.transpose()) * (0.5 * period);
        let linear = -(m.transpose() * w * r) * period;

        let terminal_weight = w.fixed_view::<NX, NX>(0, 0).into_owned();
        let terminal_hessian = terminal_weight * period;
        let terminal_linear = -(terminal_weight * r.fixed_rows::<NX>(0)) * period;
        Self {
            hessian,
            linear,
            terminal_hessian,
            terminal_linear,
        }
    }
}

#[cfg(test)]
impl StageCost {
    /// [`StageCost::of`] for the 2-link arm and its [`Task`].
    pub fn new(
        a: &toolconf_model::StateMatrix,
        b: &toolconf_model::InputMatrix,
        c: &State,
        task: &Task,
        period: f64,
    ) -> Self {
        Self::of(a, b, c, task, period)
    }
}

/// Where x_k and u_k sit in z = (x_0, …, x_N, u_0, …, u_{N−1}), for states of `nx` and
/// controls of `nu` entries.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub horizon: usize,
    nx: usize,
    nu: usize,
}

impl Layout {
    pub fn x(self, k: usize) -> usize {
        self.nx * k
    }
    pub fn u(self, k: usize) -> usize {
        self.nx * (self.horizon + 1) + self.nu * k
    }
    pub fn variables(self) -> usize {
        (self.nx + self.nu) * self.horizon + self.nx
    }
    /// Position in z of entry i of w_k = [x_k; u_k].
    fn w(self, k: usize, i: usize) -> usize {
        if i < self.nx {
            self.x(k) + i
        } else {
            self.u(k) + i - self.nx
        }
    }
    /// First row of the dynamics x_{k+1} − Ad x_k − Bd u_k = cd in A and b.
    fn dynamics_row(self, k: usize) -> usize {
        self.nx * (k + 1)
    }
}

/// The (i, j), i ≤ j, of a stage Hessian's upper triangle (NZ×NZ), in the order values are
/// written. Since every u index in z exceeds every x index, i ≤ j is also the upper triangle
/// of P.
fn stage_upper<const NZ: usize>() -> impl Iterator<Item = (usize, usize)> {
    (0..NZ).flat_map(|i| (i..NZ).map(move |j| (i, j)))
}

/// The (row, column) of the model in a dynamics block, relative to (dynamics_row(k), ·): the
/// NX×NX −Ad on x_k then the NX×N −Bd on u_k, in the order values are written.
fn dynamics_entries<const N: usize, const NX: usize>() -> impl Iterator<Item = (usize, usize)> {
    (0..NX)
        .flat_map(|i| (0..NX).map(move |j| (i, j)))
        .chain((0..NX).flat_map(|i| (NX..NX + N).map(move |j| (i, j))))
}

/// The values matching [`stage_upper`].
fn stage_values<const N: usize, const NX: usize, const NZ: usize>(
    cost: &StageCost<N, NX, NZ>,
) -> impl Iterator<Item = f64> + '_ {
    stage_upper::<NZ>().map(|(i, j)| cost.hessian[(i, j)])
}

/// The values matching [`dynamics_entries`].
fn dynamics_values<const N: usize, const NX: usize>(
    model: &Discretised<NX, N>,
) -> impl Iterator<Item = f64> + '_ {
    dynamics_entries::<N, NX>().map(|(i, j)| {
        if j < NX {
            -model.ad[(i, j)]
        } else {
            -model.bd[(i, j - NX)]
        }
    })
}

/// `values` refilled with one stage's entries, `stage()`, for each of the `horizon` stages (the
/// order of the matching index lists).
fn fill_per_stage<I: Iterator<Item = f64>>(
    values: &mut Vec<f64>,
    horizon: usize,
    stage: impl Fn() -> I,
) {
    values.clear();
    for _ in 0..horizon {
        values.extend(stage());
    }
}

/// Sparse assembly buffer. Exact zeros are kept: they are structural entries a later model may
/// fill, and Clarabel's data update can only overwrite entries that exist.
#[derive(Default)]
struct Triplets {
    rows: Vec<usize>,
    cols: Vec<usize>,
    values: Vec<f64>,
}

impl Triplets {
    fn push(&mut self, row: usize, col: usize, value: f64) {
        self.rows.push(row);
        self.cols.push(col);
        self.values.push(value);
    }

    fn into_csc(self, nrows: usize, ncols: usize) -> CscMatrix<f64> {
        CscMatrix::new_from_triplets(nrows, ncols, self.rows, self.cols, self.values)
    }
}

/// Position of (row, col) in the non-zero values of a CSC matrix that stores it.
fn nz_index(m: &CscMatrix<f64>, row: usize, col: usize) -> usize {
    let range = m.colptr[col]..m.colptr[col + 1];
    let offset = m.rowval[range.clone()]
        .binary_search(&row)
        .unwrap_or_else(|_| panic!("({row}, {col}) is not a structural entry"));
    range.start + offset
}

/// The solver settings: quiet, and nothing that would forbid in-place data updates (presolve,
/// dropping structural zeros). Everything else is Clarabel's default.
pub(crate) fn default_settings() -> DefaultSettings<f64> {
    DefaultSettingsBuilder::default()
        .verbose(false)
        .presolve_enable(false)
        .input_sparse_dropzeros(false)
        .build()
        .expect("valid Clarabel settings")
}

/// P's upper triangle: each stage's Hessian of J in w_k = [x_k; u_k], then the terminal
/// Hessian on x_N (Clarabel takes the upper triangle of a symmetric P).
fn hessian<const N: usize, const NX: usize, const NZ: usize>(
    layout: Layout,
    cost: &StageCost<N, NX, NZ>,
) -> Triplets {
    let mut p = Triplets::default();
    for k in 0..layout.horizon {
        for ((i, j), value) in zip(stage_upper::<NZ>(), stage_values(cost)) {
            p.push(layout.w(k, i), layout.w(k, j), value);
        }
    }
    let terminal = layout.x(layout.horizon);
    for i in 0..NX {
        for j in i..NX {
            p.push(terminal + i, terminal + j, cost.terminal_hessian[(i, j)]);
        }
    }
    p
}

/// A, b and the cones of the constraints A z + s = b: the equalities (the measured state, then
/// the dynamics), then the torque bounds if `torque_limit` is finite.
fn constraints<const N: usize, const NX: usize>(
    layout: Layout,
    model: &Discretised<NX, N>,
    torque_limit: f64,
) -> (Triplets, Vec<f64>, Vec<SupportedConeT<f64>>) {
    let horizon = layout.horizon;
    // Equalities: x_0 = measured state (b filled in by `solve`), then the dynamics
    // x_{k+1} − Ad x_k − Bd u_k = cd.
    let mut a = Triplets::default();
    let mut b = vec![0.0; NX * (horizon + 1)];
    for i in 0..NX {
        a.push(i, layout.x(0) + i, 1.0);
    }
    for k in 0..horizon {
        let row = layout.dynamics_row(k);
        for i in 0..NX {
            a.push(row + i, layout.x(k + 1) + i, 1.0);
            b[row + i] = model.cd[i];
        }
        for ((i, j), value) in zip(dynamics_entries::<N, NX>(), dynamics_values(model)) {
            a.push(row + i, layout.w(k, j), value);
        }
    }
    let mut cones: Vec<SupportedConeT<f64>> = vec![ZeroConeT(b.len())];
    // |u| ≤ L as u + s = L and −u + s = L with s ≥ 0; an infinite bound is no constraint
    // (Clarabel's presolve would drop it, and presolve forbids data updates).
    if torque_limit.is_finite() {
        let first = b.len();
        for k in 0..horizon {
            for j in 0..N {
                a.push(first + 2 * N * k + j, layout.u(k) + j, 1.0);
                a.push(first + 2 * N * k + N + j, layout.u(k) + j, -1.0);
            }
        }
        b.resize(first + 2 * N * horizon, torque_limit);
        cones.push(NonnegativeConeT(2 * N * horizon));
    }
    (a, b, cones)
}

/// A Clarabel solver holding the whole QP. Between solves b[0..NX] (= x_0) changes, and
/// [`QpSolver::update`] can overwrite the model-dependent values of P, q, A and b in place.
/// The defaults are the 2-link sizes.
pub(crate) struct QpSolver<const N: usize = 2, const NX: usize = 4, const NZ: usize = 6> {
    solver: DefaultSolver<f64>,
    layout: Layout,
    /// Positions in P's non-zero values of each stage's [`stage_upper`] entries, stage by stage.
    p_index: Vec<usize>,
    /// Positions in A's non-zero values of each stage's [`dynamics_entries`], stage by stage.
    a_index: Vec<usize>,
    /// The rows of b holding cd, stage by stage.
    b_index: Vec<usize>,
    /// The whole q, as last written (terminal part included).
    q: Vec<f64>,
    /// Scratch for the values of a partial update.
    values: Vec<f64>,
}

impl<const N: usize, const NX: usize, const NZ: usize> QpSolver<N, NX, NZ> {
    pub fn new(
        model: &Discretised<NX, N>,
        cost: &StageCost<N, NX, NZ>,
        horizon: usize,
        torque_limit: f64,
    ) -> Result<Self, String> {
        Self::with_settings(model, cost, horizon, torque_limit, default_settings())
    }

    pub fn with_settings(
        model: &Discretised<NX, N>,
        cost: &StageCost<N, NX, NZ>,
        horizon: usize,
        torque_limit: f64,
        settings: DefaultSettings<f64>,
    ) -> Result<Self, String> {
        let layout = Layout {
            horizon,
            nx: NX,
            nu: N,
        };
        let n = layout.variables();
        let p = hessian::<N, NX, NZ>(layout, cost).into_csc(n, n);
        let (a, b, cones) = constraints::<N, NX>(layout, model, torque_limit);
        let a = a.into_csc(b.len(), n);
        let p_index = (0..horizon)
            .flat_map(|k| stage_upper::<NZ>().map(move |(i, j)| (layout.w(k, i), layout.w(k, j))))
            .map(|(row, col)| nz_index(&p, row, col))
            .collect();
        let a_index = (0..horizon)
            .flat_map(|k| {
                dynamics_entries::<N, NX>()
                    .map(move |(i, j)| (layout.dynamics_row(k) + i, layout.w(k, j)))
            })
            .map(|(row, col)| nz_index(&a, row, col))
            .collect();
        let b_index = (0..horizon)
            .flat_map(|k| (0..NX).map(move |i| layout.dynamics_row(k) + i))
            .collect();
        let mut q = vec![0.0; n];
        write_q(&mut q, layout, cost);

        let solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
            .map_err(|e| format!("Clarabel setup: {e}"))?;
        if !solver.is_data_update_allowed() {
            return Err("Clarabel does not allow updating the QP data in place".into());
        }
        Ok(Self {
            solver,
            layout,
            p_index,
            a_index,
            b_index,
            q,
            values: Vec::with_capacity((NZ * (NZ + 1) / 2).max(NX * NZ) * horizon),
        })
    }

    /// Overwrites the model-dependent data in place: with `matrices`, the stage Hessians in P
    /// and the −Ad, −Bd blocks of A (`update_P`, `update_A`, partial updates by position);
    /// always q (`update_q`, the whole vector) and the cd rows of b (`update_b`, partial).
    /// Clarabel re-applies the equilibration it computed at setup to the new values.
    pub fn update(
        &mut self,
        model: &Discretised<NX, N>,
        cost: &StageCost<N, NX, NZ>,
        matrices: bool,
    ) -> Result<(), String> {
        let horizon = self.layout.horizon;
        if matrices {
            fill_per_stage(&mut self.values, horizon, || stage_values(cost));
            self.solver
                .update_P(&zip(self.p_index.iter(), self.values.iter()))
                .map_err(|e| format!("Clarabel update_P: {e}"))?;
            fill_per_stage(&mut self.values, horizon, || dynamics_values(model));
            self.solver
                .update_A(&zip(self.a_index.iter(), self.values.iter()))
                .map_err(|e| format!("Clarabel update_A: {e}"))?;
        }
        write_q(&mut self.q, self.layout, cost);
        self.solver
            .update_q(&self.q)
            .map_err(|e| format!("Clarabel update_q: {e}"))?;
        fill_per_stage(&mut self.values, horizon, || model.cd.iter().copied());
        self.solver
            .update_b(&zip(self.b_index.iter(), self.values.iter()))
            .map_err(|e| format!("Clarabel update_b: {e}"))?;
        Ok(())
    }

    /// Solves for the initial state `x0`; the caller checks the status.
    pub fn solve(&mut self, x0: &SVector<f64, NX>) -> Result<(), String> {
        let x0_rows: [usize; NX] = std::array::from_fn(|i| i);
        self.solver
            .update_b(&zip(x0_rows.iter(), x0.as_slice().iter()))
            .map_err(|e| format!("Clarabel update_b: {e}"))?;
        self.solver.solve();
        Ok(())
    }

    pub fn solution(&self) -> &clarabel::solver::DefaultSolution<f64> {
        &self.solver.solution
    }

    /// u_0, …, u_{N−1} of the last solve.
    pub fn plan(&self) -> impl Iterator<Item = SVector<f64, N>> + '_ {
        let z = &self.solver.solution.x;
        (0..self.layout.horizon).map(move |k| {
            let first = self.layout.u(k);
            SVector::from_fn(|j, _| z[first + j])
        })
    }
}

/// q: each stage's linear term at its x_k, u_k, and the terminal one at x_N.
fn write_q<const N: usize, const NX: usize, const NZ: usize>(
    q: &mut [f64],
    layout: Layout,
    cost: &StageCost<N, NX, NZ>,
) {
    q.fill(0.0);
    for k in 0..layout.horizon {
        for i in 0..NZ {
            q[layout.w(k, i)] += cost.linear[i];
        }
    }
    let terminal = layout.x(layout.horizon);
    for i in 0..NX {
        q[terminal + i] += cost.terminal_linear[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use toolconf_model::model::{Arm2, ArmModel};
    use toolconf_model::Arm;

    /// The paper's J times the period, evaluated directly.
    fn direct_cost(arm: &Arm, task: &Task, x: &State, u: &Vector2, period: f64) -> f64 {
        let accel = (arm.state_matrix() * (x - Arm2::equilibrium_state()) + arm.input_matrix() * u)
            .fixed_rows::<2>(2)
            .into_owned();
        let quad = |e: Vector2, p: &toolconf_model::Matrix2| (e.transpose() * p * e)[0];
        0.5 * period
            * (quad(
                x.fixed_rows::<2>(0) - task.goal(Term::Theta),
                task.precision(Term::Theta),
            ) + quad(
                x.fixed_rows::<2>(2) - task.goal(Term::ThetaDot),
                task.precision(Term::ThetaDot),
            ) + quad(
                accel - task.goal(Term::ThetaDdot),
                task.precision(Term::ThetaDdot),
            ) + quad(*u, task.precision(Term::U)))
    }

    /// A QP on the equilibrium model, and the data of the local model at a state far from it
    /// (with an input offset, as the observer adds).
    fn equilibrium_and_local(
        arm: &Arm,
        task: &Task,
    ) -> (
        (Discretised<4, 2>, StageCost),
        (Discretised<4, 2>, StageCost),
    ) {
        let t = 0.05;
        let (a, b) = (arm.state_matrix(), arm.input_matrix());
        let c = -a * Arm2::equilibrium_state();
        let equilibrium = (
            crate::mpc::discretise(&a, &b, &c, t),
            StageCost::new(&a, &b, &c, task, t),
        );
        let (x, u) = (State::new(1.0, 0.5, 0.3, 2.0), Vector2::new(1.0, -0.5));
        let (a, b) = toolconf_generated::arm2::dynamics_jacobian(&x, &u, &arm.params());
        let c = arm.dynamics(&x, &u) - a * x - b * u + b * Vector2::new(0.2, -0.1);
        let local = (
            crate::mpc::discretise(&a, &b, &c, t),
            StageCost::new(&a, &b, &c, task, t),
        );
        (equilibrium, local)
    }

    fn plan_of(qp: &mut QpSolver, x0: &State) -> Vec<Vector2> {
        qp.solve(x0).unwrap();
        assert!(matches!(
            qp.solution().status,
            clarabel::solver::SolverStatus::Solved
        ));
        qp.plan().collect()
    }

    #[test]
    fn in_place_update_solves_the_same_qp_as_a_fresh_solver() {
        let x0 = State::new(0.9, 0.6, 0.0, 1.5);
        for arm in [
            Arm::new([0.3, 0.4, 0.5, 0.2]),
            Arm::new([0.6, 0.1, 0.1, 0.6]),
        ] {
            let arm = arm.unwrap();
            for kind in crate::mpc::tasks() {
                let task = Task::paper(kind);
                let ((m0, c0), (m1, c1)) = equilibrium_and_local(&arm, &task);
                for limit in [5.0, f64::INFINITY] {
                    // Without equilibration (identity scaling) the update writes exactly the
                    // values a fresh setup stores: the same computation, bit for bit.
                    let raw = || {
                        let mut s = default_settings();
                        s.equilibrate_enable = false;
                        s
                    };
                    let mut updated = QpSolver::with_settings(&m0, &c0, 20, limit, raw()).unwrap();
                    plan_of(&mut updated, &x0);
                    updated.update(&m1, &c1, true).unwrap();
                    let mut fresh = QpSolver::with_settings(&m1, &c1, 20, limit, raw()).unwrap();
                    let bits = |p: Vec<Vector2>| {
                        p.iter()
                            .flat_map(|u| u.iter().map(|v| v.to_bits()))
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(
                        bits(plan_of(&mut updated, &x0)),
                        bits(plan_of(&mut fresh, &x0)),
                        "{arm} {kind} L={limit}"
                    );

                    // With equilibration (the default) the updated solver keeps the scaling of
                    // its first data, so it solves a differently scaled copy of the same QP:
                    // the same optimum to the solver's accuracy (≈ 2e-9 at the default
                    // tolerances, so tightened here to resolve 1e-10).
                    let tight = || {
                        let mut s = default_settings();
                        s.tol_gap_abs = 1e-12;
                        s.tol_gap_rel = 1e-12;
                        s.tol_feas = 1e-12;
                        s.tol_ktratio = 1e-10;
                        s
                    };
                    let mut updated =
                        QpSolver::with_settings(&m0, &c0, 20, limit, tight()).unwrap();
                    plan_of(&mut updated, &x0);
                    updated.update(&m1, &c1, true).unwrap();
                    let mut fresh = QpSolver::with_settings(&m1, &c1, 20, limit, tight()).unwrap();
                    let (got, want) = (plan_of(&mut updated, &x0), plan_of(&mut fresh, &x0));
                    let scale = want.iter().map(|u| u.amax()).fold(1.0, f64::max);
                    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                        assert!(
                            (g - w).amax() < 1e-10 * scale,
                            "{arm} {kind} L={limit} k={k}: {g:?} vs {w:?}"
                        );
                    }
                    // And back: an update to the setup data undoes the first one, to the same accuracy
                    // (Clarabel applies the stored scaling to an update in one product, at
                    // setup in several passes, so the last bits of the scaled data differ).
                    updated.update(&m0, &c0, true).unwrap();
                    let mut first = QpSolver::with_settings(&m0, &c0, 20, limit, tight()).unwrap();
                    let (got, want) = (plan_of(&mut updated, &x0), plan_of(&mut first, &x0));
                    let scale = want.iter().map(|u| u.amax()).fold(1.0, f64::max);
                    for (g, w) in got.iter().zip(&want) {
                        assert!(
                            (g - w).amax() < 1e-10 * scale,
                            "{arm} {kind} L={limit}: update back to the setup data"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn stage_cost_is_the_papers_cost_up_to_a_constant() {
        let arm = Arm::new([0.2, 0.5, 0.4, 0.3]).unwrap();
        let period = 0.05;
        let points = [
            (State::new(-1.0, -2.0, 0.3, -0.4), Vector2::new(0.5, -1.5)),
            (State::new(0.7, 0.1, -2.0, 1.0), Vector2::new(-3.0, 2.0)),
            (Arm2::equilibrium_state(), Vector2::zeros()),
        ];
        for kind in crate::mpc::tasks() {
            let task = Task::paper(kind);
            let a = arm.state_matrix();
            let cost = StageCost::new(
                &a,
                &arm.input_matrix(),
                &(-a * Arm2::equilibrium_state()),
                &task,
                period,
            );
            let model = |x: &State, u: &Vector2| {
                let w = SVector::<f64, 6>::from_iterator(x.iter().chain(u.iter()).copied());
                0.5 * (w.transpose() * cost.hessian * w)[0] + cost.linear.dot(&w)
            };
            let (x0, u0) = points[2];
            for (x, u) in &points[..2] {
                let expected = direct_cost(&arm, &task, x, u, period)
                    - direct_cost(&arm, &task, &x0, &u0, period);
                let got = model(x, u) - model(&x0, &u0);
                assert!(
                    (got - expected).abs() < 1e-10 * expected.abs().max(1.0),
                    "{kind}: {got} vs {expected}"
                );
            }
        }
    }
}
