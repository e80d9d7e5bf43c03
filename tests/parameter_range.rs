//! The valid input ranges (crates/core/src/validate.rs, crates/model/src/validate.rs) keep the
//! generated arithmetic finite: every generated function of every model, at every corner of the
//! parameter box (each "> 0" parameter in [1e-6, 1e6], each signed one, a URDF tool's centre of
//! mass, over its model's domain) that the model's rule admits, and at its centre, for every task with the paper's precisions and with precisions at
//! their bound 1e6 and at 1e-6, at the equilibrium and at a state and torque at the divergence
//! bound, gives finite numbers (the magnitude analysis behind the ranges is
//! python/tests/test_parameter_range.py). ln|Π^U| is finite, or, where the corner makes Π^U too
//! ill-conditioned for double precision, a typed error; over [1e-2, 1e2]^NP it is always
//! computed. Just outside the box, a tool is refused.

use nalgebra::{SMatrix, SVector};
use toolconf_generated as generated;
use toolconf_generated::validity::ToolRule;
use toolconf_model::model::Error;
use toolconf_model::model::{logdet_of, reads_tip, ArmModel, TaskN, ToolN};
use toolconf_model::validate::{STATE_BOUND, TOOL_PARAMETER};
use toolconf_model::{TaskKind, Term};

/// The corners of the box `boxes` (one interval per parameter) that the model's rule admits
/// (a URDF tool's inertia tensor a rigid body's), and its centre: in ln p for a "> 0" parameter,
/// the midpoint for a signed one (a centre of mass). The parameters a tool may leave out (a URDF
/// tool's products of inertia and tip) move together, to both ends of their intervals at once:
/// each corner of the others is taken with them at their lower ends and at their upper ends
/// (2^13 corners of every parameter apart would take minutes, and the products are bounded by
/// the moments, not by a box of their own).
fn points<const NP: usize>(rule: &ToolRule<NP>, boxes: [(f64, f64); NP]) -> Vec<[f64; NP]> {
    let linked: Vec<usize> = (0..NP).filter(|&j| rule.defaults[j].is_some()).collect();
    let free: Vec<usize> = (0..NP).filter(|j| !linked.contains(j)).collect();
    let mut points = Vec::new();
    for bits in 0..1usize << free.len() {
        for upper in [false, true] {
            points.push(std::array::from_fn(|j| {
                let high = match free.iter().position(|&f| f == j) {
                    Some(k) => bits >> k & 1 == 1,
                    None => upper,
                };
                if high {
                    boxes[j].1
                } else {
                    boxes[j].0
                }
            }));
        }
    }
    points.push(std::array::from_fn(|j| {
        let (lo, hi) = boxes[j];
        if rule.domains[j].is_positive() {
            (lo * hi).sqrt()
        } else {
            0.5 * (lo + hi)
        }
    }));
    points.retain(|p| rule.check(p).is_ok());
    points
}

/// Per parameter: `positive` for a "> 0" domain, a quarter of its lower end either way for a
/// product of inertia (a tensor whose moments are all at least that stays a rigid body's for
/// most corners), else the domain itself within ±1e6.
fn boxes<const NP: usize>(rule: &ToolRule<NP>, positive: (f64, f64)) -> [(f64, f64); NP] {
    std::array::from_fn(|j| {
        let d = &rule.domains[j];
        if d.is_positive() {
            positive
        } else if rule.inertia.is_some_and(|i| i.products.contains(&j)) {
            (-0.25 * positive.0, 0.25 * positive.0)
        } else {
            (d.lo.max(-TOOL_PARAMETER.hi), d.hi.min(TOOL_PARAMETER.hi))
        }
    })
}

/// The paper's task, and its precisions (on the terms it uses) all at `value`·I.
fn tasks<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    kind: TaskKind,
) -> Vec<TaskN<N>>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let paper = M::paper_task(kind);
    let mut tasks = vec![paper];
    for value in [1e6, 1e-6] {
        let p = SMatrix::<f64, N, N>::identity() * value;
        let mut t = paper;
        let used = |term| if kind.uses(term) { p } else { SMatrix::zeros() };
        t.precision[Term::Theta.index()] = used(Term::Theta);
        t.precision[Term::ThetaDot.index()] = used(Term::ThetaDot);
        t.precision[Term::ThetaDdot.index()] = used(Term::ThetaDdot);
        t.precision[Term::U.index()] = used(Term::U);
        tasks.push(t);
    }
    tasks
}

