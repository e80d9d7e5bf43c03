//! The generated right-hand sides of the URDF arms: one Panda / UR5
//! `dynamics_with`, its Jacobian, the per-tool coefficients, the latency of a chain of dependent
//! calls, and the finite-difference Jacobian the stiff integrators would otherwise need
//! (NX + N more right-hand sides), each over a population of 1000 random states and tools.
//!
//! `cargo bench --bench urdf_rhs`; goal: one Panda RHS ≤ 1 µs.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::SVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use toolconf_generated::{panda, ur5};

const POPULATION: usize = 1000;

/// A tool within the derivation's sampling box: 0.05–3 kg, centre of mass within 5 cm of the
/// flange axis and up to 25 cm out, the principal moments of a 1–30 cm box (no products of
/// inertia), its tip 5–35 cm out along the flange axis.
fn tool(rng: &mut ChaCha8Rng) -> SVector<f64, 13> {
    let m = rng.random_range(0.05..3.0);
    let (a, b, c): (f64, f64, f64) = (
        rng.random_range(0.01..0.3),
        rng.random_range(0.01..0.3),
        rng.random_range(0.01..0.3),
    );
    SVector::from([
        m,
        rng.random_range(-0.05..0.05),
        rng.random_range(-0.05..0.05),
        rng.random_range(0.0..0.25),
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        rng.random_range(0.05..0.35),
    ])
}

fn state<const NX: usize, const N: usize>(
    rng: &mut ChaCha8Rng,
) -> (SVector<f64, NX>, SVector<f64, N>) {
    let x = SVector::from_fn(|i, _| {
        if i < N {
            rng.random_range(-3.0..3.0)
        } else {
            rng.random_range(-2.0..2.0)
        }
    });
    (x, SVector::from_fn(|_, _| rng.random_range(-5.0..5.0)))
}

macro_rules! arm_benches {
    ($name:ident, $m:ident, $n:expr, $nx:expr) => {
        fn $name(c: &mut Criterion) {
            let mut rng = ChaCha8Rng::seed_from_u64(23);
            let points: Vec<_> = (0..POPULATION)
                .map(|_| {
                    let p = tool(&mut rng);
                    let (x, u) = state::<$nx, $n>(&mut rng);
                    (
                        x,
                        u,
                        p,
                        $m::DynamicsCoefficients::new(&p),
                        $m::DynamicsJacobianCoefficients::new(&p),
                    )
                })
                .collect();
            let mut group = c.benchmark_group(stringify!($m));
            group.throughput(Throughput::Elements(POPULATION as u64));
            group.bench_function("dynamics_with", |b| {
                b.iter(|| {
                    let mut s = 0.0;
                    for (x, u, _, k, _) in &points {
                        s += $m::dynamics_with(black_box(x), u, k)[$nx - 1];
                    }
                    s
                })
            });
            group.bench_function("dynamics_coefficients", |b| {
                b.iter(|| {
                    let mut s = 0.0;
                    for (_, _, p, _, _) in &points {
                        s += black_box($m::DynamicsCoefficients::new(black_box(p))).k[0];
                    }
                    s
                })
            });
            group.bench_function("dynamics_jacobian_with", |b| {
                b.iter(|| {
                    let mut s = 0.0;
                    for (x, u, _, _, k) in &points {
                        let (fx, fu) = $m::dynamics_jacobian_with(black_box(x), u, k);
                        s += fx[($nx - 1, 0)] + fu[($nx - 1, 0)];
                    }
                    s
                })
            });
            // What a finite-difference Jacobian costs: one extra RHS per state and control entry.
            group.bench_function("fd_jacobian", |b| {
                b.iter(|| {
                    let mut s = 0.0;
                    for (x, u, _, k, _) in &points {
                        let f0 = $m::dynamics_with(black_box(x), u, k);
                        for j in 0..$nx {
                            let mut xj = *x;
                            xj[j] += 1e-7;
                            s += ($m::dynamics_with(&xj, u, k) - f0)[$nx - 1];
                        }
                        for j in 0..$n {
                            let mut uj = *u;
                            uj[j] += 1e-7;
                            s += ($m::dynamics_with(x, &uj, k) - f0)[$nx - 1];
                        }
                    }
                    s
                })
            });
            // Latency: each call on the previous one's result, as a Runge-Kutta stage waits.
            let (x0, u0, _, k0, _) = points[0];
            group.bench_function("dynamics_chain", |b| {
                b.iter(|| {
                    let mut x = black_box(x0);
                    for _ in 0..POPULATION {
                        x += $m::dynamics_with(&x, &u0, &k0) * 1e-4;
                    }
                    x
                })
            });
            group.finish();
        }
    };
}

arm_benches!(panda_rhs, panda, 7, 14);
arm_benches!(ur5_rhs, ur5, 6, 12);

criterion_group!(benches, panda_rhs, ur5_rhs);
criterion_main!(benches);
