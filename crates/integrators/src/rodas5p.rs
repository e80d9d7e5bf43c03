//! Rodas5P: a stiffly accurate, L-stable Rosenbrock method of order 5 with an embedded order-4
//! error estimate and a continuous extension of order 4, for stiff problems.
//!
//! Sources: G. Steinebach, "Construction of Rosenbrock–Wanner method Rodas5P and numerical
//! benchmarks within the Julia Differential Equations package", BIT Numer. Math. 63, 27 (2023),
//! coefficients as tabulated in OrdinaryDiffEq.jl (`Rodas5PTableau`); the formulation and the
//! step of E. Hairer & G. Wanner, "Solving Ordinary Differential Equations II", 2nd ed., §IV.7
//! and their code `rodas.f`.
//!
//! Rodas5P was chosen by measurement on the paper's task 3 (23 arms, default tolerances, see
//! `tests/stiff_task3.rs`) over Rodas4 (Hairer–Wanner), Rodas4P2 (Steinebach 2020) and
//! `ode23s`'s modified Rosenbrock 2(3): for about as many right-hand sides as the Rodas4 pair,
//! it needs a quarter fewer Jacobians and factorisations and its worst error against the
//! reference is 30–45× smaller; `ode23s` is less accurate than DP5 at rtol = 1e-3 and needs
//! rtol = 1e-4, 1.5× the right-hand sides and 6× the Jacobians of Rodas5P, to match it. Its
//! dense output, unlike Rodas4's, keeps its accuracy on Prothero–Robinson-type problems
//! `y' = λ(y − g(t)) + g'(t)` with `h·|λ| ≫ 1`, which is what the controller's fast mode is.
//!
//! The step, the error and step-size control and the dense output are `rosenbrock`'s.

use nalgebra::{SMatrix, SVector};
use toolconf_core::linalg::Lu;

use super::rodas_lean::Lean;
use super::rosenbrock::{run, Problem, Span, Start, Stepper, Tableau};
use super::{IntegrationError, Settings, Stats};

