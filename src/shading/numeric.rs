//! Small numeric helpers shared by the shading terms. Their invariant: every helper returns a
//! finite value for every input, NaN and infinities included, so no shading term can leak a NaN
//! into the framebuffer.

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

/// `saturate(base)` raised to the sanitised exponent with `libm::powf`; always in `[0, 1]`.
#[inline]
pub(crate) fn pow01(base: f32, exponent: f32) -> f32 {
    libm::powf(saturate(base), sanitize_exponent(exponent))
}

/// Four [`pow01`]s at once, each lane bit-identical to `pow01(base[i], exponent[i])`.
///
/// Why it exists: `libm::powf` was the costliest operation of the fur shader (three or more
/// per fragment, 40 % of a frame; the batched powers are about 15 % now). This evaluates the
/// main path of the same FreeBSD `e_powf.c` algorithm that `libm::powf` implements — the same
/// IEEE operations in the same order, so the same bits — on four lanes, in loops the compiler
/// turns into SIMD. Lanes outside that path (base 0, 1 or subnormal, exponents 0, ½, 1, 2,
/// infinite or above 2^27, results that underflow or are subnormal) are recomputed with
/// `libm::powf` itself.
#[inline]
pub(crate) fn pow01_x4(base: [f32; 4], exponent: [f32; 4]) -> [f32; 4] {
    let x = saturate_x4(f32x4::new(base)).to_array();
    pow01_x4_from_log2(x, &log2_parts_x4(x), exponent)
}

/// [`pow01_x4`] of one base with two exponents, `(base^a, base^b)` lane by lane, the same
/// bits as two calls: the two powers share the logarithm half of the main path.
#[inline]
pub(crate) fn pow01_x4_two_exponents(
    base: [f32; 4],
    a: [f32; 4],
    b: [f32; 4],
) -> ([f32; 4], [f32; 4]) {
    let x = saturate_x4(f32x4::new(base)).to_array();
    let log2_x = log2_parts_x4(x);
    (
        pow01_x4_from_log2(x, &log2_x, a),
        pow01_x4_from_log2(x, &log2_x, b),
    )
}

/// `x^exponent` for saturated bases `x` whose logarithm half is `log2_x`: the main path's
/// exp2 half, and `libm::powf` on the lanes off that path.
#[inline(always)]
fn pow01_x4_from_log2(x: [f32; 4], log2_x: &Log2Parts, exponent: [f32; 4]) -> [f32; 4] {
    let y = exponent.map(sanitize_exponent);
    let (z, main_path) = exp2_of_product_x4(log2_x, y);
    std::array::from_fn(|i| {
        if main_path[i] {
            z[i]
        } else {
            libm::powf(x[i], y[i])
        }
    })
}

/// `log2 x` of the main path of FreeBSD's `e_powf.c` (as ported by `libm`) for `0 < x < 1`
/// normal, carried in two parts `t1 + t2`, and per lane whether `x` is on that path: the
/// first half of the main path, shared by powers of one base.
///
/// The main path: for `0 < x < 1` normal and finite `y > 0`, `x^y = 2^(y·log2 x)` with
/// `log2 x` and the product carried in two parts. Integer shifts wrap so off-path lanes
/// cannot overflow; their results are meaningless and replaced.
#[derive(Clone, Copy)]
struct Log2Parts {
    t1: [f32; 4],
    t2: [f32; 4],
    x_on_path: [bool; 4],
}

