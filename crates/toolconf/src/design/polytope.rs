//! The feasible set of a design: the free parameters' box and the linear constraints, with the
//! fixed parameters moved to the right-hand sides. Everything the solver and the sampler need:
//! rows G x ≤ h over the free parameters x, the centre (a Chebyshev centre, by an LP), a seeded
//! uniform sampler, and the map back to the full parameter vector.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::qp::{self, QpOutcome};
use super::DesignError;
use toolconf_messages::Clip;
use toolconf_model::inputs::design_file::constraint::dot;
use toolconf_model::inputs::design_file::DesignSpec;

/// Points within this (absolute, in parameter units) of a constraint count as on it.
pub const FEASIBILITY_TOLERANCE: f64 = 1e-9;

/// The most free parameters whose box corners are all tried as starts (2⁶ = 64 corners).
pub const MAX_CORNER_DIM: usize = 6;

#[derive(Debug, Clone, PartialEq)]
pub struct Polytope {
    /// Indices of the free parameters in the model's order.
    pub free: Vec<usize>,
    /// The full parameter vector with the fixed values in place (free entries are overwritten).
    pub base: Vec<f64>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    /// The linear constraints over the free parameters: `g[i]·x ≤ h[i]`, described by `text[i]`.
    pub g: Vec<Vec<f64>>,
    pub h: Vec<f64>,
    pub text: Vec<String>,
    /// The free parameters' names, for messages.
    pub names: Vec<&'static str>,
}

impl Polytope {
    pub fn new(spec: &DesignSpec) -> Self {
        let free: Vec<usize> = (0..spec.names.len())
            .filter(|&k| spec.fixed[k].is_none())
            .collect();
        let base: Vec<f64> = spec.bounds.iter().map(|b| b.0).collect();
        let (mut g, mut h, mut text) = (Vec::new(), Vec::new(), Vec::new());
        for c in &spec.constraints {
            let fixed_part: f64 = (0..base.len())
                .filter(|k| !free.contains(k))
                .map(|k| c.coefficients[k] * base[k])
                .sum();
            // Each row scaled to a largest coefficient of 1: the same set, and QPs whose rows
            // the solver sees on one scale whatever the user wrote (`1e6 m1 <= 3e5`).
            let row: Vec<f64> = free.iter().map(|&k| c.coefficients[k]).collect();
            let scale = row.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let scale = if scale > 0.0 { scale } else { 1.0 };
            g.push(row.iter().map(|v| v / scale).collect());
            h.push((c.bound - fixed_part) / scale);
            text.push(c.text.clone());
        }
        Self {
            names: free.iter().map(|&k| spec.names[k]).collect(),
            lo: free.iter().map(|&k| spec.bounds[k].0).collect(),
            hi: free.iter().map(|&k| spec.bounds[k].1).collect(),
            free,
            base,
            g,
            h,
            text,
        }
    }

    pub fn dim(&self) -> usize {
        self.free.len()
    }

    /// The full parameter vector for free parameters `x`.
    pub fn full(&self, x: &[f64]) -> Vec<f64> {
        let mut p = self.base.clone();
        for (&k, &v) in self.free.iter().zip(x) {
            p[k] = v;
        }
        p
    }

    /// Every row, box included: G x ≤ h with the box as ±x_j ≤ ±bound.
    pub fn all_rows(&self) -> (Vec<Vec<f64>>, Vec<f64>) {
        let (mut g, mut h) = (self.g.clone(), self.h.clone());
        for j in 0..self.dim() {
            let mut e = vec![0.0; self.dim()];
            e[j] = 1.0;
            g.push(e.clone());
            h.push(self.hi[j]);
            e[j] = -1.0;
            g.push(e);
            h.push(-self.lo[j]);
        }
        (g, h)
    }

