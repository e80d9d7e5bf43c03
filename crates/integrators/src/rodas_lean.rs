//! Rodas5P with less work per step: the stepper of [`super::Method::Fast`], for throughput on
//! populations of tools. The method, tableau, error norm and step-size rules are those
//! of [`super::rodas5p`] and [`super::rosenbrock`] (`rodas.f`'s transformed form, `ode45`'s step control); what differs
//! is only how a step is computed:
//!
//! * Rodas5P's last three stages are evaluated on successive solutions
//!   `u_7 = u_6 + k_6`, `u_8 = u_7 + k_7` (rows 7 and 8 of `a` are row 6 plus ones), so their
//!   arguments cost one vector addition each instead of a sum over all earlier stages;
//! * the `h·d_i·∂f/∂t` terms are skipped when `∂f/∂t = 0` (the closed loop is autonomous), and
//!   stages 6–8 have `d_i = 0` anyway;
//! * the solves use the LU factorisation's stored pivot reciprocals
//!   ([`Lu::solve_by_reciprocals`]): each of the eight solves per attempt multiplies instead of
//!   dividing (six divisions fewer per solve, on the critical path);
//! * the dense output's `q_r = Σ_j h_rj·k_j` are formed once per step that contains output
//!   points, not once per point.
//!
//! The results differ from [`super::Method::Stiff`]'s in the last bits only (the sums are
//! associated differently), which `tests/population.rs` checks against the tight reference.

use nalgebra::{SMatrix, SVector};
use toolconf_core::linalg::Lu;

use super::rodas5p::RODAS5P;
use super::rosenbrock::{Problem, Span, Stepper, Tableau};

/// Stages of Rodas5P.
const S: usize = 8;
/// The first stage evaluated at `t + h` on the successive solutions (0-based).
const LAST_ROW: usize = 5;

/// Rodas5P's structure that [`attempt`] relies on, checked by a unit test: stages from
/// `LAST_ROW` on are at `α = 1` with `d = 0`, and their argument rows are the previous row plus
/// a one on the previous stage.
#[cfg(test)]
fn tableau_has_successive_solutions(tab: &Tableau<S>) -> bool {
    (LAST_ROW..S).all(|i| {
        tab.alpha[i] == 1.0
            && tab.d[i] == 0.0
            && (i == LAST_ROW
                || (0..S).all(|j| {
                    let expected = tab.a[i - 1][j] + if j == i - 1 { 1.0 } else { 0.0 };
                    tab.a[i][j] == expected
                }))
    })
}

/// The dense output's `q_1, q_2, q_3` of a step.
#[inline]
fn dense_rows<const D: usize>(k: &[SVector<f64, D>; S]) -> [SVector<f64, D>; 3] {
    RODAS5P.dense.map(|row| {
        let mut sum = SVector::<f64, D>::zeros();
        for (k, &w) in k.iter().zip(&row) {
            sum += k * w;
        }
        sum
    })
}

/// An attempt: the stages, the new solution and, once the step has output points inside it,
/// its dense output's rows.
pub(super) struct LeanStep<const D: usize> {
    k: [SVector<f64, D>; S],
    y_new: SVector<f64, D>,
    dense: Option<[SVector<f64, D>; 3]>,
}

/// The lean Rodas5P step inside [`super::rosenbrock::run`].
pub(super) struct Lean;

impl<const D: usize> Stepper<D, S> for Lean {
    type Lu = Lu<D>;
    type Step = LeanStep<D>;

    fn factor(e: SMatrix<f64, D, D>) -> Option<Lu<D>> {
        Lu::new(e)
    }

