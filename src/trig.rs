//! sin and cos of one angle together, for the generated right-hand sides.
//!
//! Why not libm: an episode evaluates the dynamics ~10³ times, each needing the sines and cosines
//! of the joint angles, and each DP5 stage waits for the previous one, so the trigonometric
//! latency is on the critical path. glibc's `cos`/`sincos` are out-of-line calls that save and
//! restore the rounding mode; callgrind put them at 43 % of an episode's instructions. This is
//! fdlibm's kernels (`__kernel_sin`, `__kernel_cos`, the same polynomials glibc and musl descend
//! from) after musl's medium-size reduction by π/2, inlined, with no branch on the usual path;
//! measured in docs/performance.md. Accuracy: within 1 ulp of libm for |x| < 2·10⁵ (tests
//! below); larger or non-finite arguments go to libm.
#![allow(clippy::excessive_precision)]

const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
/// π/2 = PIO2_1 + PIO2_1T, with PIO2_1 of 33 bits so that n·PIO2_1 is exact for |n| < 2^20;
/// PIO2_2 (+ PIO2_2T) and PIO2_3 (+ PIO2_3T) continue the expansion for the rare arguments
/// close to a multiple of π/2, where the first difference cancels (musl's `__rem_pio2`).
const PIO2_1: f64 = 1.57079632673412561417e+00;
const PIO2_1T: f64 = 6.07710050650619224932e-11;
const PIO2_2: f64 = 6.07710050630396597660e-11;
const PIO2_2T: f64 = 2.02226624879595063154e-21;
const PIO2_3: f64 = 2.02226624871116645580e-21;
const PIO2_3T: f64 = 8.47842766036889956997e-32;
/// 1.5·2^52: adding and subtracting it rounds to the nearest integer.
const TO_INT: f64 = 6755399441055744.0;
/// Beyond this |x| (n ≥ 2^17) the medium-size reduction is not used; libm does the full one.
const REDUCTION_LIMIT: f64 = 2.0e5;

const S1: f64 = -1.66666666666666324348e-01;
const S2: f64 = 8.33333333332248946124e-03;
const S3: f64 = -1.98412698298579493134e-04;
const S4: f64 = 2.75573137070700676789e-06;
const S5: f64 = -2.50507602534068634195e-08;
const S6: f64 = 1.58969099521155010221e-10;
const C1: f64 = 4.16666666666666019037e-02;
const C2: f64 = -1.38888888888741095749e-03;
const C3: f64 = 2.48015872894767294178e-05;
const C4: f64 = -2.75573143513906633035e-07;
const C5: f64 = 2.08757232129817482790e-09;
const C6: f64 = -1.13596475577881948265e-11;

#[inline(always)]
fn exponent(x: f64) -> i64 {
    ((x.to_bits() >> 52) & 0x7ff) as i64
}

/// One more term of the reduction: subtracts n·(part + tail) from `hi`, returning the new head,
/// the rounding to carry and their difference.
#[inline(always)]
fn next_part(hi: f64, n: f64, part: f64, tail: f64) -> (f64, f64, f64) {
    let w = n * part;
    let new_hi = hi - w;
    let w = n * tail - ((hi - new_hi) - w);
    (new_hi, w, new_hi - w)
}

/// (sin x, cos x).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() >= REDUCTION_LIMIT {
        return x.sin_cos();
    }
    // x = n·π/2 + (r + tail), |r| ≤ π/4 (musl's medium-size `__rem_pio2`).
    let (n, mut hi, mut w, mut r) = first_reduction(x);
    if exponent(x) - exponent(r) > 16 {
        (hi, w, r) = next_part(hi, n, PIO2_2, PIO2_2T);
        if exponent(x) - exponent(r) > 49 {
            (hi, w, r) = next_part(hi, n, PIO2_3, PIO2_3T);
        }
    }
    let (sin_r, cos_r) = kernels(r, (hi - r) - w);
    by_quadrant(n as i64, sin_r, cos_r)
}

/// [`sin_cos`] of W angles at once, lane by lane the same bits: the usual path is straight-line
/// code over the lanes, which the compiler vectorises (issue 14's SIMD-across-tools direction,
/// `examples/lanes.rs`); if any lane needs more of the reduction (an angle next to a multiple of
/// π/2, or out of range) every lane takes [`sin_cos`].
#[inline(always)]
pub fn sin_cos_lanes<const W: usize>(x: [f64; W]) -> ([f64; W], [f64; W]) {
    let (mut n, mut hi, mut w, mut r) = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
    let mut rare = false;
    for i in 0..W {
        (n[i], hi[i], w[i], r[i]) = first_reduction(x[i]);
        rare |= x[i].is_nan()
            | (x[i].abs() >= REDUCTION_LIMIT)
            | (exponent(x[i]) - exponent(r[i]) > 16);
    }
    let (mut s, mut c) = ([0.0; W], [0.0; W]);
    if rare {
        for i in 0..W {
            (s[i], c[i]) = sin_cos(x[i]);
        }
        return (s, c);
    }
    for i in 0..W {
        let (sin_r, cos_r) = kernels(r[i], (hi[i] - r[i]) - w[i]);
        (s[i], c[i]) = by_quadrant(n[i] as i64, sin_r, cos_r);
    }
    (s, c)
}

