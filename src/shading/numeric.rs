//! Small numeric helpers shared by the shading terms (shading stage). Their invariant: every helper
//! returns a finite value for every input, NaN and infinities included, so no shading term can leak
//! a NaN into the framebuffer.

use super::lanes::{lane_mask, select_bits};
use wide::f32x4;

/// Clamps to `[0, 1]`; NaN becomes 0.
#[inline]
pub(crate) fn saturate(x: f32) -> f32 {
    if x > 0.0 { x.min(1.0) } else { 0.0 }
}

/// [`saturate`] of four lanes, the same bits (`−0` and NaN give `+0`), with compares and
/// selects instead of a branch per lane: the branch mispredicts on data such as shadow alphas,
/// which are 0 or not at random.
#[inline(always)]
pub(crate) fn saturate_x4(x: f32x4) -> f32x4 {
    let at_most_one = x.simd_lt(f32x4::ONE).select(x, f32x4::ONE);
    x.simd_gt(f32x4::ZERO).select(at_most_one, f32x4::ZERO)
}

/// Returns `x` when finite, else 0.
#[inline]
pub(crate) fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() { x } else { 0.0 }
}

/// The exponent convention of every lobe: NaN acts as 1 (the plain term), a negative exponent
/// as 0 (so the result is 1, with `0^0 = 1`), `+inf` is kept (`x^inf` is 0 below 1, 1 at 1).
#[inline]
pub(crate) fn sanitize_exponent(p: f32) -> f32 {
    if p.is_nan() { 1.0 } else { p.max(0.0) }
}

/// `saturate(base)` raised to the sanitised exponent: pelage's own power of saturated bases,
/// `2^(y·log2 x)` (see [`pow01_lanes`] for the algorithm and its accuracy); always in `[0, 1]`.
///
/// Edge cases: `y = 0` gives 1 (so `0^0 = 1`), `x = 0` gives 0 for `y > 0`, `x = 1` gives 1,
/// `y = +inf` gives 0 below 1; `y·log2 x < −151` gives 0, subnormal bases and results are
/// computed (not flushed). The scalar twin of the lanes: the same IEEE operations in the same
/// order, so the same bits as each lane of [`pow01_lanes`] (and as `pow01` in `src/gpu/fur.wgsl`
/// where the GPU does not contract to fused multiply-adds).
#[inline(always)]
pub(crate) fn pow01(base: f32, exponent: f32) -> f32 {
    let x = saturate(base);
    exp2_of_product_lane(x, log2_lane(x), sanitize_exponent(exponent))
}

