//! Tangent space (thesis 3.2.1): eye and light vectors are taken into the T, B, N basis so that
//! they meet the strand tangents stored in the shell textures in the same space; and the angle
//! helpers the Kajiya–Kay terms are built from.

use super::lanes::{LANES, Vec3x4};
use crate::mesh::frame::TangentFrame;
use glam::Vec3;
use wide::f32x4;

/// Tangent-space coordinates `(v·T, v·B, v·N)` of a world vector (thesis 3.2.1: "we transform
/// the eye and the light vector by multiplying them with the T, B, N matrix").
///
/// Linear, no normalisation: a zero vector maps to zero, a NaN component propagates (callers
/// normalise with `normalize_or_zero`, which maps NaN to zero).
#[inline]
pub fn to_tangent_space(v: Vec3, frame: &TangentFrame) -> Vec3 {
    Vec3::new(
        v.dot(frame.tangent),
        v.dot(frame.binormal),
        v.dot(frame.normal),
    )
}

/// Cosine and sine of the angle between two vectors that are unit or zero. The sine is
/// `sqrt(max(0, 1 − cos²))`; a zero vector gives `(0, 0)`.
#[inline]
pub(crate) fn cos_sin_unit(a: Vec3, b: Vec3) -> (f32, f32) {
    if a == Vec3::ZERO || b == Vec3::ZERO {
        return (0.0, 0.0);
    }
    let c = a.dot(b).clamp(-1.0, 1.0);
    (c, (1.0 - c * c).max(0.0).sqrt())
}

/// [`cos_sin_unit`] on four lanes, lane by lane the same bits.
#[inline(always)]
pub(crate) fn cos_sin_unit_x4(a: &Vec3x4, b: &Vec3x4) -> ([f32; LANES], [f32; LANES]) {
    let dot = f32x4::new(a.dot(b));
    // `f32::clamp`: NaN stays NaN.
    let c = dot
        .simd_lt(f32x4::splat(-1.0))
        .select(f32x4::splat(-1.0), dot);
    let c = c.simd_gt(f32x4::ONE).select(f32x4::ONE, c);
    // `f32::max(x, 0)` is 0 for NaN `x`, and so is `wide`'s `max` with a non-NaN right side.
    let s = (f32x4::ONE - c * c).max(f32x4::ZERO).sqrt();
    let zero = a.zero_mask() | b.zero_mask();
    (
        zero.select(f32x4::ZERO, c).to_array(),
        zero.select(f32x4::ZERO, s).to_array(),
    )
}

