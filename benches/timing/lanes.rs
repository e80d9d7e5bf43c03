//! "SIMD across tools", measured: several tools' DP5 episodes advanced in
//! f64 lanes, each lane with its own step size, a finished lane refilled with the next tool.
//!
//! The same lane code runs at width 1 (the scalar baseline), 4 and 8, compiled for baseline
//! x86-64 (SSE2) and, through `#[target_feature(enable = "avx2")]`, for AVX2. Every lane does
//! exactly the scalar arithmetic, so the results are checked bit for bit against width 1, and
//! width 1's right-hand side against the library's `ClosedLoopN::rhs`.
//!
//! The integrator is DP5 with ode45's error norm and a standard step controller, from t = 0 to
//! 5 s with no dense output: the accuracy-limited and stability-limited work of an episode, which
//! is what lanes would change. Run: `cargo run --release --example lanes [-- --tools N --task T]`.
//! Measurements and conclusions: docs/explanation/performance-population.md.

#![allow(clippy::needless_range_loop)] // lane code indexes its lanes by design

use std::ops::{Add, Div, Mul, Neg, Sub};
use std::time::Instant;

use nalgebra::SVector;
use toolconf::select::draw_tools;
use toolconf_generated::arm2::DynamicsCoefficients;
use toolconf_model::model::{Arm2, ArmModel, ClosedLoopN, TaskN};
use toolconf_model::{Task, TaskKind};

/// One f64 per lane, each lane a tool: what a SIMD register of W doubles holds.
#[derive(Clone, Copy, Debug)]
struct PerLane<const W: usize>([f64; W]);

macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<const W: usize> $tr for PerLane<W> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                let mut r = self.0;
                for i in 0..W {
                    r[i] = self.0[i] $op o.0[i];
                }
                PerLane(r)
            }
        }
        impl<const W: usize> $tr<f64> for PerLane<W> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: f64) -> Self {
                let mut r = self.0;
                for i in 0..W {
                    r[i] = self.0[i] $op o;
                }
                PerLane(r)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<const W: usize> Neg for PerLane<W> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        PerLane(self.0.map(|x| -x))
    }
}

impl<const W: usize> PerLane<W> {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        PerLane([x; W])
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        PerLane(self.0.map(f))
    }
    #[inline(always)]
    fn select(mask: [bool; W], a: Self, b: Self) -> Self {
        let mut r = b.0;
        for i in 0..W {
            if mask[i] {
                r[i] = a.0[i];
            }
        }
        PerLane(r)
    }
}

#[inline(always)]
fn sin_cos<const W: usize>(x: PerLane<W>) -> (PerLane<W>, PerLane<W>) {
    let (s, c) = toolconf_generated::trig::sin_cos_lanes(x.0);
    (PerLane(s), PerLane(c))
}

/// One lane per tool: the plant's coefficients and the controller's gains γK_θ, γK_θ̇, γK_θ̈, γP^U
/// (row-major 2 × 2) and goals.
#[derive(Clone, Copy)]
struct Loop<const W: usize> {
    k: [PerLane<W>; 8],
    gains: [[PerLane<W>; 4]; 4],
    goals: [[PerLane<W>; 2]; 3],
}

type Z<const W: usize> = [PerLane<W>; 6];

#[inline(always)]
fn rhs<const W: usize>(p: &Loop<W>, z: &Z<W>) -> Z<W> {
    let [th1, th2, th1d, th2d, u1, u2] = *z;
    let [k0, k1, k2, k3, k4, k5, k6, k7] = p.k;
    let (s1, c1) = sin_cos(th1);
    let (s2, c2) = sin_cos(th2);
    let trig0 = -c1 * s2 + c2 * s1;
    let trig1 = c1 * c2 + s1 * s2;
    let (t1, t2) = (u1 + 0.0, u2 + 0.0);
    let a1 = c1 * k2 + c2 * k5 * trig1 + k0 * t1 - k0 * t2
        + k1 * t2 * trig1
        + k3 * (th1d * th1d) * trig0
        + k4 * (th2d * th2d) * trig0;
    let a2 = c2 * k7 + k6 * t2;
    let e = [
        [th1 - p.goals[0][0], th2 - p.goals[0][1]],
        [th1d - p.goals[1][0], th2d - p.goals[1][1]],
        [a1 - p.goals[2][0], a2 - p.goals[2][1]],
        [u1, u2],
    ];
    let mv = |m: &[PerLane<W>; 4], v: &[PerLane<W>; 2]| {
        [m[0] * v[0] + m[1] * v[1], m[2] * v[0] + m[3] * v[1]]
    };
    let [g0, g1, g2, g3] = [
        mv(&p.gains[0], &e[0]),
        mv(&p.gains[1], &e[1]),
        mv(&p.gains[2], &e[2]),
        mv(&p.gains[3], &e[3]),
    ];
    let du = |i: usize| -(((g0[i] + g1[i]) + g2[i]) + g3[i]);
    [th1d, th2d, a1, a2, du(0), du(1)]
}