    /// The largest violation of any row at `x` (≤ 0 when feasible).
    pub fn violation(&self, x: &[f64]) -> f64 {
        let (g, h) = self.all_rows();
        g.iter()
            .zip(&h)
            .map(|(row, b)| dot(row, x) - b)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    pub fn contains(&self, x: &[f64]) -> bool {
        self.violation(x) <= FEASIBILITY_TOLERANCE
    }

    /// The corners of the box (each free parameter at its lower or upper bound, the all-lower
    /// corner first) that satisfy the constraints; none beyond [`MAX_CORNER_DIM`] free
    /// parameters.
    pub fn feasible_corners(&self) -> Vec<Vec<f64>> {
        let n = self.dim();
        if n == 0 || n > MAX_CORNER_DIM {
            return Vec::new();
        }
        (0..1usize << n)
            .map(|bits| {
                (0..n)
                    .map(|j| {
                        if bits >> j & 1 == 0 {
                            self.lo[j]
                        } else {
                            self.hi[j]
                        }
                    })
                    .collect::<Vec<f64>>()
            })
            .filter(|x| self.contains(x))
            .collect()
    }

    /// A Chebyshev centre (the centre of the largest ball inside, in parameter units): the
    /// multi-start's first, deterministic start; or [`DesignError::Infeasible`] naming the
    /// constraints when the set is empty.
    pub fn centre(&self, file: &str) -> Result<Vec<f64>, DesignError> {
        let (g, h) = self.all_rows();
        let n = self.dim();
        if n == 0 {
            return if self.violation(&[]) <= FEASIBILITY_TOLERANCE {
                Ok(Vec::new())
            } else {
                Err(self.infeasible(file))
            };
        }
        // Variables [x; r]: maximise r subject to g·x + |g| r ≤ h and r ≥ 0.
        let mut rows: Vec<Vec<f64>> = g
            .iter()
            .map(|row| {
                let mut r = row.clone();
                r.push(dot(row, row).sqrt());
                r
            })
            .collect();
        let mut rhs = h.clone();
        let mut nonneg = vec![0.0; n + 1];
        nonneg[n] = -1.0;
        rows.push(nonneg);
        rhs.push(0.0);
        let mut cost = vec![0.0; n + 1];
        cost[n] = -1.0;
        match qp::solve_robustly(None, &cost, &rows, &rhs) {
            QpOutcome::Solved { x, .. } => {
                let x = x[..n].to_vec();
                if self.violation(&x) <= 1e-7 {
                    Ok(self.clamp(x))
                } else {
                    Err(self.infeasible(file))
                }
            }
            QpOutcome::Infeasible => Err(self.infeasible(file)),
            QpOutcome::Failed { reason, tight } => {
                // The centre's LP has the rows of all_rows (and r ≥ 0 last).
                let tight: Vec<usize> = tight.into_iter().filter(|&i| i < h.len()).collect();
                Err(self.solver_failed(file, "finding a feasible design", &reason, &tight))
            }
        }
    }

    /// The QP solver's failure, naming the file and the constraints it was solving under, and
    /// first those that were active when it failed (`tight`: rows of [`Polytope::all_rows`]).
    pub fn solver_failed(
        &self,
        file: &str,
        doing: &str,
        reason: &str,
        tight: &[usize],
    ) -> DesignError {
        let near = if tight.is_empty() {
            String::new()
        } else {
            let rows: Vec<String> = tight.iter().map(|&i| self.row_text(i)).collect();
            format!(" at {}", rows.join(", "))
        };
        DesignError::Failed(format!(
            "{file}: the QP solver failed {doing}{near} ({reason}) under the bounds and {}",
            self.constraints_text()
        ))
    }

    /// Row `i` of [`Polytope::all_rows`] in words: a constraint as the file gives it, or a
    /// bound (`tool_com_z >= 0`).
    pub fn row_text(&self, i: usize) -> String {
        let m = self.text.len();
        if i < m {
            return format!("'{}'", Clip(&self.text[i]));
        }
        let j = (i - m) / 2;
        let name = self.names.get(j).copied().unwrap_or("?");
        match ((i - m) % 2, self.hi.get(j), self.lo.get(j)) {
            (0, Some(hi), _) => format!("the bound {name} <= {}", toolconf_messages::Short(*hi)),
            (_, _, Some(lo)) => format!("the bound {name} >= {}", toolconf_messages::Short(*lo)),
            _ => format!("row {i}"),
        }
    }

    fn constraints_text(&self) -> String {
        if self.text.is_empty() {
            "no constraints".to_string()
        } else {
            let quoted: Vec<String> = self.text.iter().map(|t| format!("'{}'", Clip(t))).collect();
            format!("the constraints {}", quoted.join(", "))
        }
    }

    fn clamp(&self, x: Vec<f64>) -> Vec<f64> {
        x.iter()
            .enumerate()
            .map(|(j, v)| v.clamp(self.lo[j], self.hi[j]))
            .collect()
    }

    fn infeasible(&self, file: &str) -> DesignError {
        DesignError::Infeasible(format!(
            "{file}: the constraints are infeasible: no parameters within the bounds satisfy {}",
            self.constraints_text()
        ))
    }
}

/// How a sampler draws each coordinate from the box.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spread {
    /// lo + (hi − lo)·u: uniform in the parameters (the random tools a design is compared with).
    Uniform,
    /// lo·(hi/lo)^u: uniform in ln p, every decade of a wide box as likely as any other (the
    /// SQP's starts: in [1e-6, 1e6] a uniform start is almost surely above 1e4, where ln|Π^U| is
    /// flat, and the light corner is never started from).
    LogUniform,
}

/// Draws from the polytope by rejection from its box: ChaCha8 seeded with `seed`, each
/// coordinate from u = (next_u64 >> 11)·2⁻⁵³ as [`Spread`] says, a draw kept when it satisfies
/// every constraint. Sequential, so the same seed gives the same points on any machine.
pub struct FeasibleSampler<'a> {
    polytope: &'a Polytope,
    rng: ChaCha8Rng,
    spread: Spread,
    pub drawn: u64,
}

impl<'a> FeasibleSampler<'a> {
    pub fn new(polytope: &'a Polytope, seed: u64) -> Self {
        Self::with_spread(polytope, seed, Spread::Uniform)
    }

    pub fn with_spread(polytope: &'a Polytope, seed: u64, spread: Spread) -> Self {
        Self {
            polytope,
            rng: ChaCha8Rng::seed_from_u64(seed),
            spread,
            drawn: 0,
        }
    }

    /// The next feasible point, or None after `max_draws` draws in all without one.
    pub fn next_point(&mut self, max_draws: u64) -> Option<Vec<f64>> {
        let p = self.polytope;
        while self.drawn < max_draws {
            self.drawn += 1;
            let x: Vec<f64> = (0..p.dim())
                .map(|j| {
                    let u = (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
                    let (lo, hi) = (p.lo[j], p.hi[j]);
                    match self.spread {
                        Spread::Uniform => lo + (hi - lo) * u,
                        Spread::LogUniform => {
                            (lo.ln() + (hi.ln() - lo.ln()) * u).exp().clamp(lo, hi)
                        }
                    }
                })
                .collect();
            if p.g.iter().zip(&p.h).all(|(row, b)| dot(row, &x) <= *b) {
                return Some(x);
            }
        }
        None
    }
}