/// Sine of the angle between `a` and `b`, in `[0, 1]`: both are normalised inside, then
/// `sin = sqrt(max(0, 1 − cos²))` as a shader computes it (thesis eq. 2.5 and 2.7 use
/// `sin(t, l)`).
///
/// A zero, infinite-length or NaN vector (which `normalize_or_zero` maps to zero) gives 0:
/// no defined direction, no lit cylinder.
///
/// Conditioning: near-parallel inputs lose precision, the absolute error being about
/// `1e-7 / sin` (cancellation in `1 − cos²`); the tests bound it by `1e-6·(1 + 1/sin)`.
#[inline]
pub fn sin_between(a: Vec3, b: Vec3) -> f32 {
    cos_sin_unit(a.normalize_or_zero(), b.normalize_or_zero()).1
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};
    use glam::DVec3;

    /// f64 sine of the angle via the cross product (well conditioned, independent of the
    /// `1 − cos²` route).
    pub(crate) fn sin64(a: Vec3, b: Vec3) -> f64 {
        let (a, b) = (a.as_dvec3(), b.as_dvec3());
        a.cross(b).length() / (a.length() * b.length())
    }

    /// Bound on `sin_between` versus `sin64`: `1e-6·(1 + 1/sin)`.
    pub(crate) fn sin_tol(s: f64) -> f64 {
        1e-6 * (1.0 + 1.0 / s.max(1e-12))
    }

    fn random_frame(rng: &mut Lcg) -> TangentFrame {
        let n = rng.direction();
        let d = rng.direction();
        let t = (d - n * n.dot(d)).normalize_or(n.any_orthonormal_vector());
        TangentFrame {
            tangent: t,
            binormal: n.cross(t),
            normal: n,
        }
    }

    #[test]
    fn tangent_space_matches_f64_dot_products() {
        // Bound: 1e-6·Σ|v_i·e_i| per coordinate (three f32 products and two sums).
        let mut rng = Lcg::new(1);
        for _ in 0..500 {
            let frame = random_frame(&mut rng);
            let v = rng.cube() * 10.0;
            let got = to_tangent_space(v, &frame);
            for (k, axis) in [frame.tangent, frame.binormal, frame.normal]
                .into_iter()
                .enumerate()
            {
                let (vd, ad) = (v.as_dvec3(), axis.as_dvec3());
                let tol = 1e-6 * (vd.abs().dot(ad.abs()) + 1e-30);
                assert_close(got[k], vd.dot(ad), tol, "tangent-space coordinate");
            }
        }
    }

    #[test]
    fn tangent_space_of_frame_axes_is_identity() {
        let frame = TangentFrame {
            tangent: Vec3::X,
            binormal: Vec3::Z,
            normal: -Vec3::Y,
        };
        assert_eq!(to_tangent_space(Vec3::X, &frame), Vec3::X);
        assert_eq!(to_tangent_space(Vec3::Z, &frame), Vec3::Y);
        assert_eq!(to_tangent_space(-Vec3::Y, &frame), Vec3::Z);
        assert_eq!(to_tangent_space(Vec3::ZERO, &frame), Vec3::ZERO);
    }

    #[test]
    fn sin_between_matches_f64_cross_product() {
        let mut rng = Lcg::new(2);
        for _ in 0..2000 {
            let a = rng.cube() * rng.range(0.1, 10.0);
            let b = rng.cube() * rng.range(0.1, 10.0);
            let expected = sin64(a, b);
            assert_close(
                sin_between(a, b),
                expected,
                sin_tol(expected),
                "sin_between",
            );
        }
    }

    #[test]
    fn cos_sin_unit_x4_is_four_single_calls_bit_for_bit() {
        let mut rng = Lcg::new(44);
        for k in 0..3000 {
            let a = crate::shading::lanes::tests::lanes(&mut rng, k);
            let b = crate::shading::lanes::tests::lanes(&mut rng, k + 2);
            let unit =
                |v: [Vec3; LANES]| v.map(|v| if k % 2 == 0 { v.normalize_or_zero() } else { v });
            let (a, b) = (unit(a), unit(b));
            let (cos, sin) = cos_sin_unit_x4(&Vec3x4::from_lanes(a), &Vec3x4::from_lanes(b));
            for i in 0..LANES {
                let (c, s) = cos_sin_unit(a[i], b[i]);
                assert_eq!(
                    [cos[i].to_bits(), sin[i].to_bits()],
                    [c.to_bits(), s.to_bits()],
                    "{:?} {:?}",
                    a[i],
                    b[i]
                );
            }
        }
    }

    #[test]
    fn sin_between_edge_cases() {
        assert_eq!(sin_between(Vec3::X, Vec3::X), 0.0);
        assert_eq!(sin_between(Vec3::X, -Vec3::X * 3.0), 0.0);
        assert_eq!(sin_between(Vec3::X, Vec3::Y), 1.0);
        assert_eq!(sin_between(Vec3::ZERO, Vec3::Y), 0.0);
        assert_eq!(sin_between(Vec3::X, Vec3::ZERO), 0.0);
        assert_eq!(sin_between(Vec3::new(f32::NAN, 0.0, 1.0), Vec3::Y), 0.0);
        assert_eq!(
            sin_between(Vec3::new(f32::INFINITY, 0.0, 1.0), Vec3::Y),
            0.0
        );
        // 45°: sin = cos = 1/√2.
        assert_close(
            sin_between(Vec3::new(1.0, 1.0, 0.0), Vec3::X),
            DVec3::new(1.0, 1.0, 0.0).normalize().y,
            1e-6,
            "45 degrees",
        );
    }
}