/// The `log2 x` half of the main path.
#[inline(always)]
#[allow(clippy::excessive_precision)]
fn log2_parts_x4(x: [f32; 4]) -> Log2Parts {
    const BP: [f32; 2] = [1.0, 1.5];
    const DP_H: [f32; 2] = [0.0, 5.84960938e-01];
    const DP_L: [f32; 2] = [0.0, 1.56322085e-06];
    const L1: f32 = 6.0000002384e-01;
    const L2: f32 = 4.2857143283e-01;
    const L3: f32 = 3.3333334327e-01;
    const L4: f32 = 2.7272811532e-01;
    const L5: f32 = 2.3066075146e-01;
    const L6: f32 = 2.0697501302e-01;
    const CP: f32 = 9.6179670095e-01;
    const CP_H: f32 = 9.6191406250e-01;
    const CP_L: f32 = -1.1736857402e-04;
    let trunc = |v: f32, mask: u32| f32::from_bits(v.to_bits() & mask);
    let mut parts = Log2Parts {
        t1: [0.0; 4],
        t2: [0.0; 4],
        x_on_path: [false; 4],
    };
    for lane in 0..4 {
        let x = x[lane];
        let hx = x.to_bits() as i32;
        // On the path: x normal in (0, 1).
        parts.x_on_path[lane] = (0x0080_0000..0x3f80_0000).contains(&hx);
        // log2(x) = n + dp_h[k] + z_h + z_l, with x reduced to [sqrt(1/2), sqrt(2)·...).
        let mut n = (hx >> 23) - 0x7f;
        let j = hx & 0x007f_ffff;
        let mut ix = j | 0x3f80_0000;
        let k = usize::from(j > 0x001c_c471 && j < 0x005d_b3d7);
        if j >= 0x005d_b3d7 {
            n += 1;
            ix -= 0x0080_0000;
        }
        let ax = f32::from_bits(ix as u32);
        let u = ax - BP[k];
        let v = 1.0 / (ax + BP[k]);
        let s = u * v;
        let s_h = trunc(s, 0xffff_f000);
        let t_h = f32::from_bits(
            ((((ix as u32) >> 1) & 0xffff_f000) | 0x2000_0000) + 0x0040_0000 + ((k as u32) << 21),
        );
        let t_l = ax - (t_h - BP[k]);
        let s_l = v * ((u - s_h * t_h) - s_h * t_l);
        let mut s2 = s * s;
        let mut r = s2 * s2 * (L1 + s2 * (L2 + s2 * (L3 + s2 * (L4 + s2 * (L5 + s2 * L6)))));
        r += s_l * (s_h + s);
        s2 = s_h * s_h;
        let t_h = trunc(3.0 + s2 + r, 0xffff_f000);
        let t_l = r - ((t_h - 3.0) - s2);
        let u = s_h * t_h;
        let v = s_l * t_h + t_l * s;
        let p_h = trunc(u + v, 0xffff_f000);
        let p_l = v - (p_h - u);
        let z_h = CP_H * p_h;
        let z_l = CP_L * p_h + p_l * CP + DP_L[k];
        let t = n as f32;
        let t1 = trunc(((z_h + z_l) + DP_H[k]) + t, 0xffff_f000);
        let t2 = z_l - (((t1 - t) - DP_H[k]) - z_h);
        parts.t1[lane] = t1;
        parts.t2[lane] = t2;
    }
    parts
}

