//! The closed loop linearised at the equilibrium: ż = M z + c with z = [δX; U], δX = X − X^e,
//! and every term the controller observes as an affine function of z.

use nalgebra::{SMatrix, SVector};

use crate::model::{ActiveInferenceN, ArmModel, TaskN, ToolN};
use crate::Error;
use toolconf_core::{reads_tip, TipKinematics};
use toolconf_generated::{Read, Term, TERMS};

/// One observed term, linearised: term ≈ `offset` + `gain_dt` ΔT + `c` z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearTerm<const N: usize, const NZ: usize> {
    pub c: SMatrix<f64, N, NZ>,
    /// The term at z = [0; 0] without ΔT: its value at X^e with U = 0.
    pub offset: SVector<f64, N>,
    /// ∂term/∂ΔT: B's rows for θ̈, J times them for ÿ, zero otherwise.
    pub gain_dt: SMatrix<f64, N, N>,
}

/// The linearised closed loop of one tool on one task ([`LinearLoop::new`]).
///
/// The plant is Ẋ ≈ f(X^e, U^e) + A δX + B (U + ΔT − U^e) (A, B at the equilibrium, as Π^U
/// has them); the controller is the runtime's own, U̇ = −γ Σ_i K_i (term_i − goal_i) with
/// K_i = S_iᵀ P_i; each term is linearised at X^e: θ, θ̇ and U are read off z, θ̈ is Ẋ's lower
/// rows, y ≈ y(q^e) + J δq, ẏ ≈ J δq̇ and ÿ ≈ J q̈, J = ∂y/∂q at q^e. At an equilibrium
/// (q̇^e = 0, f(X^e, U^e) = 0) the tip's second-order terms J̇ q̇ and ∂J/∂q q̈ vanish to first
/// order, which is why they are left out.
#[derive(Debug, Clone)]
pub struct LinearLoop<const N: usize, const NX: usize, const NZ: usize> {
    /// M = ∂ż/∂z.
    pub m: SMatrix<f64, NZ, NZ>,
    /// ż at z = 0 without ΔT, and its change per unit ΔT: c(ΔT) = `c` + `c_dt` ΔT.
    pub c: SVector<f64, NZ>,
    pub c_dt: SMatrix<f64, NZ, N>,
    pub terms: [LinearTerm<N, NZ>; TERMS],
    pub x_e: SVector<f64, NX>,
    pub controller: ActiveInferenceN<N>,
}

impl<const N: usize, const NX: usize, const NZ: usize> LinearLoop<N, NX, NZ> {
    /// The loop of `tool` on `task` (goals resolved already) with learning rate γ.
    pub fn new<M, const NP: usize>(
        tool: &ToolN<M, N, NX, NP, NZ>,
        task: &TaskN<N>,
        learning_rate: f64,
    ) -> Result<Self, Error>
    where
        M: ArmModel<N, NX, NP, NZ>,
    {
        let p = tool.params();
        let (x_e, u_e) = (M::equilibrium_state(), M::equilibrium_control());
        let f0 = M::dynamics(&x_e, &u_e, &p);
        let (a, b) = M::dynamics_jacobian(&x_e, &u_e, &p);
        let controller = ActiveInferenceN::new(tool, task, learning_rate)?;
        let tip = match reads_tip(task.kind) {
            true => {
                let q_e = x_e.fixed_rows::<N>(0).into_owned();
                TipKinematics::of::<M, NX, NP, NZ>(&q_e, &p).ok_or(toolconf_core::Error::NoTip {
                    kind: task.kind,
                    model: M::name(),
                })?
            }
            false => TipKinematics {
                position: SVector::zeros(),
                jacobian: SMatrix::zeros(),
                dim: 0,
                bias: None,
            },
        };
        // Ẋ's constant part at z = 0 (U = 0, so the plant's input is ΔT − U^e).
        let x_dot0 = f0 - b * u_e;
        let terms = Term::ALL.map(|term| linear_term(term, (&x_e, &x_dot0, &a, &b), &tip));
        let gains = controller.scaled_gains();
        let mut m = SMatrix::<f64, NZ, NZ>::zeros();
        let mut c = SVector::<f64, NZ>::zeros();
        let mut c_dt = SMatrix::<f64, NZ, N>::zeros();
        m.fixed_view_mut::<NX, NX>(0, 0).copy_from(&a);
        m.fixed_view_mut::<NX, N>(0, NX).copy_from(&b);
        c.fixed_rows_mut::<NX>(0).copy_from(&x_dot0);
        c_dt.fixed_view_mut::<NX, N>(0, 0).copy_from(&b);
        for term in Term::ALL {
            let (k, t) = (gains[term.index()], &terms[term.index()]);
            let mut u_rows = m.fixed_view_mut::<N, NZ>(NX, 0);
            u_rows -= k * t.c;
            let mut u_c = c.fixed_rows_mut::<N>(NX);
            u_c -= k * (t.offset - task.goal(term));
            let mut u_dt = c_dt.fixed_view_mut::<N, N>(NX, 0);
            u_dt -= k * t.gain_dt;
        }
        Ok(Self {
            m,
            c,
            c_dt,
            terms,
            x_e,
            controller,
        })
    }