const A: [[f64; 5]; 5] = [
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
    ],
];
const B: [f64; 6] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
];
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

#[inline(always)]
fn combine<const W: usize>(y: &Z<W>, k: &[Z<W>], a: &[f64], h: PerLane<W>) -> Z<W> {
    let mut out = *y;
    for c in 0..6 {
        let mut s = k[0][c] * a[0];
        for j in 1..k.len() {
            if a[j] != 0.0 {
                s = s + k[j][c] * a[j];
            }
        }
        out[c] = y[c] + s * h;
    }
    out
}

const RTOL: f64 = 1e-3;
const ATOL: f64 = 1e-6;
const T_END: f64 = 5.0;
const H_MAX: f64 = 0.5;

/// Per-lane episode bookkeeping.
struct Lanes<const W: usize> {
    p: Loop<W>,
    y: Z<W>,
    k1: Z<W>,
    t: PerLane<W>,
    h: PerLane<W>,
    tool: [usize; W],
    rhs: [usize; W],
}

fn load<const W: usize>(lanes: &mut Lanes<W>, lane: usize, src: &Loop<1>, tool: usize, z0: &Z<1>) {
    for i in 0..8 {
        lanes.p.k[i].0[lane] = src.k[i].0[0];
    }
    for a in 0..4 {
        for b in 0..4 {
            lanes.p.gains[a][b].0[lane] = src.gains[a][b].0[0];
        }
    }
    for a in 0..3 {
        for b in 0..2 {
            lanes.p.goals[a][b].0[lane] = src.goals[a][b].0[0];
        }
    }
    for c in 0..6 {
        lanes.y[c].0[lane] = z0[c].0[0];
    }
    lanes.t.0[lane] = 0.0;
    lanes.h.0[lane] = 0.01;
    lanes.tool[lane] = tool;
    lanes.rhs[lane] = 1;
}

/// Integrates every tool's closed loop to T_END; returns (final state, RHS count) per tool.
#[inline(always)]
fn run_lanes<const W: usize>(loops: &[Loop<1>], z0: &Z<1>) -> Vec<([f64; 6], usize)> {
    let mut out = vec![([0.0; 6], 0); loops.len()];
    let zero = Loop {
        k: [PerLane::splat(0.0); 8],
        gains: [[PerLane::splat(0.0); 4]; 4],
        goals: [[PerLane::splat(0.0); 2]; 3],
    };
    let mut lanes = Lanes {
        p: zero,
        y: [PerLane::splat(0.0); 6],
        k1: [PerLane::splat(0.0); 6],
        t: PerLane::splat(T_END),
        h: PerLane::splat(0.01),
        tool: [usize::MAX; W],
        rhs: [0; W],
    };
    let mut next = 0;
    let mut active = [false; W];
    for lane in 0..W.min(loops.len()) {
        load(&mut lanes, lane, &loops[next], next, z0);
        active[lane] = true;
        next += 1;
    }
    lanes.k1 = rhs(&lanes.p, &lanes.y);
    let threshold = ATOL / RTOL;
    while active.iter().any(|&a| a) {
        let t_new = PerLane(std::array::from_fn(|i| {
            (lanes.t.0[i] + lanes.h.0[i]).min(T_END)
        }));
        let h = t_new - lanes.t;
        let y = lanes.y;
        let k1 = lanes.k1;
        let k2 = rhs(&lanes.p, &combine(&y, &[k1], &A[0][..1], h));
        let k3 = rhs(&lanes.p, &combine(&y, &[k1, k2], &A[1][..2], h));
        let k4 = rhs(&lanes.p, &combine(&y, &[k1, k2, k3], &A[2][..3], h));
        let k5 = rhs(&lanes.p, &combine(&y, &[k1, k2, k3, k4], &A[3][..4], h));
        let k6 = rhs(&lanes.p, &combine(&y, &[k1, k2, k3, k4, k5], &A[4], h));
        let y_new = combine(&y, &[k1, k2, k3, k4, k5, k6], &B, h);
        let k7 = rhs(&lanes.p, &y_new);
        let ks = [k1, k2, k3, k4, k5, k6, k7];
        let mut err = PerLane::<W>::splat(0.0);
        for c in 0..6 {
            let mut ek = ks[0][c] * E[0];
            for j in 2..7 {
                ek = ek + ks[j][c] * E[j];
            }
            let scale = PerLane(std::array::from_fn(|i| {
                y[c].0[i].abs().max(y_new[c].0[i].abs()).max(threshold)
            }));
            let r = (ek * h / scale).map(f64::abs);
            err = PerLane(std::array::from_fn(|i| err.0[i].max(r.0[i])));
        }
        let mut accept = [false; W];
        let mut fac = [0.0; W];
        for i in 0..W {
            let e = err.0[i] / RTOL;
            accept[i] = active[i] && e <= 1.0;
            let f = 0.9 * e.powf(-0.2);
            fac[i] = if f >= 0.2 { f.min(5.0) } else { 0.2 };
            lanes.rhs[i] += 6;
        }
        for c in 0..6 {
            lanes.y[c] = PerLane::select(accept, y_new[c], y[c]);
            lanes.k1[c] = PerLane::select(accept, k7[c], k1[c]);
        }
        lanes.t = PerLane::select(accept, t_new, lanes.t);
        lanes.h = PerLane(std::array::from_fn(|i| (h.0[i] * fac[i]).min(H_MAX)));
        refill(&mut lanes, &mut active, &mut next, loops, z0, &mut out);
    }
    out
}