    #[inline(always)]
    // k[j] and the tableau's a[i][j], c[i][j] are indexed together, as in the formulas.
    #[allow(clippy::needless_range_loop)]
    fn attempt<P: Problem<D>>(&self, problem: &mut P, lu: &Lu<D>, span: Span<D>) -> LeanStep<D> {
        let (t, t_new, y, f0, dfdt) = (span.t, span.t_new, span.y, span.f0, span.dfdt);
        let tab: &Tableau<S> = &RODAS5P;
        let dfdt = (!dfdt.iter().all(|&v| v == 0.0)).then_some(dfdt);
        let h = t_new - t;
        let r = 1.0 / h;
        let mut k = [SVector::<f64, D>::zeros(); S];
        let time_term = |b: &mut SVector<f64, D>, i: usize| {
            if let Some(dfdt) = dfdt {
                *b += dfdt * (h * tab.d[i]);
            }
        };
        let mut b = *f0;
        time_term(&mut b, 0);
        k[0] = lu.solve_by_reciprocals(&b);
        for i in 1..LAST_ROW {
            let mut u = *y;
            for j in 0..i {
                u += k[j] * tab.a[i][j];
            }
            let mut b = problem.rhs(t + tab.alpha[i] * h, &u);
            time_term(&mut b, i);
            for j in 0..i {
                b += k[j] * (tab.c[i][j] * r);
            }
            k[i] = lu.solve_by_reciprocals(&b);
        }
        let mut u = *y;
        for j in 0..LAST_ROW {
            u += k[j] * tab.a[LAST_ROW][j];
        }
        for i in LAST_ROW..S {
            if i > LAST_ROW {
                u += k[i - 1];
            }
            let mut b = problem.rhs(t_new, &u);
            for j in 0..i {
                b += k[j] * (tab.c[i][j] * r);
            }
            k[i] = lu.solve_by_reciprocals(&b);
        }
        LeanStep {
            y_new: u + k[S - 1],
            k,
            dense: None,
        }
    }

    fn y_new(step: &LeanStep<D>) -> &SVector<f64, D> {
        &step.y_new
    }

    fn estimate(step: &LeanStep<D>) -> &SVector<f64, D> {
        &step.k[S - 1]
    }

    fn interpolate(
        &self,
        step: &mut LeanStep<D>,
        t: f64,
        y: &SVector<f64, D>,
        h: f64,
        t_out: f64,
    ) -> SVector<f64, D> {
        let [q1, q2, q3] = step.dense.get_or_insert_with(|| dense_rows(&step.k));
        let s = (t_out - t) / h;
        y * (1.0 - s) + (step.y_new + (*q1 + (*q2 + *q3 * s) * s) * (1.0 - s)) * s
    }
}

#[cfg(test)]
mod tests {
    use super::super::rosenbrock::Start;
    use super::super::Stats;
    use super::*;

    #[test]
    fn rodas5p_has_the_structure_the_lean_step_relies_on() {
        assert!(tableau_has_successive_solutions(&RODAS5P));
    }

    /// A stiff nonlinear problem (Van der Pol, μ = 50) with its Jacobian.
    struct VanDerPol;

    impl Problem<2> for VanDerPol {
        fn rhs(&mut self, _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
            nalgebra::vector![y[1], 50.0 * ((1.0 - y[0] * y[0]) * y[1]) - y[0]]
        }

        fn jacobian(
            &mut self,
            _t: f64,
            y: &SVector<f64, 2>,
            _f: &SVector<f64, 2>,
        ) -> (SMatrix<f64, 2, 2>, SVector<f64, 2>, usize) {
            let j =
                nalgebra::matrix![0.0, 1.0; -100.0 * y[0] * y[1] - 1.0, 50.0 * (1.0 - y[0] * y[0])];
            (j, SVector::zeros(), 0)
        }
    }

    /// The lean step is Rodas5P: the same steps and output as `rodas5p.rs` up to rounding.
    #[test]
    fn lean_rodas5p_takes_the_steps_of_rodas5p_rs() {
        // Two relaxation jumps (period ≈ (3 − 2 ln 2)·μ ≈ 81) by t = 100.
        let grid = super::super::uniform_grid(0.0, 100.0, 0.25);
        let options = super::super::Options::default();
        let settings = super::super::resolve(&options, &grid).unwrap();
        let y0 = nalgebra::vector![2.0, 0.0];
        let run = |lean: bool| {
            let start = Start {
                t: 0.0,
                y: y0,
                f: VanDerPol.rhs(0.0, &y0),
                abs_h: None,
                next: 1,
                stats: Stats::default(),
            };
            let mut out = Vec::new();
            let output = |_, _, y: &SVector<f64, 2>| out.push(*y);
            let stats = super::super::rodas5p::integrate(
                &mut VanDerPol,
                start,
                &grid,
                &settings,
                output,
                lean,
            )
            .unwrap();
            (stats, out)
        };
        let ((lean, y_lean), (plain, y_plain)) = (run(true), run(false));
        assert_eq!(lean, plain);
        assert!(lean.steps > 100, "{lean:?}");
        assert_eq!(y_lean.len(), grid.len() - 1);
        let worst = y_lean
            .iter()
            .zip(&y_plain)
            .map(|(a, b)| (a - b).amax() / b.amax().max(1.0))
            .fold(0.0, f64::max);
        // Rounding of differently associated sums, amplified through the two jumps (measured
        // 2.4e-10): six orders below the tolerance, with exactly the same steps.
        assert!(worst <= 1e-9, "{worst:e}");
    }
}