fn finite(what: &str, at: &[f64], values: impl IntoIterator<Item = f64>) {
    let values: Vec<f64> = values.into_iter().collect();
    assert!(
        values.iter().all(|v| v.is_finite()),
        "{what} at p = {at:?}: {values:?}"
    );
}

fn check<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>()
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let extreme_x = SVector::<f64, NX>::repeat(STATE_BOUND);
    let extreme_u = SVector::<f64, N>::repeat(STATE_BOUND);
    let rule = &M::tool_rule();
    let positive: Vec<usize> = (0..NP).filter(|&j| rule.domains[j].is_positive()).collect();
    let well_conditioned = |p: &[f64; NP]| positive.iter().all(|&j| (1e-2..=1e2).contains(&p[j]));
    // A tip task's sensitivity J ∂θ/∂U carries the tip's lever arm, linear in the lengths, into
    // Π^U squared: the box within which its condition stays that of the joint tasks is the square
    // root of theirs, [1e-1, 1e1] (arm2_payload at l = 100 m, m = 0.01 kg: |Π^U| / Π Π_ii = 3e-12).
    let well_conditioned_tip =
        |p: &[f64; NP]| positive.iter().all(|&j| (1e-1..=1e1).contains(&p[j]));
    let mut corners = points(rule, boxes(rule, (TOOL_PARAMETER.lo, TOOL_PARAMETER.hi)));
    corners.extend(points(rule, boxes(rule, (1e-2, 1e2))));
    assert!(corners.len() > NP, "{} corners", corners.len());
    for p in corners {
        let tool = ToolN::<M, N, NX, NP, NZ>::new(p).expect("a corner of the valid box");
        let params = tool.params();
        finite("A", &p, tool.state_matrix().iter().copied());
        finite("B", &p, tool.input_matrix().iter().copied());
        for (x, u) in [
            (M::equilibrium_state(), SVector::zeros()),
            (extreme_x, extreme_u),
        ] {
            finite("f(X, U)", &p, M::dynamics(&x, &u, &params).iter().copied());
            let (fx, fu) = M::dynamics_jacobian(&x, &u, &params);
            finite("∂f/∂X, ∂f/∂U", &p, fx.iter().chain(fu.iter()).copied());
        }
        for kind in TaskKind::ALL {
            let s = tool.sensitivities(kind);
            for m in Term::ALL.iter().filter_map(|t| s.of(*t)) {
                finite("a sensitivity", &p, m.iter().copied());
            }
            for task in tasks::<M, N, NX, NP, NZ>(kind) {
                let pi = M::pi_u(&task, &params);
                finite("Π^U", &p, pi.iter().copied());
                match logdet_of(&pi) {
                    Ok(logdet) => {
                        finite("ln|Π^U|", &p, [logdet]);
                        let gradient = M::logdet_gradient(&task, &params);
                        finite("∂ln|Π^U|/∂p", &p, gradient.iter().copied());
                    }
                    Err(Error::IllConditioned { .. }) if !well_conditioned(&p) => {}
                    Err(Error::IllConditioned { .. })
                        if reads_tip(kind) && !well_conditioned_tip(&p) => {}
                    Err(e) => panic!("{kind} at {p:?}: {e}"),
                }
            }
        }
    }
    let (first, last) = (positive[0], positive[positive.len() - 1]);
    for (j, outside) in [
        (first, TOOL_PARAMETER.lo * 0.999),
        (last, TOOL_PARAMETER.hi * 1.001),
    ] {
        let mut p = points(rule, boxes(rule, (1.0, 1.0)))[0];
        p[j] = outside;
        assert!(matches!(
            ToolN::<M, N, NX, NP, NZ>::new(p),
            Err(Error::InvalidParameter { .. })
        ));
    }
}

macro_rules! range_tests {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        mod generated_arithmetic_is_finite_over_the_valid_box {
            use super::*;
            $(
                #[test]
                fn $module() {
                    check::<
                        toolconf_model::model::$marker,
                        { generated::$module::DOF },
                        { generated::$module::STATE_DIM },
                        { generated::$module::PARAMETER_COUNT },
                        { generated::$module::STATE_DIM + generated::$module::DOF },
                    >();
                }
            )*
        }
    };
}

toolconf_generated::for_each_model!(range_tests);
