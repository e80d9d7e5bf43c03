//! Finite-horizon discrete LQR by backward Riccati recursion: the unconstrained MPC's
//! reference solution, computed without any QP solver.

use nalgebra::{SMatrix, SVector};

use super::discretise::Discretised;
use super::qp::StageCost;
use toolconf_model::{State, Vector2};

/// The optimal open-loop controls u_0..u_{N−1} from x0 for the same problem the QP poses:
/// stage cost ½wᵀHw + hᵀw over w = [x; u] (cross terms included), affine dynamics
/// x⁺ = Ad x + Bd u + cd, terminal ½xᵀH_f x + h_fᵀx.
///
/// The value function stays quadratic with a linear part, V_k(x) = ½xᵀS_k x + s_kᵀx + const,
/// which is how the goals (h) and the offset (cd) are carried backwards.
pub(crate) fn plan(
    model: &Discretised<4, 2>,
    cost: &StageCost,
    horizon: usize,
    x0: &State,
) -> Vec<Vector2> {
    let (ad, bd, cd) = (model.ad, model.bd, model.cd);
    let h_xx = cost.hessian.fixed_view::<4, 4>(0, 0);
    let h_ux = cost.hessian.fixed_view::<2, 4>(4, 0);
    let h_uu = cost.hessian.fixed_view::<2, 2>(4, 4);
    let h_x = cost.linear.fixed_rows::<4>(0);
    let h_u = cost.linear.fixed_rows::<2>(4);

    let mut s = cost.terminal_hessian;
    let mut s_lin = cost.terminal_linear;
    // Feedback u_k = gain_k x_k + offset_k, stored backwards.
    let mut laws: Vec<(SMatrix<f64, 2, 4>, SVector<f64, 2>)> = Vec::with_capacity(horizon);
    for _ in 0..horizon {
        let next = s * cd + s_lin;
        let q_xx = h_xx + ad.transpose() * s * ad;
        let q_ux = h_ux + bd.transpose() * s * ad;
        let q_uu = h_uu + bd.transpose() * s * bd;
        let q_x = h_x + ad.transpose() * next;
        let q_u = h_u + bd.transpose() * next;
        let q_uu_inv = q_uu
            .try_inverse()
            .expect("Q_uu is singular: the stage cost does not fix u");
        let gain = -q_uu_inv * q_ux;
        let offset = -q_uu_inv * q_u;
        s = q_xx + q_ux.transpose() * gain;
        s = (s + s.transpose()) * 0.5;
        s_lin = q_x + q_ux.transpose() * offset;
        laws.push((gain, offset));
    }

    let mut x = *x0;
    laws.iter()
        .rev()
        .map(|(gain, offset)| {
            let u = gain * x + offset;
            x = ad * x + bd * u + cd;
            u
        })
        .collect()
}
