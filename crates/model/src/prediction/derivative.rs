//! The prediction's derivative along directions in the space of its linear system
//! ([`LinearSystem`]: M, c, z_0, each term's C_i, o_i − goal_i and P_i, ln|Π^U|), exactly, by
//! forward propagation along the grid: with [Φ, Γ; 0, 1] = exp(h [[M, c], [0, 0]]) (Van Loan),
//! z_{k+1} = Φ z_k + Γ and the sensitivity dz_{k+1} = dΦ z_k + Φ dz_k + dΓ, where [dΦ, dΓ] is the
//! Fréchet derivative of the exponential in the direction h [[dM, dc], [0, 0]]: the upper right
//! block of exp([[X, E], [0, X]]) (Van Loan's block form again); then
//! d(eᵀPe) = 2 eᵀ P de + eᵀ dP e with de = dC z + C dz + d(o − goal), summed as the values are.
//! A design by the predicted cost (`toolconf::design`) chains it with the system's derivative
//! over the tool's parameters; its tests check the chain against central differences.

use nalgebra::{DMatrix, DVector};
use toolconf_integrators::uniform_grid;

use super::LinearSystem;

/// Which predicted cost (a design minimises one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PredictedCost {
    /// Σ over the grid of (e − e^g)ᵀ P (e − e^g) on the task's error term.
    TaskError,
    /// ∫F dt = ∫(J − ½ ln|Π^U|) dt (eq. free_energy), trapezoidal on the grid.
    FreeEnergy,
}

/// One term of the cost in dense form: e = C z + d (d = offset − goal), its precision P.
#[derive(Debug, Clone)]
struct DenseTerm {
    c: DMatrix<f64>,
    d: DVector<f64>,
    p: DMatrix<f64>,
    error: bool,
    cost: bool,
}

/// A [`LinearSystem`] in nalgebra's dense form (or a direction in its space: the same fields).
#[derive(Debug, Clone)]
pub struct DenseSystem {
    m: DMatrix<f64>,
    c: DVector<f64>,
    z0: DVector<f64>,
    terms: Vec<DenseTerm>,
    logdet: f64,
    t_end: f64,
    dt: f64,
}

fn matrix(rows: &[Vec<f64>]) -> DMatrix<f64> {
    let (r, c) = (rows.len(), rows.first().map_or(0, Vec::len));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

impl DenseSystem {
    /// The terms the task error and J read, the others dropped.
    pub fn new(s: &LinearSystem) -> Self {
        let terms = s
            .terms
            .iter()
            .filter(|t| t.in_cost || t.name == s.error_term)
            .map(|t| DenseTerm {
                c: matrix(&t.c),
                d: DVector::from_iterator(
                    t.offset.len(),
                    t.offset.iter().zip(&t.goal).map(|(o, g)| o - g),
                ),
                p: matrix(&t.precision),
                error: t.name == s.error_term,
                cost: t.in_cost,
            })
            .collect();
        Self {
            m: matrix(&s.m),
            c: DVector::from_column_slice(&s.c),
            z0: DVector::from_column_slice(&s.z0),
            terms,
            logdet: s.logdet,
            t_end: s.t_end,
            dt: s.dt,
        }
    }

    /// (plus − minus) / width, field by field: a central difference of two systems.
    pub fn difference(plus: &Self, minus: &Self, width: f64) -> Self {
        let terms = plus
            .terms
            .iter()
            .zip(&minus.terms)
            .map(|(a, b)| DenseTerm {
                c: (&a.c - &b.c) / width,
                d: (&a.d - &b.d) / width,
                p: (&a.p - &b.p) / width,
                error: a.error,
                cost: a.cost,
            })
            .collect();
        Self {
            m: (&plus.m - &minus.m) / width,
            c: (&plus.c - &minus.c) / width,
            z0: (&plus.z0 - &minus.z0) / width,
            terms,
            logdet: (plus.logdet - minus.logdet) / width,
            t_end: plus.t_end,
            dt: plus.dt,
        }
    }
}

/// The predicted task error and ∫F dt.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Costs {
    pub task_error: f64,
    pub free_energy: f64,
}

impl Costs {
    pub fn get(&self, which: PredictedCost) -> f64 {
        match which {
            PredictedCost::TaskError => self.task_error,
            PredictedCost::FreeEnergy => self.free_energy,
        }
    }
}

/// The step over `h` and its derivatives in each direction: (Φ, Γ), and per direction (dΦ, dΓ).
struct Step {
    phi: DMatrix<f64>,
    gamma: DVector<f64>,
    tangents: Vec<(DMatrix<f64>, DVector<f64>)>,
}

