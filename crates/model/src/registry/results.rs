//! What the registry's models return, with the sizes known only at run time: matrices as rows
//! or flat arrays, trajectories per joint.

use nalgebra::{SMatrix, SVector};

use crate::model::{Metrics, TrajectoryN};
use crate::Error;
use toolconf_generated::{Read, Term, TERMS};

/// A tool's linearisation and confidence with the sizes known only at run time (matrices as
/// rows): what `toolconf confidence --model` prints.
#[derive(Debug, Clone, PartialEq)]
pub struct Linearisation {
    /// A = ∂f/∂X at the equilibrium.
    pub a: Vec<Vec<f64>>,
    /// B = ∂f/∂U at the equilibrium.
    pub b: Vec<Vec<f64>>,
    /// The task's sensitivities by name (`d_theta_du`, `d_theta_dot_du`, `d_theta_ddot_du`), the
    /// terms it uses only.
    pub sensitivities: Vec<(&'static str, Vec<Vec<f64>>)>,
    /// Π^U (eq. control_conf).
    pub pi_u: Vec<Vec<f64>>,
    pub logdet: f64,
}

impl Linearisation {
    /// Every number finite ([`crate::validate::finite_output`]), naming `tool` and the quantity.
    pub fn check_finite(&self, tool: &dyn std::fmt::Display) -> Result<(), Error> {
        use crate::validate::finite_output;
        let flat = |m: &Vec<Vec<f64>>| m.iter().flatten().copied().collect::<Vec<f64>>();
        finite_output(tool, "A", flat(&self.a))?;
        finite_output(tool, "B", flat(&self.b))?;
        for (_, m) in &self.sensitivities {
            finite_output(tool, "a sensitivity", flat(m))?;
        }
        finite_output(tool, "Π^U", flat(&self.pi_u))?;
        finite_output(tool, "ln|Π^U|", [self.logdet])
    }
}

/// `m` as rows.
pub(super) fn rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Vec<Vec<f64>> {
    (0..R)
        .map(|i| (0..C).map(|j| m[(i, j)]).collect())
        .collect()
}

/// One episode of a tool of any model: its metrics, the constant torque perturbation on each
/// joint, and the trajectory if it was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct AnyEpisode {
    pub metrics: Metrics,
    pub perturbation: Vec<f64>,
    pub trajectory: Option<TrajectoryTable>,
}

/// A trajectory on the output grid with the joint count known only at run time: for each
/// term by [`Term::index`] (θ, θ̇, θ̈ (the plant's) and U), `terms[k][j][i]` is joint j at `t[i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryTable {
    pub t: Vec<f64>,
    pub terms: [Vec<Vec<f64>>; TERMS],
}

impl TrajectoryTable {
    /// The table of a trajectory with N joints known at compile time.
    pub fn from_trajectory<const N: usize>(tr: &TrajectoryN<N>) -> Self {
        TrajectoryTable {
            t: tr.t.clone(),
            terms: Term::ALL.map(|term| components(tr.of(term), tr.components(term))),
        }
    }

    /// The values of `term`, per joint.
    pub fn of(&self, term: Term) -> &[Vec<f64>] {
        &self.terms[term.index()]
    }

    /// As CSV: `t`, then every term of each joint (`theta1, …, theta1_dot, …, u<n>`: the joint's
    /// number after the name's first word), then on a tip task the tip's components (`tip_x`,
    /// `tip_dot_x`, …), one row per time.
    pub fn to_csv(&self) -> String {
        let column = |term: Term, j: usize| match (term.read(), term.name().split_once('_')) {
            (Read::Tip { .. }, _) => format!("{}_{}", term.name(), AXES[j - 1]),
            (_, Some((first, rest))) => format!("{first}{j}_{rest}"),
            (_, None) => format!("{}{j}", term.name()),
        };
        let blocks: Vec<(Term, &Vec<Vec<f64>>)> = Term::ALL
            .iter()
            .map(|&t| (t, &self.terms[t.index()]))
            .collect();
        let mut header = vec!["t".to_string()];
        for &(term, block) in &blocks {
            header.extend((1..=block.len()).map(|j| column(term, j)));
        }
        let mut out = header.join(",") + "\n";
        for i in 0..self.t.len() {
            let mut row = vec![self.t[i].to_string()];
            for (_, block) in &blocks {
                row.extend(block.iter().map(|joint| joint[i].to_string()));
            }
            out += &(row.join(",") + "\n");
        }
        out
    }
}