/// Stores each lane that reached T_END into `out` and loads the next tool into it (or retires
/// it when none is left).
#[inline(always)]
fn refill<const W: usize>(
    lanes: &mut Lanes<W>,
    active: &mut [bool; W],
    next: &mut usize,
    loops: &[Loop<1>],
    z0: &Z<1>,
    out: &mut [([f64; 6], usize)],
) {
    let mut refilled = false;
    for lane in 0..W {
        if active[lane] && lanes.t.0[lane] >= T_END {
            out[lanes.tool[lane]] = (std::array::from_fn(|c| lanes.y[c].0[lane]), lanes.rhs[lane]);
            if *next < loops.len() {
                load(lanes, lane, &loops[*next], *next, z0);
                *next += 1;
                refilled = true;
            } else {
                active[lane] = false;
                lanes.t.0[lane] = T_END;
                lanes.h.0[lane] = 0.01;
            }
        }
    }
    if refilled {
        // A refilled lane needs its own k1; the others keep theirs (FSAL), bit for bit.
        let fresh = rhs(&lanes.p, &lanes.y);
        for lane in 0..W {
            if lanes.t.0[lane] == 0.0 && active[lane] {
                for c in 0..6 {
                    lanes.k1[c].0[lane] = fresh[c].0[lane];
                }
            }
        }
    }
}

#[target_feature(enable = "avx2")]
fn run_lanes_avx2<const W: usize>(loops: &[Loop<1>], z0: &Z<1>) -> Vec<([f64; 6], usize)> {
    run_lanes::<W>(loops, z0)
}

fn lane_loop(
    arm: &toolconf_model::Arm,
    task: &TaskN<2>,
) -> (Loop<1>, ClosedLoopN<Arm2, 2, 4, 4, 6>) {
    let tool = *arm;
    let cl = ClosedLoopN::<Arm2, 2, 4, 4, 6>::new(&tool, task, 1.0, 0.0).expect("closed loop");
    let coeff = DynamicsCoefficients::new(&tool.params());
    let gains = cl.controller.scaled_gains();
    let m = |g: &nalgebra::Matrix2<f64>| {
        [
            PerLane([g[(0, 0)]]),
            PerLane([g[(0, 1)]]),
            PerLane([g[(1, 0)]]),
            PerLane([g[(1, 1)]]),
        ]
    };
    let t = &cl.controller.task;
    let v = |g: &SVector<f64, 2>| [PerLane([g[0]]), PerLane([g[1]])];
    let p = Loop {
        k: coeff.k.map(|k| PerLane([k])),
        gains: [m(&gains[0]), m(&gains[1]), m(&gains[2]), m(&gains[3])],
        // The goals of the terms read from X and Ẋ, in term order (the control's is zero).
        goals: std::array::from_fn(|i| v(&t.goal[i])),
    };
    (p, cl)
}

/// A way to run the lanes: its width, its build, and the run.
type Variant<'a> = (
    usize,
    &'static str,
    Box<dyn Fn(&[Loop<1>]) -> Vec<([f64; 6], usize)> + 'a>,
);

/// `--tools N`, `--task T` and `--rounds R`, with their defaults.
fn arguments() -> (usize, Vec<TaskKind>, usize) {
    let mut tools_n = 2000;
    let mut kinds: Vec<TaskKind> = vec!["position".parse().unwrap(), "velocity".parse().unwrap()];
    let mut rounds = 5;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--tools" => tools_n = it.next().unwrap().parse().unwrap(),
            "--task" => kinds = vec![it.next().unwrap().parse().unwrap()],
            "--rounds" => rounds = it.next().unwrap().parse().unwrap(),
            other => panic!("unknown argument {other}"),
        }
    }
    (tools_n, kinds, rounds)
}