/// `N` [`pow01`]s at once, each lane bit-identical to `pow01(base[i], exponent[i])`.
///
/// pelage's power of a saturated base `x` in `[0, 1]` by a sanitised exponent `y ≥ 0`, a
/// convention of its own (not a copy of a C library): `2^(y·log2 x)` with its own polynomials,
/// only IEEE `+ − × ÷`, comparisons, selects and bit casts, no fused multiply-add, in a fixed
/// order, so every lane, the scalar twin and the WGSL port give the same bits.
///
/// 1. `x = 2^e·m` with `m` in `[√½, √2)` (subnormal `x` scaled by `2^23` first).
/// 2. `L = e + (c·s + (s·z)·Q(z))`, `s = (m − 1)/(m + 1)`, `z = s²`, `c = 2/ln 2` rounded to
///    f32, `Q` a degree-2 minimax fit ([`LOG2_Q`]); [`log2_lane`], within 3 ulp of `log2 x`.
/// 3. `t = y·L`, rounded once: the single-precision product a GPU's `pow` forms too.
/// 4. `2^t = 2^n·(1 + f·P(f))`, `n = round(t)` (ties to even), `f = t − n` (exact), `P` a
///    degree-5 minimax fit ([`EXP2_P`], relative error 2e-9 on `[−½, ½]`); `2^n` goes into
///    the exponent bits, in two steps (`2^(n+64)` then `×2^−64`) when the result is subnormal.
///
/// Accuracy against f64 `powf`, exponents 0.5 to 512 and a dense sweep of bases (test
/// `pow01_error_against_f64`): a normal result within `3·(1 + |t|)` ulp (measured 2.61·(1 +
/// |t|)), since the rounding of `L` and of `t` is multiplied by `ln 2·|t|`; a subnormal one
/// within `2^-142`. This is the class of a GPU's `pow` (`exp2(y·log2 x)` in f32); until
/// 2026-11-26 pelage carried `log2 x` and `t` as two floats each (at most 2 ulp from 1e-6
/// up), which took twice the operations for no difference a GPU could show.
///
/// Written as plain per-lane loops of the scalar steps ([`log2_lane`], [`exp2_of_product_lane`]),
/// which LLVM vectorises as wide as the level's copy of the hot path allows.
#[inline(always)]
pub(crate) fn pow01_lanes<const N: usize>(base: [f32; N], exponent: [f32; N]) -> [f32; N] {
    let (mut x, mut y) = ([0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        x[i] = saturate_select(base[i]);
        y[i] = sanitize_exponent(exponent[i]);
    }
    let mut l = [0.0f32; N];
    for i in 0..N {
        l[i] = log2_lane(x[i]);
    }
    let mut out = [0.0f32; N];
    for i in 0..N {
        out[i] = exp2_of_product_lane(x[i], l[i], y[i]);
    }
    out
}

/// The powers of `N` fragments' strand lighting with one tangent, in three batches of `N`
/// lanes instead of five: `(d^banks, c^specular, c^dampened)` lane by lane for the diffuse
/// bases `d` and the specular bases `c`, the same bits as [`pow01`] of each. The logarithms of
/// both bases are taken in one pass and `d^banks, c^specular` in another; `c^dampened` shares
/// `c`'s logarithm.
///
/// Written as plain per-lane loops over arrays of the scalar steps (no `wide` type): LLVM turns
/// a batch's loop into 256-bit instructions in the AVX2 copy of the hot path ([`crate::simd`];
/// four a step for its 32 lanes) and into 128-bit halves in the baseline's 8, while
/// `wide::f32x8` is always two halves in a baseline build. Each lane runs the scalar [`pow01`]'s IEEE operations in its order.
#[inline(always)]
pub(crate) fn pow01_diffuse_specular_dampened_lanes<const N: usize>(
    diffuse: [f32; N],
    specular: [f32; N],
    exponents: [f32; 3],
) -> ([f32; N], [f32; N], [f32; N]) {
    let [banks, spec, damp] = [
        sanitize_exponent(exponents[0]),
        sanitize_exponent(exponents[1]),
        sanitize_exponent(exponents[2]),
    ];
    let (mut xd, mut xs) = ([0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        xd[i] = saturate_select(diffuse[i]);
        xs[i] = saturate_select(specular[i]);
    }
    let (mut ld, mut ls) = ([0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        ld[i] = log2_lane(xd[i]);
        ls[i] = log2_lane(xs[i]);
    }
    let (mut d, mut c, mut dampened) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    // The three exponentials in one loop: three independent chains side by side, which the
    // core overlaps (one after the other, each waited on its own latency).
    for i in 0..N {
        d[i] = exp2_of_product_lane(xd[i], ld[i], banks);
        c[i] = exp2_of_product_lane(xs[i], ls[i], spec);
        dampened[i] = exp2_of_product_lane(xs[i], ls[i], damp);
    }
    (d, c, dampened)
}

/// [`saturate`] as compares and selects, the same bits (`−0` and NaN give `+0`), so that a
/// loop of it vectorises.
#[inline(always)]
pub(crate) fn saturate_select(x: f32) -> f32 {
    let at_most_one = if x < 1.0 { x } else { 1.0 };
    if x > 0.0 { at_most_one } else { 0.0 }
}

/// `log2 x` of a positive `x` (subnormal included), pelage's own (steps 1 and 2 of
/// [`pow01_lanes`]): `e + (c·s + (s·z)·Q(z))` with `x = 2^e·m`, `m` in `[√½, √2)`,
/// `s = (m − 1)/(m + 1)`, `z = s²`, `c = 2/ln 2`. Within 3 ulp of `log2 x` for `x` in
/// `[√½, √2)`, within 2 ulp elsewhere (test `log2_error_against_f64`). For `x = 0` a
/// meaningless finite value, which [`exp2_of_product_lane`] replaces. Its branch is a select,
/// so that loops of it over lanes vectorise.
#[inline(always)]
pub(crate) fn log2_lane(x: f32) -> f32 {
    let subnormal = x < f32::MIN_POSITIVE;
    let scaled = x * TWO_POW_23;
    let xs = if subnormal { scaled } else { x };
    let bias = if subnormal { -23.0 } else { 0.0 };
    let bits = xs.to_bits() as i32;
    let k = bits.wrapping_sub(SQRT_HALF_BITS) >> 23;
    let m = f32::from_bits(bits.wrapping_sub(k << 23) as u32);
    let e = k as f32 + bias;
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let q = LOG2_Q[0] + z * (LOG2_Q[1] + z * LOG2_Q[2]);
    let r = LOG2_C * s + (s * z) * q;
    e + r
}

/// The second half of [`pow01`] (steps 3 and 4 of [`pow01_lanes`], from `x`'s logarithm `l`
/// and the sanitised `y`) with the edge cases: `y = 0` → 1, `x = 0` → 0, `x = 1` → 1,
/// underflow → 0. Its branches are selects, so that loops of it over lanes vectorise.
#[inline(always)]
fn exp2_of_product_lane(x: f32, l: f32, y: f32) -> f32 {
    let t = y * l;
    // NaN (`y = +inf` at `l = 0`, only for `x = 1`, replaced below) takes the clamp too.
    let clamped = if t > EXP2_LOWEST { t } else { EXP2_LOWEST };
    let shifted = clamped + ROUND_MAGIC;
    let n = shifted - ROUND_MAGIC;
    let whole = (shifted.to_bits() as i32).wrapping_sub(ROUND_MAGIC.to_bits() as i32);
    let f = clamped - n;
    let mut p = EXP2_P[5];
    for c in EXP2_P[..5].iter().rev() {
        p = c + f * p;
    }
    let fraction = 1.0 + f * p;
    let small = whole < -125;
    let whole = if small { whole + 64 } else { whole };
    let scale = if small { TWO_POW_MINUS_64 } else { 1.0 };
    let scaled = f32::from_bits((fraction.to_bits() as i32).wrapping_add(whole << 23) as u32);
    let out = scaled * scale;
    let out = if t >= UNDERFLOW_BELOW { out } else { 0.0 };
    let out = if x == 0.0 { 0.0 } else { out };
    let out = if x == 1.0 { 1.0 } else { out };
    if y == 0.0 { 1.0 } else { out }
}

/// The bits of `√½` (rounded), where the reduced mantissa's interval starts.
const SQRT_HALF_BITS: i32 = 0x3f35_04f3;
/// `2^23`, which makes a subnormal base normal.
const TWO_POW_23: f32 = 8_388_608.0;
/// `2^-64`, the second step of a subnormal result's scaling.
const TWO_POW_MINUS_64: f32 = f32::from_bits(0x1f80_0000);
/// `1.5·2^23`: `(t + M) − M` rounds `|t| < 2^22` to the nearest integer, ties to even.
const ROUND_MAGIC: f32 = 12_582_912.0;
/// `t` below this is clamped before `n = round(t)`; its result is 0 anyway.
const EXP2_LOWEST: f32 = -152.0;
/// `t` below this gives 0: `2^t < 2^-150.9`, under half the smallest subnormal.
const UNDERFLOW_BELOW: f32 = -151.0;
/// `2/ln 2` rounded to f32.
const LOG2_C: f32 = 2.885_39;
/// `Q(z)`, `z = s²`, `s = (m − 1)/(m + 1)`: `log2 m ≈ (2/ln 2)·s + s³·Q(z)` on `|s| ≤ 0.1716`,
/// a minimax fit relative to `log2 m` (Lawson's iteration on 3000 Chebyshev nodes, then
/// rounded to f32): relative error under `8.1e-10`. Evaluated `Q0 + z·(Q1 + z·Q2)`.
const LOG2_Q: [f32; 3] = [0.961_798_25, 0.576_754_03, 0.430_957_94];
/// `P(f)` with `2^f ≈ 1 + f·P(f)` on `[−½, ½]`, a minimax fit relative to `2^f` (as [`LOG2_Q`]):
/// relative error under `2e-9`. Evaluated by Horner from `P5` down, then `1 + f·P`. (`P0` came
/// out of the fit as `ln 2` rounded to f32.)
const EXP2_P: [f32; 6] = [
    std::f32::consts::LN_2,
    0.240_226_48,
    0.055_503_324,
    0.009_618_438,
    0.001_339_890_1,
    0.000_153_533_42,
];

/// Hermite smoothstep `t²(3 − 2t)` of `saturate(t)`.
#[inline]
pub(crate) fn smoothstep01(t: f32) -> f32 {
    let t = saturate(t);
    t * t * (3.0 - 2.0 * t)
}

/// A rising smooth ramp: 0 for `x <= lo`, 1 for `x >= hi` (checked first), smoothstep between.
/// With `lo >= hi` it is a step at `hi`. NaN `x` gives 0.
#[inline]
pub(crate) fn ramp(x: f32, lo: f32, hi: f32) -> f32 {
    if x.is_nan() {
        0.0
    } else if x >= hi {
        1.0
    } else if x <= lo {
        0.0
    } else {
        smoothstep01((x - lo) / (hi - lo))
    }
}

/// [`ramp`] of `N` lanes, the same bits: every branch computed, the scalar's first taken
/// branch selected (`x ≥ hi` → 1, then `x ≤ lo` → 0, else the smoothstep; NaN compares false
/// and its smoothstep saturates to +0, the scalar's 0). A plain loop with bit selects, so it
/// vectorises as wide as the level's copy of the hot path allows.
#[inline(always)]
pub(crate) fn ramp_lanes<const N: usize>(x: [f32; N], lo: f32, hi: f32) -> [f32; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        // `smoothstep01`: `t·t·(3 − 2t)` of the saturated ring coordinate.
        let t = saturate_select((x[i] - lo) / (hi - lo));
        let smooth = t * t * (3.0 - 2.0 * t);
        let below = select_bits(lane_mask(x[i] <= lo), 0.0, smooth);
        out[i] = select_bits(lane_mask(x[i] >= hi), 1.0, below);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn helpers_are_finite_on_special_values() {
        for x in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -1.0,
            0.0,
            0.5,
            1.0,
            2.0,
        ] {
            assert!(saturate(x).is_finite());
            assert!(finite_or_zero(x).is_finite());
            for p in [f32::NAN, f32::INFINITY, -3.0, 0.0, 4.8] {
                let v = pow01(x, p);
                assert!((0.0..=1.0).contains(&v), "pow01({x}, {p}) = {v}");
            }
            for (lo, hi) in [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (f32::NAN, 1.0)] {
                let r = ramp(x, lo, hi);
                assert!((0.0..=1.0).contains(&r), "ramp({x}, {lo}, {hi}) = {r}");
            }
        }
        assert_eq!(saturate(f32::NAN), 0.0);
        assert_eq!(saturate(-0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(sanitize_exponent(f32::NAN), 1.0);
        assert_eq!(sanitize_exponent(-2.0), 0.0);
    }

    #[test]
    fn four_lane_saturate_is_saturate_bit_for_bit() {
        let mut values = vec![
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            1.0,
            -1.0,
            1.0f32.next_up(),
            1.0f32.next_down(),
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MAX,
        ];
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..4000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            values.push(f32::from_bits((state >> 32) as u32));
        }
        for chunk in values.chunks_exact(4) {
            let lanes: [f32; 4] = chunk.try_into().expect("four");
            let packed = saturate_x4(f32x4::new(lanes)).to_array();
            for (got, x) in packed.iter().zip(lanes) {
                assert_eq!(got.to_bits(), saturate(x).to_bits(), "{x:e}");
            }
        }
    }

    /// Bases that exercise every step: both halves of the reduced mantissa's interval, values
    /// near 0 (underflow, subnormal results) and near 1, subnormal bases and special values.
    fn pow_bases() -> Vec<f32> {
        let mut bases = vec![
            0.0,
            -0.0,
            1.0,
            f32::MIN_POSITIVE,
            f32::MIN_POSITIVE / 4.0,
            f32::from_bits(1),
            1e-30,
            1e-10,
            1e-3,
            0.5,
            0.25,
            // Either side of where the reduced mantissa's interval starts.
            f32::from_bits(SQRT_HALF_BITS as u32 - 1),
            f32::from_bits(SQRT_HALF_BITS as u32),
            0.75,
            0.8660,
            0.9,
            0.99999994,
            1.5,
            -0.5,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let mut state = 0x1234_5678_9abc_def0u64;
        for _ in 0..20_000 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Uniform in (0, 1) and log-uniform over the normal range.
            let u = (state >> 40) as f32 / (1u64 << 24) as f32;
            bases.push(u);
            bases.push(f32::from_bits(
                0x0080_0000 + ((state >> 33) as u32 % 0x3f00_0000),
            ));
        }
        bases
    }

    /// Exponents: the scenes' (4.8, 7.5, 8, 20, 40, 80, 512), the edge cases and extremes.
    const POW_EXPONENTS: [f32; 22] = [
        4.8,
        40.0,
        80.0,
        20.0,
        0.3,
        7.3,
        1.0,
        2.0,
        0.5,
        0.0,
        -0.0,
        -1.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        1.0e-6,
        1.0e-40,
        150.0,
        512.0,
        3.0e7,
        1.0e30,
        f32::MAX,
    ];

    #[test]
    fn pow01_lanes_are_bit_identical_to_pow01() {
        let bases = pow_bases();
        for (e_index, chunk) in bases.chunks_exact(4).enumerate() {
            let base = [chunk[0], chunk[1], chunk[2], chunk[3]];
            let exponent: [f32; 4] =
                std::array::from_fn(|i| POW_EXPONENTS[(e_index + i * 5) % POW_EXPONENTS.len()]);
            let got = pow01_lanes(base, exponent);
            for i in 0..4 {
                let want = pow01(base[i], exponent[i]);
                assert!((0.0..=1.0).contains(&want), "{}^{}", base[i], exponent[i]);
                assert_eq!(
                    got[i].to_bits(),
                    want.to_bits(),
                    "pow01({}, {}) = {want}, x4 gave {}",
                    base[i],
                    exponent[i],
                    got[i]
                );
            }
            let specular = [chunk[3], chunk[1], chunk[2], chunk[0]];
            let n = POW_EXPONENTS.len();
            for k in 0..n {
                let exponents = [
                    POW_EXPONENTS[k],
                    POW_EXPONENTS[(k + e_index) % n],
                    POW_EXPONENTS[(k + 2 * e_index + 1) % n],
                ];
                assert_powers_are_pow01(base, specular, exponents);
            }
        }
    }

    /// Each lane of [`pow01_diffuse_specular_dampened_lanes`] and [`pow01_lanes`] against
    /// [`pow01`], bit for bit, at 4 and 8 lanes.
    fn assert_powers_are_pow01(diffuse: [f32; 4], specular: [f32; 4], exponents: [f32; 3]) {
        let (d, c, damp) = pow01_diffuse_specular_dampened_lanes(diffuse, specular, exponents);
        let wide: [f32; 8] = std::array::from_fn(|i| [diffuse, specular][i / 4][i % 4]);
        let (d8, c8, damp8) = pow01_diffuse_specular_dampened_lanes(wide, wide, exponents);
        let one = pow01_lanes(wide, [exponents[0]; 8]);
        for i in 0..8 {
            let want = pow01(wide[i], exponents[0]);
            assert_eq!(one[i].to_bits(), want.to_bits(), "pow01_lanes");
            for (got, exponent) in [
                (d8[i], exponents[0]),
                (c8[i], exponents[1]),
                (damp8[i], exponents[2]),
            ] {
                assert_eq!(got.to_bits(), pow01(wide[i], exponent).to_bits(), "8 lanes");
            }
        }
        let [banks, spec, dampened] = exponents;
        for i in 0..4 {
            for (got, base, exponent) in [
                (d[i], diffuse[i], banks),
                (c[i], specular[i], spec),
                (damp[i], specular[i], dampened),
            ] {
                let want = pow01(base, exponent);
                assert_eq!(
                    got.to_bits(),
                    want.to_bits(),
                    "pow01({base:e}, {exponent:e}) = {want:e}, the 8-lane batch gave {got:e}"
                );
            }
        }
    }

    /// Random bases over every bit pattern of [0, 1] and random exponents from 2^-12 to 2^14:
    /// results from 1 down to the subnormals and to 0.
    #[test]
    fn pow01_lanes_match_pow01_on_random_bases_and_exponents() {
        let mut rng = crate::shading::test_support::Lcg::new(97);
        for _ in 0..100_000 {
            let base: [f32; 4] =
                std::array::from_fn(|_| f32::from_bits((rng.next_u64() % 0x3f80_0001) as u32));
            let exponent: [f32; 4] = std::array::from_fn(|_| 2f32.powf(rng.range(-12.0, 14.0)));
            let specular: [f32; 4] =
                std::array::from_fn(|_| f32::from_bits((rng.next_u64() % 0x3f80_0001) as u32));
            let exponents: [f32; 3] = std::array::from_fn(|_| 2f32.powf(rng.range(-12.0, 14.0)));
            let got = pow01_lanes(base, exponent);
            for i in 0..4 {
                let want = pow01(base[i], exponent[i]);
                assert_eq!(
                    got[i].to_bits(),
                    want.to_bits(),
                    "{}^{}",
                    base[i],
                    exponent[i]
                );
            }
            assert_powers_are_pow01(base, specular, exponents);
        }
    }

    #[test]
    fn pow_constants_are_what_they_claim() {
        assert_eq!(LOG2_C, (2.0 / std::f64::consts::LN_2) as f32);
        assert_eq!(f64::from(TWO_POW_MINUS_64), 2f64.powi(-64));
        assert_eq!(f64::from(ROUND_MAGIC), 1.5 * 2f64.powi(23));
    }

    #[test]
    fn pow01_edge_cases() {
        let cases = [
            (0.0, 0.0, 1.0),
            (0.0, 2.0, 0.0),
            (-3.0, 2.0, 0.0),
            (f32::NAN, 2.0, 0.0),
            (0.0, f32::NAN, 0.0),
            (0.5, f32::NAN, 0.5),
            (0.5, -2.0, 1.0),
            (1.0, 80.0, 1.0),
            (1.0, f32::INFINITY, 1.0),
            (7.0, 3.0, 1.0),
            (0.5, f32::INFINITY, 0.0),
            (0.99999994, f32::INFINITY, 0.0),
            (0.5, 0.0, 1.0),
            (0.5, 1.0, 0.5),
            (0.25, 0.5, 0.5),
            (0.5, 149.0, f32::from_bits(1)),
            (0.5, 151.0, 0.0),
            (0.5, 126.0, f32::MIN_POSITIVE),
            (f32::from_bits(1), 1.0, f32::from_bits(1)),
            (f32::from_bits(1), 2.0, 0.0),
            (f32::MIN_POSITIVE / 4.0, 0.5, 2f32.powi(-64)),
            (0.3, 1.0e-40, 1.0),
        ];
        for (x, y, want) in cases {
            let got = pow01(x, y);
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "pow01({x}, {y}) = {got}, not {want}"
            );
        }
    }

    /// [`log2_lane`] of a normal `x = 2^k·m` is `k + r(m)` rounded once, with `r(m)` the
    /// result for the reduced mantissa `m` in `[√½, √2)` alone: every such `m` (2^23 of them)
    /// within `2·10⁻⁶` of `log2 m` (the mip level choice of
    /// `crate::raster::texture::Texture::levels_of_footprint` relies on it), and the
    /// decomposition checked bit for bit at every exponent for a sample of mantissas.
    #[test]
    fn log2_of_every_reduced_mantissa_is_close() {
        let reduced = SQRT_HALF_BITS as u32..SQRT_HALF_BITS as u32 + (1 << 23);
        let mut worst = 0.0f64;
        for bits in reduced.clone() {
            let m = f32::from_bits(bits);
            let r = log2_lane(m);
            worst = worst.max((f64::from(r) - f64::from(m).log2()).abs());
            if bits % 4099 == 0 {
                for k in -126i32..=127 {
                    let x = f32::from_bits((bits as i32 + (k << 23)) as u32);
                    if x.is_normal() {
                        assert_eq!(
                            log2_lane(x).to_bits(),
                            (k as f32 + r).to_bits(),
                            "log2({x:e}) against {k} + r({m})"
                        );
                    }
                }
            }
        }
        assert!(worst <= 2e-6, "log2 of a reduced mantissa off by {worst:e}");
        eprintln!("log2 of the reduced mantissas: within {worst:e}");
    }

    /// The stated accuracy of [`log2_lane`]: every 101st bit pattern of the positive finite
    /// floats (subnormals included) and every 3rd of `[√½, √2)`, where the result is smallest,
    /// against f64 `log2`. Bounds in ulp of the exact result: 3 in `[√½, √2)` (measured 2.76),
    /// 2 elsewhere (measured 1.73).
    #[test]
    fn log2_error_against_f64() {
        let sparse = (1..0x7f80_0000u32).step_by(101);
        let near_one = (SQRT_HALF_BITS as u32..0x3fb5_04f3).step_by(3);
        let mut worst = [0.0f64; 2];
        for bits in sparse.chain(near_one) {
            let x = f32::from_bits(bits);
            let exact = f64::from(x).log2();
            let got = f64::from(log2_lane(x));
            if exact == 0.0 {
                assert_eq!(got, 0.0, "log2 1");
                continue;
            }
            let ulp = 2f64.powi(exact.abs().log2().floor() as i32 - 23);
            let e = (got - exact).abs() / ulp;
            let class = usize::from(
                !(std::f32::consts::FRAC_1_SQRT_2..std::f32::consts::SQRT_2).contains(&x),
            );
            assert!(
                e <= [3.0, 2.0][class],
                "log2({x:e}) = {got:e} vs {exact:e}: {e} ulp"
            );
            worst[class] = worst[class].max(e);
        }
        eprintln!(
            "log2 against f64: {:.3} ulp in [√½, √2), {:.3} elsewhere",
            worst[0], worst[1]
        );
    }

    /// The stated accuracy of the powers: every 97th base of (0, 1] and every 7th of [½, 1)
    /// against f64 `powf`, for exponents over the scenes' range (0.5 to 512). With
    /// `t = y·log2 x` (the error of the rounded `t` is multiplied by `ln 2·|t|` in `2^t`): a
    /// normal result within `3·(1 + |t|)` ulp (measured 2.61), a subnormal one within 128
    /// steps of `2^-149`, that is `2^-142` (measured 125.6).
    #[test]
    fn pow01_error_against_f64() {
        let exponents = [
            0.5f32, 0.75, 1.0, 1.5, 2.0, 3.3, 4.8, 7.5, 8.0, 13.7, 20.0, 40.0, 64.0, 80.0, 150.0,
            256.0, 333.3, 512.0,
        ];
        // Worst errors: in ulp of normal results, in ulp over `1 + |t|`, in subnormal steps.
        let mut worst = [0.0f64; 3];
        for &y in &exponents {
            let sparse = (1..=0x3f80_0000u32).step_by(97);
            let near_one = (0x3f00_0000..0x3f80_0000u32).step_by(7);
            let bits: Vec<u32> = sparse.chain(near_one).collect();
            for chunk in bits.chunks(4) {
                let base: [f32; 4] =
                    std::array::from_fn(|i| f32::from_bits(chunk[i.min(chunk.len() - 1)]));
                let got = pow01_lanes(base, [y; 4]);
                for i in 0..4 {
                    let t = (f64::from(y) * f64::from(base[i]).log2()).abs();
                    let exact = f64::from(base[i]).powf(f64::from(y));
                    let err = (f64::from(got[i]) - exact).abs();
                    if exact >= f64::from(f32::MIN_POSITIVE) {
                        let ulp = 2f64.powi(exact.log2().floor() as i32 - 23);
                        let e = err / ulp;
                        assert!(
                            e <= 3.0 * (1.0 + t),
                            "{}^{y} = {:e} vs {exact:e}: {e} ulp at |t| = {t}",
                            base[i],
                            got[i]
                        );
                        worst[0] = worst[0].max(e);
                        worst[1] = worst[1].max(e / (1.0 + t));
                    } else {
                        let steps = err / 2f64.powi(-149);
                        assert!(steps <= 128.0, "{}^{y}: {steps} subnormal steps", base[i]);
                        worst[2] = worst[2].max(steps);
                    }
                }
            }
        }
        eprintln!(
            "pow01 against f64: {:.3} ulp, {:.3} ulp per 1 + |t|, {:.3} subnormal steps",
            worst[0], worst[1], worst[2]
        );
    }

    #[test]
    fn ramp_of_4_and_8_lanes_is_the_scalar_ramp_bit_for_bit() {
        let mut rng = crate::shading::test_support::Lcg::new(29);
        let specials = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            0.1,
            0.9,
        ];
        for k in 0..20_000usize {
            let (lo, hi) = if k % 5 == 0 {
                (0.5, 0.5)
            } else if k % 7 == 0 {
                (0.9, 0.1)
            } else {
                (rng.range(-1.0, 0.5), rng.range(0.5, 2.0))
            };
            let x: [f32; 8] = std::array::from_fn(|i| {
                if (k + i) % 13 == 0 {
                    specials[(k + i) % specials.len()]
                } else {
                    rng.range(-1.5, 2.5)
                }
            });
            let got = ramp_lanes(x, lo, hi);
            let four = ramp_lanes([x[0], x[1], x[2], x[3]], lo, hi);
            for i in 0..8 {
                if i < 4 {
                    assert_eq!(four[i].to_bits(), got[i].to_bits(), "4 lanes");
                }
                assert_eq!(
                    got[i].to_bits(),
                    ramp(x[i], lo, hi).to_bits(),
                    "{} {lo} {hi}",
                    x[i]
                );
            }
        }
    }

    #[test]
    fn ramp_matches_f64_smoothstep() {
        for k in 0..=100 {
            let x = k as f32 / 100.0 * 1.4 - 0.2;
            let t = ((f64::from(x) - 0.1) / 0.8).clamp(0.0, 1.0);
            let expected = t * t * (3.0 - 2.0 * t);
            let got = ramp(x, 0.1, 0.9);
            assert!(
                (f64::from(got) - expected).abs() <= 1e-6,
                "{x}: {got} vs {expected}"
            );
        }
    }
}