/// The names of a tip term's components, in the base frame.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// The first `count` rows of `series[i]` (time i) as `out[j][i]`: every joint of a joint term,
/// a tip term's own components.
pub(super) fn components<const N: usize>(
    series: &[SVector<f64, N>],
    count: usize,
) -> Vec<Vec<f64>> {
    (0..count.min(N))
        .map(|j| series.iter().map(|v| v[j]).collect())
        .collect()
}

/// The task variable of one episode on the output grid, per joint, with the goal.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTrace {
    pub t: Vec<f64>,
    /// `value[j][i]`: joint j (or the tip's component j, on a tip task) at `t[i]`.
    pub value: Vec<Vec<f64>>,
    pub goal: Vec<f64>,
    /// On a tip task, the tip's path in the base frame: `tip_path[j][i]` is component j of
    /// y(q(t_i)) (whatever the error term: ẏ on a tip velocity task).
    pub tip_path: Option<Vec<Vec<f64>>>,
    /// The joint angles: `joints[j][i]` is θ_j(t_i) (what a view of the arm poses it by).
    pub joints: Vec<Vec<f64>>,
}

/// Why a batch over many tools or states gave no result.
#[derive(Debug)]
pub enum BatchError {
    /// Tool `i` (in the order given) is bad or its result is not finite.
    Tool(usize, Error),
    /// Bad input other than a tool's parameters, in words.
    Input(String),
    /// The output, `bytes` long, cannot be allocated: an error to report, never an abort.
    OutOfMemory { bytes: usize },
}

/// An empty vector with room for `n` values, or [`BatchError::OutOfMemory`] of `total` values
/// (what the whole output needs, not only this part of it).
pub(super) fn room<T>(n: usize, total: usize) -> Result<Vec<T>, BatchError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| BatchError::OutOfMemory {
            bytes: total.saturating_mul(std::mem::size_of::<T>()),
        })?;
    Ok(v)
}

/// The linearisation and confidence of k tools, each array flat in C order (tool, row, column).
#[derive(Debug, Clone, PartialEq)]
pub struct Confidences {
    pub k: usize,
    pub n: usize,
    pub nx: usize,
    /// A = ∂f/∂X at the equilibrium (k × NX × NX).
    pub a: Vec<f64>,
    /// B = ∂f/∂U at the equilibrium (k × NX × N).
    pub b: Vec<f64>,
    /// The task's sensitivities by name, with their rows (each k × rows × N: N rows for a joint
    /// term, the tip's components for a tip term); a term the task does not use is absent.
    pub sensitivities: Vec<(&'static str, usize, Vec<f64>)>,
    /// Π^U (k × N × N).
    pub pi_u: Vec<f64>,
    /// ln|Π^U| (k).
    pub logdet: Vec<f64>,
}

/// Appends `m` to `out` in C order (row by row; nalgebra stores columns).
pub(super) fn push_c_order<const R: usize, const C: usize>(
    out: &mut Vec<f64>,
    m: &SMatrix<f64, R, C>,
) {
    out.extend((0..R).flat_map(|i| (0..C).map(move |j| m[(i, j)])));
}

/// One argument of a batch, a run-time matrix of `width` columns: one row shared by every
/// item, or one row per item.
#[derive(Debug, Clone, Copy)]
pub struct Rows<'a> {
    pub data: &'a [f64],
    pub width: usize,
    pub shared: bool,
}

impl Rows<'_> {
    /// Item `i`'s row.
    pub fn row(&self, i: usize) -> &[f64] {
        let i = if self.shared { 0 } else { i };
        &self.data[i * self.width..(i + 1) * self.width]
    }
}