fn main() {
    let (tools_n, kinds, rounds) = arguments();
    let arms = draw_tools(tools_n, 1);
    println!(
        "{tools_n} tools (draw_tools({tools_n}, 1)), one thread, fastest of {rounds} rounds per 64-tool chunk, variants alternating; avx2 detected: {}",
        is_x86_feature_detected!("avx2")
    );
    println!("| task | lanes | build | µs per tool | × width 1 | mean RHS | bits = width 1 |");
    println!("|---|---:|---|---:|---:|---:|---|");
    for kind in kinds {
        let task = Task::paper(kind);
        let pairs: Vec<_> = arms.iter().map(|a| lane_loop(a, &task)).collect();
        let loops: Vec<Loop<1>> = pairs.iter().map(|p| p.0).collect();
        let x0 = Arm2::equilibrium_state();
        let z0: Z<1> = [x0[0], x0[1], x0[2], x0[3], 0.1, 0.1].map(|v| PerLane([v]));
        same_rhs_as_the_library(&pairs);
        let variants = variants(&z0);
        let (per_tool, outputs) = measure(&variants, &loops, rounds);
        let base = &outputs[0];
        let mean_rhs = base.iter().map(|r| r.1).sum::<usize>() as f64 / base.len() as f64;
        for (v, (w, build, _)) in variants.iter().enumerate() {
            let same = outputs[v].iter().zip(base).all(|(a, b)| {
                a.1 == b.1
                    && a.0
                        .iter()
                        .zip(&b.0)
                        .all(|(x, y)| x.to_bits() == y.to_bits())
            });
            println!(
                "| {kind} | {w} | {build} | {:.1} | {:.2} | {mean_rhs:.0} | {same} |",
                per_tool[v],
                per_tool[v] / per_tool[0]
            );
        }
    }
}

/// The width-1 right-hand side is the library's, bit for bit (on the first 50 tools).
fn same_rhs_as_the_library(pairs: &[(Loop<1>, ClosedLoopN<Arm2, 2, 4, 4, 6>)]) {
    for (p, cl) in pairs.iter().take(50) {
        let z = SVector::<f64, 6>::from_column_slice(&[-1.3, -1.9, 0.4, -0.7, 0.3, -0.2]);
        let ours = rhs(p, &std::array::from_fn(|c| PerLane([z[c]])));
        let lib = cl.rhs(&z);
        for c in 0..6 {
            assert_eq!(
                ours[c].0[0].to_bits(),
                lib[c].to_bits(),
                "rhs component {c}"
            );
        }
    }
}

/// Widths 1, 2 and 4 for baseline x86-64, and 1, 4 and 8 for AVX2 where the CPU has it.
fn variants(z0: &Z<1>) -> Vec<Variant<'_>> {
    let mut variants: Vec<Variant> = vec![
        (1, "baseline", Box::new(|l| run_lanes::<1>(l, z0))),
        (2, "baseline", Box::new(|l| run_lanes::<2>(l, z0))),
        (4, "baseline", Box::new(|l| run_lanes::<4>(l, z0))),
    ];
    if is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked above).
        variants.push((
            1,
            "avx2",
            Box::new(|l| unsafe { run_lanes_avx2::<1>(l, z0) }),
        ));
        variants.push((
            4,
            "avx2",
            Box::new(|l| unsafe { run_lanes_avx2::<4>(l, z0) }),
        ));
        variants.push((
            8,
            "avx2",
            Box::new(|l| unsafe { run_lanes_avx2::<8>(l, z0) }),
        ));
    }
    variants
}

/// µs per tool of each variant, and its results (from the first round). Chunks of 64 tools,
/// the variants alternating chunk by chunk and round by round; each (variant, chunk) keeps its
/// fastest round, which drops preemptions on a shared machine.
#[allow(clippy::type_complexity)]
fn measure(
    variants: &[Variant],
    loops: &[Loop<1>],
    rounds: usize,
) -> (Vec<f64>, Vec<Vec<([f64; 6], usize)>>) {
    let mut best = vec![vec![f64::INFINITY; loops.len().div_ceil(64)]; variants.len()];
    let mut outputs: Vec<Vec<([f64; 6], usize)>> = vec![Vec::new(); variants.len()];
    for round in 0..rounds {
        for (c, chunk) in loops.chunks(64).enumerate() {
            for (v, (_, _, run)) in variants.iter().enumerate() {
                let s = Instant::now();
                let out = std::hint::black_box(run(std::hint::black_box(chunk)));
                best[v][c] = best[v][c].min(s.elapsed().as_secs_f64());
                if round == 0 {
                    outputs[v].extend(out);
                }
            }
        }
    }
    let per_tool: Vec<f64> = best
        .iter()
        .map(|b| b.iter().sum::<f64>() * 1e6 / loops.len() as f64)
        .collect();
    (per_tool, outputs)
}
