//! The MPC quadratic programme in Clarabel's form, min ½zᵀPz + qᵀz s.t. Az + s = b, s ∈ K.

use std::iter::zip;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SupportedConeT, ZeroConeT,
};
use nalgebra::{SMatrix, SVector};

use super::discretise::Discretised;
use crate::{InputMatrix, State, StateMatrix, Task, Vector2};

/// The paper's J per stage, times the period, as a quadratic in w = [x; u]:
/// ½wᵀ hessian w + linearᵀw (+ a constant that does not move the optimum).
///
/// The terminal cost keeps the state-only terms (θ and θ̇); θ̈ needs a control, and there is
/// no u_N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StageCost {
    pub hessian: SMatrix<f64, 6, 6>,
    pub linear: SVector<f64, 6>,
    pub terminal_hessian: SMatrix<f64, 4, 4>,
    pub terminal_linear: SVector<f64, 4>,
}

impl StageCost {
    /// θ̈ = A₃₄(x − X^e) + B₃₄u (rows 3–4 of the linear model), so every term of J is a
    /// residual M w − r with M = [C D] and the cost is ½ T (Mw − r)ᵀW(Mw − r) + ½ T uᵀPᵁu.
    pub fn new(
        a: &StateMatrix,
        b: &InputMatrix,
        equilibrium: &State,
        task: &Task,
        period: f64,
    ) -> Self {
        let mut m = SMatrix::<f64, 6, 6>::zeros();
        m.fixed_view_mut::<4, 4>(0, 0).fill_with_identity();
        m.fixed_view_mut::<2, 4>(4, 0)
            .copy_from(&a.fixed_view::<2, 4>(2, 0));
        m.fixed_view_mut::<2, 2>(4, 4)
            .copy_from(&b.fixed_view::<2, 2>(2, 0));
        let mut r = SVector::<f64, 6>::zeros();
        r.fixed_rows_mut::<2>(0).copy_from(&task.goal_theta);
        r.fixed_rows_mut::<2>(2).copy_from(&task.goal_theta_dot);
        r.fixed_rows_mut::<2>(4)
            .copy_from(&(task.goal_theta_ddot + a.fixed_view::<2, 4>(2, 0) * equilibrium));
        let mut w = SMatrix::<f64, 6, 6>::zeros();
        w.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&task.precision_theta);
        w.fixed_view_mut::<2, 2>(2, 2)
            .copy_from(&task.precision_theta_dot);
        w.fixed_view_mut::<2, 2>(4, 4)
            .copy_from(&task.precision_theta_ddot);

        let mut hessian = m.transpose() * w * m;
        let mut uu = hessian.fixed_view_mut::<2, 2>(4, 4);
        uu += task.precision_u;
        // Clarabel reads only the upper triangle, the Riccati reference the whole matrix:
        // make them the same matrix.
        let hessian = (hessian + hessian.transpose()) * (0.5 * period);
        let linear = -(m.transpose() * w * r) * period;

        let terminal_weight = w.fixed_view::<4, 4>(0, 0).into_owned();
        let terminal_hessian = terminal_weight * period;
        let terminal_linear = -(terminal_weight * r.fixed_rows::<4>(0)) * period;
        Self {
            hessian,
            linear,
            terminal_hessian,
            terminal_linear,
        }
    }
}

/// Where x_k and u_k sit in z = (x_0, …, x_N, u_0, …, u_{N−1}).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub horizon: usize,
}

impl Layout {
    pub fn x(self, k: usize) -> usize {
        4 * k
    }
    pub fn u(self, k: usize) -> usize {
        4 * (self.horizon + 1) + 2 * k
    }
    pub fn variables(self) -> usize {
        6 * self.horizon + 4
    }
}

/// Sparse assembly buffer; exact zeros are left out, since only b is ever updated and the
/// sparsity pattern of P and A never has to accommodate new values.
#[derive(Default)]
struct Triplets {
    rows: Vec<usize>,
    cols: Vec<usize>,
    values: Vec<f64>,
}

impl Triplets {
    fn push(&mut self, row: usize, col: usize, value: f64) {
        if value != 0.0 {
            self.rows.push(row);
            self.cols.push(col);
            self.values.push(value);
        }
    }

    fn into_csc(self, nrows: usize, ncols: usize) -> CscMatrix<f64> {
        CscMatrix::new_from_triplets(nrows, ncols, self.rows, self.cols, self.values)
    }
}

/// A Clarabel solver holding the whole QP; between solves only b[0..4] (= x_0) changes.
pub(crate) struct QpSolver {
    solver: DefaultSolver<f64>,
    layout: Layout,
}