/// The `2^(y·log2 x)` half of the main path: the results and, per lane, whether `x`
/// and `y` are on the main path (`y` positive finite, at most 2^27, not ½, 1 or 2) and the
/// result neither underflows nor is subnormal.
#[inline(always)]
#[allow(clippy::excessive_precision)]
fn exp2_of_product_x4(log2_x: &Log2Parts, y: [f32; 4]) -> ([f32; 4], [bool; 4]) {
    const P1: f32 = 1.6666667163e-01;
    const P2: f32 = -2.7777778450e-03;
    const P3: f32 = 6.6137559770e-05;
    const P4: f32 = -1.6533901999e-06;
    const P5: f32 = 4.1381369442e-08;
    const LG2: f32 = 6.9314718246e-01;
    const LG2_H: f32 = 6.93145752e-01;
    const LG2_L: f32 = 1.42860654e-06;
    let trunc = |v: f32, mask: u32| f32::from_bits(v.to_bits() & mask);
    let mut out = [0.0f32; 4];
    let mut ok = [false; 4];
    for lane in 0..4 {
        let (t1, t2, y) = (log2_x.t1[lane], log2_x.t2[lane], y[lane]);
        let hy = y.to_bits() as i32;
        let on_path = log2_x.x_on_path[lane]
            && hy > 0
            && hy <= 0x4d00_0000
            && hy != 0x3f80_0000
            && hy != 0x4000_0000
            && hy != 0x3f00_0000;
        // y·log2(x) as p_h + p_l.
        let y1 = trunc(y, 0xffff_f000);
        let p_l = (y - y1) * t1 + y * t2;
        let mut p_h = y1 * t1;
        let z = p_l + p_h;
        let j = z.to_bits() as i32;
        // Overflow cannot happen for x < 1, y > 0; underflow goes to libm.
        let no_underflow = (j & 0x7fff_ffff) <= 0x4316_0000 && j as u32 != 0xc316_0000;
        // 2^(p_h + p_l): split off the integer part n when |z| > 0.5.
        let i = j & 0x7fff_ffff;
        let kk = (i >> 23) - 0x7f;
        let mut n = 0i32;
        if i > 0x3f00_0000 {
            let m = j.wrapping_add(0x0080_0000i32.wrapping_shr((kk + 1) as u32));
            let k2 = ((m & 0x7fff_ffff) >> 23) - 0x7f;
            let t = f32::from_bits(m as u32 & !(0x007f_ffffu32.wrapping_shr(k2 as u32)));
            n = ((m & 0x007f_ffff) | 0x0080_0000).wrapping_shr((23 - k2) as u32);
            if j < 0 {
                n = n.wrapping_neg();
            }
            p_h -= t;
        }
        let t = trunc(p_l + p_h, 0xffff_8000);
        let u = t * LG2_H;
        let v = (p_l - (t - p_h)) * LG2 + t * LG2_L;
        let z = u + v;
        let w = v - (z - u);
        let t = z * z;
        let t1 = z - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
        let r = (z * t1) / (t1 - 2.0) - (w + z * w);
        let z = 1.0 - (r - z);
        let j = (z.to_bits() as i32).wrapping_add(n.wrapping_shl(23));
        // A subnormal result takes libm's scalbn path.
        let normal_result = (j >> 23) > 0;
        out[lane] = f32::from_bits(j as u32);
        ok[lane] = on_path && no_underflow && normal_result;
    }
    (out, ok)
}

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

    /// Bases that exercise every branch: the three intervals of the reduced mantissa, values
    /// near 0 (underflow, subnormal results) and near 1, subnormal bases and special values.
    fn pow_bases() -> Vec<f32> {
        let mut bases = vec![
            0.0,
            -0.0,
            1.0,
            f32::MIN_POSITIVE,
            f32::MIN_POSITIVE / 4.0,
            1e-30,
            1e-10,
            1e-3,
            0.5,
            0.7072,
            0.75,
            0.8660,
            0.9,
            0.99999994,
            1.5,
            -0.5,
            f32::NAN,
            f32::INFINITY,
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

    #[test]
    fn pow01_x4_is_bit_identical_to_pow01() {
        let exponents = [
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
            -1.0,
            f32::NAN,
            f32::INFINITY,
            1.0e-6,
            150.0,
            3.0e7,
            134217728.0,
            1000.0,
        ];
        let bases = pow_bases();
        for (e_index, chunk) in bases.chunks_exact(4).enumerate() {
            let base = [chunk[0], chunk[1], chunk[2], chunk[3]];
            let exponent = std::array::from_fn(|i| exponents[(e_index + i * 5) % exponents.len()]);
            let got = pow01_x4(base, exponent);
            for i in 0..4 {
                let want = pow01(base[i], exponent[i]);
                assert_eq!(
                    got[i].to_bits(),
                    want.to_bits(),
                    "pow01({}, {}) = {want}, x4 gave {}",
                    base[i],
                    exponent[i],
                    got[i]
                );
            }
        }
    }

    /// Random bases over every bit pattern of [0, 1] and random exponents from 2^-12 to 2^14:
    /// results from 1 down to the subnormals, so every split of `y·log2 x` into integer and
    /// fraction (the variable shifts of the main path) is met.
    #[test]
    fn pow01_x4_matches_pow01_on_random_bases_and_exponents() {
        let mut rng = crate::shading::test_support::Lcg::new(97);
        for _ in 0..100_000 {
            let base: [f32; 4] =
                std::array::from_fn(|_| f32::from_bits((rng.next_u64() % 0x3f80_0001) as u32));
            let exponent: [f32; 4] = std::array::from_fn(|_| 2f32.powf(rng.range(-12.0, 14.0)));
            let other: [f32; 4] = std::array::from_fn(|_| 2f32.powf(rng.range(-12.0, 14.0)));
            let got = pow01_x4(base, exponent);
            let (first, second) = pow01_x4_two_exponents(base, exponent, other);
            for i in 0..4 {
                let want = pow01(base[i], exponent[i]);
                assert_eq!(
                    got[i].to_bits(),
                    want.to_bits(),
                    "{}^{}",
                    base[i],
                    exponent[i]
                );
                assert_eq!(
                    first[i].to_bits(),
                    want.to_bits(),
                    "{}^{}",
                    base[i],
                    exponent[i]
                );
                assert_eq!(
                    second[i].to_bits(),
                    pow01(base[i], other[i]).to_bits(),
                    "{}^{}",
                    base[i],
                    other[i]
                );
            }
        }
    }

    /// Every base in (0, 1] against libm for the exponents the scenes use. Minutes in release:
    /// `cargo test --release -- --ignored pow01_x4_exhaustive`.
    #[test]
    #[ignore]
    fn pow01_x4_exhaustive() {
        for exponent in [4.8f32, 40.0, 80.0, 20.0, 0.3] {
            let mut bits = 1u32;
            while bits <= 0x3f80_0000 {
                let base: [f32; 4] =
                    std::array::from_fn(|i| f32::from_bits((bits + i as u32).min(0x3f80_0000)));
                let got = pow01_x4(base, [exponent; 4]);
                for i in 0..4 {
                    assert_eq!(
                        got[i].to_bits(),
                        pow01(base[i], exponent).to_bits(),
                        "{}^{exponent}",
                        base[i]
                    );
                }
                bits += 4;
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
