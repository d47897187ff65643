//! Small numeric helpers shared by the shading terms. Their invariant: every helper returns a
//! finite value for every input, NaN and infinities included, so no shading term can leak a NaN
//! into the framebuffer.

/// Clamps to `[0, 1]`; NaN becomes 0.
#[inline]
pub(crate) fn saturate(x: f32) -> f32 {
    if x > 0.0 { x.min(1.0) } else { 0.0 }
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
        assert_eq!(sanitize_exponent(f32::NAN), 1.0);
        assert_eq!(sanitize_exponent(-2.0), 0.0);
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