impl QpSolver {
    pub fn new(
        model: &Discretised<4, 2>,
        cost: &StageCost,
        horizon: usize,
        torque_limit: f64,
    ) -> Result<Self, String> {
        let layout = Layout { horizon };
        let n = layout.variables();

        let mut p = Triplets::default();
        let mut q = vec![0.0; n];
        for k in 0..horizon {
            let index = |i: usize| {
                if i < 4 {
                    layout.x(k) + i
                } else {
                    layout.u(k) + i - 4
                }
            };
            for i in 0..6 {
                q[index(i)] += cost.linear[i];
                for j in 0..6 {
                    if index(i) <= index(j) {
                        p.push(index(i), index(j), cost.hessian[(i, j)]);
                    }
                }
            }
        }
        let terminal = layout.x(horizon);
        for i in 0..4 {
            q[terminal + i] += cost.terminal_linear[i];
            for j in i..4 {
                p.push(terminal + i, terminal + j, cost.terminal_hessian[(i, j)]);
            }
        }

        // Equalities: x_0 = measured state (b filled in by `solve`), then the dynamics
        // x_{k+1} − Ad x_k − Bd u_k = cd.
        let mut a = Triplets::default();
        let mut b = vec![0.0; 4 * (horizon + 1)];
        for i in 0..4 {
            a.push(i, layout.x(0) + i, 1.0);
        }
        for k in 0..horizon {
            let row = 4 * (k + 1);
            for i in 0..4 {
                a.push(row + i, layout.x(k + 1) + i, 1.0);
                for j in 0..4 {
                    a.push(row + i, layout.x(k) + j, -model.ad[(i, j)]);
                }
                for j in 0..2 {
                    a.push(row + i, layout.u(k) + j, -model.bd[(i, j)]);
                }
                b[row + i] = model.cd[i];
            }
        }
        let mut cones: Vec<SupportedConeT<f64>> = vec![ZeroConeT(b.len())];
        // |u| ≤ L as u + s = L and −u + s = L with s ≥ 0; an infinite bound is no constraint
        // (Clarabel's presolve would drop it, and presolve forbids data updates).
        if torque_limit.is_finite() {
            let first = b.len();
            for k in 0..horizon {
                for j in 0..2 {
                    a.push(first + 4 * k + j, layout.u(k) + j, 1.0);
                    a.push(first + 4 * k + 2 + j, layout.u(k) + j, -1.0);
                }
            }
            b.resize(first + 4 * horizon, torque_limit);
            cones.push(NonnegativeConeT(4 * horizon));
        }

        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .presolve_enable(false)
            .build()
            .map_err(|e| format!("Clarabel settings: {e}"))?;
        let solver = DefaultSolver::new(
            &p.into_csc(n, n),
            &q,
            &a.into_csc(b.len(), n),
            &b,
            &cones,
            settings,
        )
        .map_err(|e| format!("Clarabel setup: {e}"))?;
        if !solver.is_data_update_allowed() {
            return Err("Clarabel does not allow updating b in place for this problem".into());
        }
        Ok(Self { solver, layout })
    }

    /// Solves for the initial state `x0`; the caller checks the status.
    pub fn solve(&mut self, x0: &State) -> Result<(), String> {
        const X0_ROWS: [usize; 4] = [0, 1, 2, 3];
        self.solver
            .update_b(&zip(X0_ROWS.iter(), x0.as_slice().iter()))
            .map_err(|e| format!("Clarabel update_b: {e}"))?;
        self.solver.solve();
        Ok(())
    }

    pub fn solution(&self) -> &clarabel::solver::DefaultSolution<f64> {
        &self.solver.solution
    }

    /// u_0, …, u_{N−1} of the last solve.
    pub fn plan(&self) -> impl Iterator<Item = Vector2> + '_ {
        let z = &self.solver.solution.x;
        (0..self.layout.horizon)
            .map(move |k| Vector2::new(z[self.layout.u(k)], z[self.layout.u(k) + 1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Arm, TaskKind};

    /// The paper's J times the period, evaluated directly.
    fn direct_cost(arm: &Arm, task: &Task, x: &State, u: &Vector2, period: f64) -> f64 {
        let accel = (arm.state_matrix() * (x - Arm::equilibrium_state()) + arm.input_matrix() * u)
            .fixed_rows::<2>(2)
            .into_owned();
        let quad = |e: Vector2, p: &crate::Matrix2| (e.transpose() * p * e)[0];
        0.5 * period
            * (quad(
                x.fixed_rows::<2>(0) - task.goal_theta,
                &task.precision_theta,
            ) + quad(
                x.fixed_rows::<2>(2) - task.goal_theta_dot,
                &task.precision_theta_dot,
            ) + quad(accel - task.goal_theta_ddot, &task.precision_theta_ddot)
                + quad(*u, &task.precision_u))
    }

    #[test]
    fn stage_cost_is_the_papers_cost_up_to_a_constant() {
        let arm = Arm::new(0.2, 0.5, 0.4, 0.3).unwrap();
        let period = 0.05;
        let points = [
            (State::new(-1.0, -2.0, 0.3, -0.4), Vector2::new(0.5, -1.5)),
            (State::new(0.7, 0.1, -2.0, 1.0), Vector2::new(-3.0, 2.0)),
            (Arm::equilibrium_state(), Vector2::zeros()),
        ];
        for kind in TaskKind::ALL {
            let task = Task::paper(kind);
            let cost = StageCost::new(
                &arm.state_matrix(),
                &arm.input_matrix(),
                &Arm::equilibrium_state(),
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