/// h [[M, c], [0, 0]].
fn augmented(m: &DMatrix<f64>, c: &DVector<f64>, h: f64) -> DMatrix<f64> {
    let n = m.nrows();
    let mut a = DMatrix::zeros(n + 1, n + 1);
    a.view_mut((0, 0), (n, n)).copy_from(&(m * h));
    a.view_mut((0, n), (n, 1)).copy_from(&(c * h));
    a
}

impl Step {
    fn new(s: &DenseSystem, directions: &[DenseSystem], h: f64) -> Self {
        let n = s.m.nrows();
        let x = augmented(&s.m, &s.c, h);
        let e = x.clone().exp();
        let tangents = directions
            .iter()
            .map(|d| {
                // exp([[X, E], [0, X]]) = [[e^X, L(X, E)], [0, e^X]].
                let mut block = DMatrix::zeros(2 * (n + 1), 2 * (n + 1));
                block.view_mut((0, 0), (n + 1, n + 1)).copy_from(&x);
                block.view_mut((n + 1, n + 1), (n + 1, n + 1)).copy_from(&x);
                block
                    .view_mut((0, n + 1), (n + 1, n + 1))
                    .copy_from(&augmented(&d.m, &d.c, h));
                let l = block.exp();
                (
                    l.view((0, n + 1), (n, n)).into_owned(),
                    l.view((0, 2 * n + 1), (n, 1)).column(0).into_owned(),
                )
            })
            .collect();
        Self {
            phi: e.view((0, 0), (n, n)).into_owned(),
            gamma: e.view((0, n), (n, 1)).column(0).into_owned(),
            tangents,
        }
    }
}

/// The predicted costs of `s` and their derivatives in each of `directions`, as
/// [`super::predict`] forms the values (the same grid, sums and trapezoidal rule).
pub fn costs_and_derivatives(s: &DenseSystem, directions: &[DenseSystem]) -> (Costs, Vec<Costs>) {
    let grid = uniform_grid(0.0, s.t_end, s.dt);
    let regular = Step::new(s, directions, s.dt);
    let h_last = grid[grid.len() - 1] - grid[grid.len() - 2];
    let last = ((h_last - s.dt).abs() > 1e-12 * s.dt).then(|| Step::new(s, directions, h_last));
    let mut z = s.z0.clone();
    let mut dz: Vec<DVector<f64>> = directions.iter().map(|d| d.z0.clone()).collect();
    let mut value = Costs::default();
    let mut derivatives = vec![Costs::default(); directions.len()];
    // (t, F, dF per direction) at the previous point, for the trapezoidal rule.
    let mut previous: Option<(f64, f64, Vec<f64>)> = None;
    for (k, &t) in grid.iter().enumerate() {
        if k > 0 {
            let step = match (&last, k + 1 == grid.len()) {
                (Some(last), true) => last,
                _ => &regular,
            };
            for (dz, (dphi, dgamma)) in dz.iter_mut().zip(&step.tangents) {
                *dz = dphi * &z + &step.phi * &*dz + dgamma;
            }
            z = &step.phi * &z + &step.gamma;
        }
        let (error, j) = point(s, &z, None);
        value.task_error += error;
        let f = j - 0.5 * s.logdet;
        let df: Vec<f64> = directions
            .iter()
            .zip(&dz)
            .zip(derivatives.iter_mut())
            .map(|((d, dz), out)| {
                let (derror, dj) = point(s, &z, Some((d, dz)));
                out.task_error += derror;
                dj - 0.5 * d.logdet
            })
            .collect();
        if let Some((t_prev, f_prev, df_prev)) = &previous {
            let h = t - t_prev;
            value.free_energy += 0.5 * h * (f + f_prev);
            for ((out, a), b) in derivatives.iter_mut().zip(&df).zip(df_prev) {
                out.free_energy += 0.5 * h * (a + b);
            }
        }
        previous = Some((t, f, df));
    }
    (value, derivatives)
}

/// At one point: the task's weighted error and J = ½ Σ eᵀPe over J's terms, or with
/// `tangent` (a direction and dz along it) their derivatives.
fn point(
    s: &DenseSystem,
    z: &DVector<f64>,
    tangent: Option<(&DenseSystem, &DVector<f64>)>,
) -> (f64, f64) {
    let (mut error, mut j) = (0.0, 0.0);
    for (i, term) in s.terms.iter().enumerate() {
        let e = &term.c * z + &term.d;
        let v = match tangent {
            None => e.dot(&(&term.p * &e)),
            Some((d, dz)) => {
                let dt = &d.terms[i];
                let de = &dt.c * z + &term.c * dz + &dt.d;
                de.dot(&(&term.p * &e)) + e.dot(&(&term.p * &de)) + e.dot(&(&dt.p * &e))
            }
        };
        if term.error {
            error += v;
        }
        if term.cost {
            j += v;
        }
    }
    (error, 0.5 * j)
}