    /// c(ΔT) = c + c_dt ΔT.
    pub fn input(&self, perturbation: &SVector<f64, N>) -> SVector<f64, NZ> {
        self.c + self.c_dt * perturbation
    }

    /// Every term the controller observes at `z` under ΔT, as the runtime's observation.
    pub fn observe(
        &self,
        z: &SVector<f64, NZ>,
        perturbation: &SVector<f64, N>,
    ) -> [SVector<f64, N>; TERMS] {
        self.terms
            .map(|t| t.offset + t.gain_dt * perturbation + t.c * z)
    }
}

/// `term` linearised at X^e (`at`: X^e, Ẋ's constant part at z = 0, A, B; `tip` the tip's
/// kinematics at q^e, zero on a joint-space task).
fn linear_term<const N: usize, const NX: usize, const NZ: usize>(
    term: Term,
    (x_e, x_dot0, a, b): (
        &SVector<f64, NX>,
        &SVector<f64, NX>,
        &SMatrix<f64, NX, NX>,
        &SMatrix<f64, NX, N>,
    ),
    tip: &TipKinematics<N>,
) -> LinearTerm<N, NZ> {
    let mut t = LinearTerm::<N, NZ> {
        c: SMatrix::zeros(),
        offset: SVector::zeros(),
        gain_dt: SMatrix::zeros(),
    };
    let j = tip.padded_jacobian();
    // The plant's q̈ rows: ∂/∂X, ∂/∂U, the value at z = 0.
    let (a_q, b_q) = (a.fixed_rows::<N>(N), b.fixed_rows::<N>(N));
    let rates = x_dot0.fixed_rows::<N>(N);
    match term.read() {
        Read::State { block } => {
            t.c.fixed_view_mut::<N, N>(0, block * N)
                .copy_from(&SMatrix::<f64, N, N>::identity());
            t.offset = x_e.fixed_rows::<N>(block * N).into_owned();
        }
        Read::StateRate { block } => {
            t.c.fixed_view_mut::<N, NX>(0, 0)
                .copy_from(&a.fixed_rows::<N>(block * N));
            t.c.fixed_view_mut::<N, N>(0, NX)
                .copy_from(&b.fixed_rows::<N>(block * N));
            t.offset = x_dot0.fixed_rows::<N>(block * N).into_owned();
            t.gain_dt = b.fixed_rows::<N>(block * N).into_owned();
        }
        Read::Control => {
            t.c.fixed_view_mut::<N, N>(0, NX)
                .copy_from(&SMatrix::<f64, N, N>::identity());
        }
        Read::Tip { order: 0 } => {
            t.c.fixed_view_mut::<N, N>(0, 0).copy_from(&j);
            t.offset = tip.pad(&tip.position);
        }
        Read::Tip { order: 1 } => {
            t.c.fixed_view_mut::<N, N>(0, N).copy_from(&j);
            t.offset = j * x_e.fixed_rows::<N>(N);
        }
        Read::Tip { .. } => {
            t.c.fixed_view_mut::<N, NX>(0, 0).copy_from(&(j * a_q));
            t.c.fixed_view_mut::<N, N>(0, NX).copy_from(&(j * b_q));
            t.offset = j * rates;
            t.gain_dt = j * b_q;
        }
    }
    t
}