/// n = round(x·2/π) and the first term of x − n·π/2: (n, head, rounding, head − rounding).
#[inline(always)]
fn first_reduction(x: f64) -> (f64, f64, f64, f64) {
    let n = (x * INV_PIO2 + TO_INT) - TO_INT;
    let hi = x - n * PIO2_1;
    let w = n * PIO2_1T;
    (n, hi, w, hi - w)
}

/// fdlibm's __kernel_sin(r, tail) and __kernel_cos(r, tail), |r| ≤ π/4.
#[inline(always)]
fn kernels(r: f64, tail: f64) -> (f64, f64) {
    let z = r * r;
    let w = z * z;
    let v = z * r;
    let ps = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let sin_r = r - ((z * (0.5 * tail - v * ps) - tail) - v * S1);
    let pc = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let half_z = 0.5 * z;
    let head = 1.0 - half_z;
    let cos_r = head + (((1.0 - head) - half_z) + (z * pc - r * tail));
    (sin_r, cos_r)
}

/// (sin x, cos x) from those of r, x = n·π/2 + r. The quadrant as bit masks, not branches: a
/// joint hanging near −π/2 sits on a quadrant boundary, where branches on n mispredicted
/// (docs/performance.md); swapping and negating by masks gives the same bits.
#[inline(always)]
fn by_quadrant(quadrant: i64, sin_r: f64, cos_r: f64) -> (f64, f64) {
    const SIGN: u64 = 1 << 63;
    let odd = 0u64.wrapping_sub((quadrant & 1) as u64);
    let flip = ((quadrant & 2) as u64) << 62;
    let (sin_bits, cos_bits) = (sin_r.to_bits(), cos_r.to_bits());
    let s = (cos_bits & odd) | (sin_bits & !odd);
    let c = ((sin_bits ^ SIGN) & odd) | (cos_bits & !odd);
    (f64::from_bits(s ^ flip), f64::from_bits(c ^ flip))
}

#[cfg(test)]
mod tests {
    use super::sin_cos;

    /// |a − b| in units of the last place of b (b's ulp at 1 for |b| < f64::MIN_POSITIVE·2^52).
    fn ulps(a: f64, b: f64) -> f64 {
        let ulp = (f64::from_bits(b.abs().to_bits() + 1) - b.abs()).max(f64::EPSILON * 1e-300);
        (a - b).abs() / ulp
    }

    fn worst_over(xs: impl Iterator<Item = f64>) -> f64 {
        xs.map(|x| {
            let (s, c) = sin_cos(x);
            ulps(s, x.sin()).max(ulps(c, x.cos()))
        })
        .fold(0.0, f64::max)
    }

    #[test]
    fn within_an_ulp_of_libm_where_joint_angles_live() {
        // libm is correctly rounded in practice here, so ≤ 1 ulp from it is ≤ 1.5 ulp from exact;
        // the fdlibm kernels' own bound is < 1 ulp.
        let worst = worst_over((-4_000_000..=4_000_000).map(|i| i as f64 * 2.5e-6 * 3.0));
        assert!(worst <= 1.0, "worst {worst} ulp on [-30, 30]");
    }

    #[test]
    fn within_an_ulp_near_the_quadrant_boundaries_and_far_out() {
        let near = (-2000..=2000).flat_map(|k| {
            let b = k as f64 * std::f64::consts::FRAC_PI_2;
            [
                b,
                f64::from_bits(b.to_bits() + 1),
                b + 1e-9,
                b - 1e-9,
                b + 0.785,
                b - 0.785,
            ]
        });
        assert!(worst_over(near) <= 1.0);
        let far = (0..20_000).map(|i| 1.0e5 + i as f64 * 7.77);
        assert!(worst_over(far) <= 1.0);
    }

    #[test]
    fn lanes_give_each_lane_the_scalar_bits() {
        use super::sin_cos_lanes;
        let same = |x: [f64; 4]| {
            let (s, c) = sin_cos_lanes(x);
            (0..4).all(|i| {
                let (si, ci) = sin_cos(x[i]);
                s[i].to_bits() == si.to_bits() && c[i].to_bits() == ci.to_bits()
            })
        };
        for i in -200_000..200_000 {
            let x = i as f64 * 1.3e-4;
            assert!(same([x, -x, x + 0.5, x * 7.0]), "x = {x}");
        }
        // A lane next to a multiple of π/2, out of range or NaN sends every lane the slow way.
        let b = 3.0 * std::f64::consts::FRAC_PI_2;
        assert!(same([b, 0.3, -1.2, 2.0]));
        assert!(same([f64::from_bits(b.to_bits() + 1), 0.3, 1e12, f64::NAN]));
    }

    #[test]
    fn exact_at_zero_and_libm_outside_the_reduction_range() {
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        for x in [3.0e5, -1.0e12, 1.0e300] {
            assert_eq!(sin_cos(x), x.sin_cos());
        }
        let (s, c) = sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos(f64::INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }
}