/// Rodas5P (Steinebach 2023). Rows i = 1…8 of `a` and `c` list the coefficients of k_1…k_{i−1}.
#[rustfmt::skip]
pub(super) const RODAS5P: Tableau<8> = Tableau {
    gamma: 0.21193756319429014,
    alpha: [
        0.0, 0.6358126895828704, 0.4095798393397535, 0.9769306725060716, 0.4288403609558664,
        1.0, 1.0, 1.0,
    ],
    a: [
        [0.0; 8],
        [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [2.849394379747939, 0.45842242204463923, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [-6.954028509809101, 2.489845061869568, -10.358996098473584, 0.0, 0.0, 0.0, 0.0, 0.0],
        [2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641,
         0.0, 0.0, 0.0, 0.0],
        [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
         0.030198172008377946, 0.0, 0.0, 0.0],
        [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
         0.030198172008377946, 1.0, 0.0, 0.0],
        [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
         0.030198172008377946, 1.0, 1.0, 0.0],
    ],
    c: [
        [0.0; 8],
        [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [-17.97296035885952, -2.859693295451294, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [147.12150275711716, -1.41221402718213, 71.68940251302358, 0.0, 0.0, 0.0, 0.0, 0.0],
        [165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306,
         0.0, 0.0, 0.0, 0.0],
        [24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125,
         -0.6610691825249471, 0.0, 0.0, 0.0],
        [30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783,
         -19.097331116725623, -28.087943162872662, 0.0, 0.0],
        [37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047,
         -40.06618937091002, -54.66780262877968, -9.48861652309627, 0.0],
    ],
    d: [
        0.21193756319429014, -0.42387512638858027, -0.3384627126235924, 1.8046452872882734,
        2.325825639765069, 0.0, 0.0, 0.0,
    ],
    dense: [
        [25.948786856663858, -2.5579724845846235, 10.433815404888879, -2.3679251022685204,
         0.524948541321073, 1.1241088310450404, 0.4272876194431874, -0.17202221070155493],
        [-9.91568850695171, -0.9689944594115154, 3.0438037242978453, -24.495224566215796,
         20.176138334709044, 15.98066361424651, -6.789040303419874, -6.710236069923372],
        [11.419903575922262, 2.8879645146136994, 72.92137995996029, 80.12511834622643,
         -52.072871366152654, -59.78993625266729, -0.15582684282751913, 4.883087185713722],
    ],
    exponent: 0.2,
};

/// One attempted step.
struct Attempt<const D: usize, const S: usize> {
    y_new: SVector<f64, D>,
    /// The stages, for the dense output; the last is the error estimate.
    k: [SVector<f64, D>; S],
}

/// The continuous extension at `t_out` inside the step `[t, t + h]`.
#[inline]
fn interpolate<const D: usize, const S: usize>(
    tab: &Tableau<S>,
    t: f64,
    y: &SVector<f64, D>,
    h: f64,
    step: &Attempt<D, S>,
    t_out: f64,
) -> SVector<f64, D> {
    let s = (t_out - t) / h;
    let q = |row: &[f64; S]| {
        let mut sum = SVector::<f64, D>::zeros();
        for (k, &w) in step.k.iter().zip(row) {
            sum += k * w;
        }
        sum
    };
    let [h1, h2, h3] = &tab.dense;
    y * (1.0 - s) + (step.y_new + (q(h1) + (q(h2) + q(h3) * s) * s) * (1.0 - s)) * s
}

/// `rodas.f`'s step for any stiffly accurate [`Tableau`].
struct Standard<'a, const S: usize>(&'a Tableau<S>);

impl<const D: usize, const S: usize> Stepper<D, S> for Standard<'_, S> {
    type Lu = Lu<D>;
    type Step = Attempt<D, S>;

    fn factor(e: SMatrix<f64, D, D>) -> Option<Lu<D>> {
        Lu::new(e)
    }

    #[inline(always)]
    fn attempt<P: Problem<D>>(&self, problem: &mut P, lu: &Lu<D>, span: Span<D>) -> Attempt<D, S> {
        let (t, t_new, y, f0, dfdt) = (span.t, span.t_new, span.y, span.f0, span.dfdt);
        let tab = self.0;
        let h = t_new - t;
        let r = 1.0 / h;
        let mut k = [SVector::<f64, D>::zeros(); S];
        let mut u = *y;
        for i in 0..S {
            let f = if i == 0 {
                *f0
            } else {
                u = *y;
                for (k, &a) in k[..i].iter().zip(&tab.a[i][..i]) {
                    u += k * a;
                }
                // Stages at α = 1 are evaluated at t_new itself.
                let t_i = if tab.alpha[i] == 1.0 {
                    t_new
                } else {
                    t + tab.alpha[i] * h
                };
                problem.rhs(t_i, &u)
            };
            let mut b = f;
            if tab.d[i] != 0.0 {
                b += dfdt * (h * tab.d[i]);
            }
            for (k, &c) in k[..i].iter().zip(&tab.c[i][..i]) {
                b += k * (c * r);
            }
            k[i] = lu.solve(&b);
        }
        Attempt {
            y_new: u + k[S - 1],
            k,
        }
    }

    fn y_new(step: &Attempt<D, S>) -> &SVector<f64, D> {
        &step.y_new
    }

    fn estimate(step: &Attempt<D, S>) -> &SVector<f64, D> {
        &step.k[S - 1]
    }

    fn interpolate(
        &self,
        step: &mut Attempt<D, S>,
        t: f64,
        y: &SVector<f64, D>,
        h: f64,
        t_out: f64,
    ) -> SVector<f64, D> {
        interpolate(self.0, t, y, h, step, t_out)
    }
}

/// The Rodas5P main loop from `start` over a validated grid and settings: with the published step,
/// or with `lean`, the lean one of [`super::rodas_lean`] ([`super::Method::Fast`]).
pub(super) fn integrate<const D: usize, P, O>(
    problem: &mut P,
    start: Start<D>,
    grid: &[f64],
    s: &Settings,
    output: O,
    lean: bool,
) -> Result<Stats, IntegrationError>
where
    P: Problem<D>,
    O: FnMut(usize, f64, &SVector<f64, D>),
{
    if lean {
        run(&RODAS5P, &Lean, problem, start, grid, s, output)
    } else {
        run(
            &RODAS5P,
            &Standard(&RODAS5P),
            problem,
            start,
            grid,
            s,
            output,
        )
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use nalgebra::{matrix, vector, Matrix1, Matrix2, Matrix3, SVector};

    use super::super::{
        solve_grid, solve_grid_with_jacobian, uniform_grid, IntegrationError, Method, Options,
        Stats,
    };

    type V1 = SVector<f64, 1>;
    type V2 = SVector<f64, 2>;
    type V3 = SVector<f64, 3>;

    fn options(method: Method, rtol: f64, atol: f64) -> Options {
        Options {
            rtol,
            atol,
            method,
            ..Options::default()
        }
    }

    /// Steps of exactly `h` (a tolerance loose enough never to reject).
    fn fixed(h: f64) -> Options {
        Options {
            rtol: 1e3,
            atol: 1e3,
            initial_step: Some(h),
            max_step: Some(h),
            max_steps: 100_000,
            method: Method::Stiff,
        }
    }

    /// Prothero–Robinson: y' = −1000(y − cos t) − sin t, y(0) = 2, so y = cos t + e^(−1000 t).
    fn prothero_robinson(t: f64, y: &V1) -> V1 {
        vector![-1000.0 * (y[0] - t.cos()) - t.sin()]
    }

    fn prothero_robinson_jacobian(t: f64, _y: &V1) -> (Matrix1<f64>, V1) {
        (Matrix1::new(-1000.0), vector![-1000.0 * t.sin() - t.cos()])
    }

    fn prothero_robinson_exact(t: f64) -> f64 {
        t.cos() + (-1000.0 * t).exp()
    }

    /// Runs `solve`, checking the output indices, and returns the largest error against `exact`.
    fn max_error<const D: usize>(
        grid: &[f64],
        exact: impl Fn(f64) -> SVector<f64, D>,
        solve: impl FnOnce(&mut dyn FnMut(usize, f64, &SVector<f64, D>)) -> Stats,
    ) -> (f64, Stats) {
        let mut worst = 0.0f64;
        let mut seen = Vec::new();
        let stats = solve(&mut |i, t, y| {
            seen.push((i, t));
            worst = worst.max((y - exact(t)).amax());
        });
        let expected: Vec<_> = grid.iter().copied().enumerate().collect();
        assert_eq!(seen, expected);
        (worst, stats)
    }

    #[test]
    fn stiff_linear_problem_matches_closed_form_cheaply() {
        let grid = uniform_grid(0.0, 10.0, 0.1);
        let exact = |t: f64| vector![prothero_robinson_exact(t)];
        let y0 = vector![2.0];
        let explicit = options(Method::Explicit, 1e-3, 1e-6);
        let (e_dp5, dp5) = max_error(&grid, exact, |out| {
            solve_grid(prothero_robinson, &y0, &grid, &explicit, out).unwrap()
        });
        assert!(e_dp5 < 1e-2, "{e_dp5:e}");
        for method in [Method::Stiff, Method::Auto, Method::Fast] {
            let o = options(method, 1e-3, 1e-6);
            let (e, analytic) = max_error(&grid, exact, |out| {
                let jac = prothero_robinson_jacobian;
                solve_grid_with_jacobian(prothero_robinson, jac, &y0, &grid, &o, out).unwrap()
            });
            // Within the tolerance even between steps of up to 1 s (Rodas4's dense output is
            // off by 1e-2 there).
            assert!(e < 1e-3, "{method:?}: {e:e} {analytic:?}");
            assert!(analytic.jacobian_evals > 0, "{method:?}: {analytic:?}");
            assert!(
                10 * analytic.rhs_evals < dp5.rhs_evals,
                "{analytic:?} vs {dp5:?}"
            );
            // Finite differences: the same steps within rounding, D + 1 more evaluations a step.
            let (e_fd, fd) = max_error(&grid, exact, |out| {
                solve_grid(prothero_robinson, &y0, &grid, &o, out).unwrap()
            });
            assert!((e_fd - e).abs() < 1e-6, "{method:?}: {e_fd:e} vs {e:e}");
            assert_eq!(fd.steps, analytic.steps, "{fd:?} vs {analytic:?}");
            assert_eq!(fd.rhs_evals, analytic.rhs_evals + 2 * fd.jacobian_evals);
        }
        // The tolerance is honoured more tightly when the steps are kept short.
        let short = Options {
            max_step: Some(0.1),
            ..options(Method::Stiff, 1e-3, 1e-6)
        };
        let (e, _) = max_error(&grid, exact, |out| {
            let jac = prothero_robinson_jacobian;
            solve_grid_with_jacobian(prothero_robinson, jac, &y0, &grid, &short, out).unwrap()
        });
        assert!(e < 1e-6, "{e:e}");
    }

    /// Robertson's chemical kinetics (Hairer & Wanner II, §IV.1), stiff with λ down to −1e4.
    fn robertson(_t: f64, y: &V3) -> V3 {
        let (a, b, c) = (0.04, 1e4, 3e7);
        vector![
            -a * y[0] + b * y[1] * y[2],
            a * y[0] - b * y[1] * y[2] - c * y[1] * y[1],
            c * y[1] * y[1]
        ]
    }

    fn robertson_jacobian(_t: f64, y: &V3) -> (Matrix3<f64>, V3) {
        let (a, b, c) = (0.04, 1e4, 3e7);
        let j = matrix![
            -a, b * y[2], b * y[1];
            a, -b * y[2] - 2.0 * c * y[1], -b * y[1];
            0.0, 2.0 * c * y[1], 0.0
        ];
        (j, V3::zeros())
    }

    #[test]
    fn robertson_matches_a_tight_reference_and_conserves_mass() {
        let grid = [0.0, 0.4, 4.0, 40.0, 400.0, 4e3, 4e4, 4e5];
        let run = |rtol: f64, atol: f64| {
            let o = Options {
                max_step: Some(1e5),
                ..options(Method::Stiff, rtol, atol)
            };
            let mut out = Vec::new();
            let stats = solve_grid_with_jacobian(
                robertson,
                robertson_jacobian,
                &vector![1.0, 0.0, 0.0],
                &grid,
                &o,
                |_, _, y| out.push(*y),
            )
            .unwrap();
            (out, stats)
        };
        let (reference, _) = run(1e-10, 1e-14);
        // Hairer & Wanner's reference values at t = 40.
        let at_40 = vector![
            0.7158270687193488,
            0.9185534764557368e-5,
            0.2841637457458438
        ];
        assert!((reference[3] - at_40).amax() < 1e-9, "{}", reference[3]);
        let (out, stats) = run(1e-4, 1e-10);
        assert!(stats.steps < 150, "{stats:?}");
        for (y, r) in out.iter().zip(&reference) {
            // A Rosenbrock step conserves the linear invariant y1 + y2 + y3 to rounding.
            assert!((y.sum() - 1.0).abs() < 1e-13, "{y}");
            for i in [0, 2] {
                assert!(
                    (y[i] - r[i]).abs() <= 1e-4 * r[i].abs() + 1e-10,
                    "{y} vs {r}"
                );
            }
            assert!((y[1] - r[1]).abs() <= 1e-3 * r[1], "{y} vs {r}");
        }
    }

    /// Van der Pol with μ = 1000 (MATLAB's `vdp1000`): relaxation oscillations of period ≈ 1614.
    fn van_der_pol(_t: f64, y: &V2) -> V2 {
        vector![y[1], 1000.0 * (1.0 - y[0] * y[0]) * y[1] - y[0]]
    }

    fn van_der_pol_jacobian(_t: f64, y: &V2) -> (Matrix2<f64>, V2) {
        let j = matrix![
            0.0, 1.0;
            -2000.0 * y[0] * y[1] - 1.0, 1000.0 * (1.0 - y[0] * y[0])
        ];
        (j, V2::zeros())
    }

    #[test]
    fn van_der_pol_mu_1000_through_three_relaxation_jumps() {
        let grid = uniform_grid(0.0, 3000.0, 100.0);
        let run = |o: &Options| {
            let mut out = Vec::new();
            let jac = van_der_pol_jacobian;
            let stats = solve_grid_with_jacobian(
                van_der_pol,
                jac,
                &vector![2.0, 0.0],
                &grid,
                o,
                |_, _, y| out.push(y[0]),
            )
            .unwrap();
            (out, stats)
        };
        let (reference, _) = run(&options(Method::Stiff, 1e-9, 1e-9));
        // A jump from ≈ ±1 to ∓2 every half period (≈ 807): three by t = 3000.
        let jumps = reference.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
        assert_eq!(jumps, 3, "{reference:?}");
        for method in [Method::Stiff, Method::Auto, Method::Fast] {
            let (out, stats) = run(&options(method, 1e-3, 1e-6));
            assert!(stats.steps < 600, "{method:?}: {stats:?}");
            let worst = out
                .iter()
                .zip(&reference)
                .map(|(y, r)| (y - r).abs())
                .fold(0.0, f64::max);
            assert!(worst < 2e-3, "{method:?}: {worst:e}");
        }
    }

    /// y' = cos t − (y − sin t), y(0) = 1: y = sin t + e^(−t), with ∂f/∂t = −sin t + cos t.
    fn forced(t: f64, y: &V1) -> V1 {
        vector![t.cos() - (y[0] - t.sin())]
    }

    fn forced_jacobian(t: f64, _y: &V1) -> (Matrix1<f64>, V1) {
        (Matrix1::new(-1.0), vector![t.cos() - t.sin()])
    }

    #[test]
    fn fixed_steps_converge_at_fifth_order_and_the_interpolant_at_fourth() {
        // Errors at the step ends (t multiple of h) and between them (the dense output).
        let errors = |h: f64| {
            let grid = uniform_grid(0.0, 4.0, 0.025);
            let (mut at_ends, mut between) = (0.0f64, 0.0f64);
            let stats = solve_grid_with_jacobian(
                forced,
                forced_jacobian,
                &vector![1.0],
                &grid,
                &fixed(h),
                |_, t, y| {
                    let e = (y[0] - t.sin() - (-t).exp()).abs();
                    if ((t / h) - (t / h).round()).abs() < 1e-9 {
                        at_ends = at_ends.max(e);
                    } else {
                        between = between.max(e);
                    }
                },
            )
            .unwrap();
            assert_eq!(
                (stats.steps, stats.rejected),
                ((4.0 / h).round() as usize, 0)
            );
            (at_ends, between)
        };
        let (coarse, coarse_between) = errors(0.4);
        let (fine, fine_between) = errors(0.2);
        let order = (coarse / fine).log2();
        assert!(
            (4.6..6.0).contains(&order),
            "order {order}: {coarse:e} -> {fine:e}"
        );
        let order = (coarse_between / fine_between).log2();
        assert!(
            order > 3.7,
            "dense order {order}: {coarse_between:e} -> {fine_between:e}"
        );
    }

    #[test]
    fn l_stable_and_a_stable_on_single_steps() {
        // y' = λy, one step of h = 1: R(λ) → 0 as λ → −∞ (L-stability), |R| ≤ 1 for λ < 0.
        for lambda in [-1e-2, -1.0, -10.0, -1e3, -1e6, -1e10] {
            let mut y1 = f64::NAN;
            solve_grid_with_jacobian(
                move |_, y: &V1| y * lambda,
                move |_, _| (Matrix1::new(lambda), V1::zeros()),
                &vector![1.0],
                &[0.0, 1.0],
                &fixed(1.0),
                |i, _, y| {
                    if i == 1 {
                        y1 = y[0]
                    }
                },
            )
            .unwrap();
            assert!(y1.abs() <= 1.0, "R({lambda}) = {y1}");
            if lambda <= -1e6 {
                assert!(y1.abs() < 20.0 / lambda.abs(), "R({lambda}) = {y1}");
            }
            if lambda == -1e-2 {
                assert!((y1 - lambda.exp()).abs() < 1e-12, "R({lambda}) = {y1}");
            }
        }
        // A rotation (eigenvalues ±iω) never grows, however large ω·h.
        for omega in [0.1, 1.0, 10.0, 1e3, 1e6] {
            let mut norm = f64::NAN;
            solve_grid_with_jacobian(
                move |_, y: &V2| vector![omega * y[1], -omega * y[0]],
                move |_, _| (matrix![0.0, omega; -omega, 0.0], V2::zeros()),
                &vector![1.0, 0.0],
                &[0.0, 1.0],
                &fixed(1.0),
                |i, _, y| {
                    if i == 1 {
                        norm = y.norm()
                    }
                },
            )
            .unwrap();
            assert!(norm <= 1.0 + 1e-12, "|R(i{omega})| = {norm}");
        }
    }

    #[test]
    fn evaluation_counts_match_the_calls() {
        let grid = uniform_grid(0.0, 2.0, 0.1);
        let y0 = vector![2.0];
        let (rhs_calls, jac_calls) = (Cell::new(0), Cell::new(0));
        let rhs = |t: f64, y: &V1| {
            rhs_calls.set(rhs_calls.get() + 1);
            prothero_robinson(t, y)
        };
        let jac = |t: f64, y: &V1| {
            jac_calls.set(jac_calls.get() + 1);
            prothero_robinson_jacobian(t, y)
        };
        // A first step of 0.5 is rejected (the e^(−1000 t) transient), so retries are counted.
        let o = Options {
            initial_step: Some(0.5),
            ..options(Method::Stiff, 1e-3, 1e-6)
        };
        let s = solve_grid_with_jacobian(rhs, jac, &y0, &grid, &o, |_, _, _| {}).unwrap();
        assert!(s.rejected > 0, "{s:?}");
        assert_eq!(s.rhs_evals, rhs_calls.get());
        assert_eq!(s.jacobian_evals, jac_calls.get());
        assert_eq!(s.jacobian_evals, s.steps);
        assert_eq!(s.factorisations, s.steps + s.rejected);
        assert_eq!(s.rhs_evals, s.steps + 7 * (s.steps + s.rejected));

        // Finite differences: D + 1 = 2 more evaluations per Jacobian.
        rhs_calls.set(0);
        let s = solve_grid(rhs, &y0, &grid, &o, |_, _, _| {}).unwrap();
        assert_eq!(s.rhs_evals, rhs_calls.get());
        assert_eq!(s.rhs_evals, 3 * s.steps + 7 * (s.steps + s.rejected));

        // Auto: DP5's FSAL count until the switch, then Rodas5P's, which reuses DP5's f(t, y).
        rhs_calls.set(0);
        jac_calls.set(0);
        let o = options(Method::Auto, 1e-3, 1e-6);
        let s = solve_grid_with_jacobian(rhs, jac, &y0, &grid, &o, |_, _, _| {}).unwrap();
        assert_eq!(s.rhs_evals, rhs_calls.get());
        assert_eq!(s.jacobian_evals, jac_calls.get());
        assert!(s.jacobian_evals > 0 && s.jacobian_evals < s.steps, "{s:?}");
    }

    #[test]
    fn auto_is_dp5_bit_for_bit_on_a_nonstiff_problem() {
        let oscillator = |_t: f64, y: &V2| vector![y[1], -y[0]];
        let no_jacobian = |_t: f64, _y: &V2| -> (Matrix2<f64>, V2) {
            panic!("the Jacobian is not needed while DP5 runs")
        };
        let grid = uniform_grid(0.0, 20.0, 0.05);
        let run = |method| {
            let mut out = Vec::new();
            let o = options(method, 1e-6, 1e-9);
            let stats = solve_grid_with_jacobian(
                oscillator,
                no_jacobian,
                &vector![1.0, 0.0],
                &grid,
                &o,
                |_, _, y| out.push(*y),
            )
            .unwrap();
            (out, stats)
        };
        assert_eq!(run(Method::Auto), run(Method::Explicit));
    }

    #[test]
    fn non_finite_values_are_errors() {
        let grid = uniform_grid(0.0, 2.0, 0.1);
        let y0 = vector![2.0];
        for method in [Method::Stiff, Method::Auto, Method::Fast] {
            let o = options(method, 1e-3, 1e-6);
            // A NaN right-hand side after t = 1.
            let rhs = |t: f64, y: &V1| {
                if t > 1.0 {
                    vector![f64::NAN]
                } else {
                    prothero_robinson(t, y)
                }
            };
            let mut last = 0.0;
            let result = solve_grid_with_jacobian(
                rhs,
                prothero_robinson_jacobian,
                &y0,
                &grid,
                &o,
                |_, t, y| {
                    assert!(y[0].is_finite());
                    last = t;
                },
            );
            match result {
                Err(IntegrationError::NonFinite { t }) => assert!(t > 1.0 && t < 2.0, "{t}"),
                other => panic!("{method:?}: {other:?}"),
            }
            assert!(last <= 1.0 + 1e-12, "{last}");
            // A NaN Jacobian.
            let jac = |_t: f64, _y: &V1| (Matrix1::new(f64::NAN), V1::zeros());
            let result =
                solve_grid_with_jacobian(prothero_robinson, jac, &y0, &grid, &o, |_, _, _| {});
            assert!(
                matches!(result, Err(IntegrationError::NonFinite { .. })),
                "{method:?}: {result:?}"
            );
        }
        // A non-finite initial state or slope.
        let o = options(Method::Stiff, 1e-3, 1e-6);
        let jac = prothero_robinson_jacobian;
        let e = solve_grid_with_jacobian(
            prothero_robinson,
            jac,
            &vector![f64::INFINITY],
            &grid,
            &o,
            |_, _, _| {},
        );
        assert_eq!(e, Err(IntegrationError::NonFinite { t: 0.0 }));
        let nan = |_t: f64, _y: &V1| vector![f64::NAN];
        let e = solve_grid_with_jacobian(nan, jac, &y0, &grid, &o, |_, _, _| {});
        assert_eq!(e, Err(IntegrationError::NonFinite { t: 0.0 }));
    }

    #[test]
    fn singular_iteration_matrix_halves_the_step() {
        // y' = γ⁻¹·y with h = 1: E = I/(h·γ) − J = 0 on the first attempt.
        let gamma = super::RODAS5P.gamma;
        let lambda = 1.0 / gamma;
        let o = Options {
            initial_step: Some(1.0),
            max_step: Some(1.0),
            ..options(Method::Stiff, 1e-6, 1e-9)
        };
        let mut y2 = f64::NAN;
        let stats = solve_grid_with_jacobian(
            move |_, y: &V1| y * lambda,
            move |_, _| (Matrix1::new(lambda), V1::zeros()),
            &vector![1.0],
            &[0.0, 2.0],
            &o,
            |i, _, y| {
                if i == 1 {
                    y2 = y[0]
                }
            },
        )
        .unwrap();
        assert!(stats.rejected >= 1, "{stats:?}");
        let exact = (2.0 * lambda).exp();
        assert!(((y2 - exact) / exact).abs() < 1e-4, "{y2} vs {exact}");
    }

    #[test]
    fn step_limit_and_step_size_floor_are_enforced() {
        let o = Options {
            max_steps: 5,
            ..options(Method::Stiff, 1e-3, 1e-6)
        };
        let jac = prothero_robinson_jacobian;
        let e = solve_grid_with_jacobian(
            prothero_robinson,
            jac,
            &vector![2.0],
            &[0.0, 10.0],
            &o,
            |_, _, _| {},
        );
        match e {
            Err(IntegrationError::TooManySteps {
                t, max_steps: 5, ..
            }) => assert!(t > 0.0 && t < 10.0),
            other => panic!("{other:?}"),
        }
        // y' = y², y(0) = 1 blows up at t = 1. A linearly implicit step can land just past the
        // pole, where the next steps then shrink to nothing.
        let e = solve_grid_with_jacobian(
            |_, y: &V1| vector![y[0] * y[0]],
            |_, y: &V1| (Matrix1::new(2.0 * y[0]), V1::zeros()),
            &vector![1.0],
            &uniform_grid(0.0, 2.0, 0.1),
            &options(Method::Stiff, 1e-3, 1e-6),
            |_, t, y| assert!(t <= 1.0 && y[0].is_finite()),
        );
        match e {
            Err(
                IntegrationError::StepSizeTooSmall { t, .. } | IntegrationError::NonFinite { t },
            ) => {
                assert!(t > 0.99 && t < 1.01, "stopped at {t}")
            }
            other => panic!("{other:?}"),
        }
    }
}
