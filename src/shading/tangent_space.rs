//! Tangent space (thesis 3.2.1; shading stage): eye and light vectors are taken into the T, B, N
//! basis so that they meet the strand tangents stored in the shell textures in the same space; and
//! the angle helpers the Kajiya–Kay terms are built from.

use super::lanes::{Vec3xN, select_bits};
use crate::mesh::frame::TangentFrame;
use glam::Vec3;

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

/// [`cos_sin_unit`] on `N` lanes, lane by lane the same bits (a plain loop that vectorises).
#[inline(always)]
pub(crate) fn cos_sin_unit_lanes<const N: usize>(
    a: &Vec3xN<N>,
    b: &Vec3xN<N>,
) -> ([f32; N], [f32; N]) {
    let dot = a.dot(b);
    let (a_zero, b_zero) = (a.zero_mask(), b.zero_mask());
    let (mut cos, mut sin) = ([0.0; N], [0.0; N]);
    for i in 0..N {
        // `f32::clamp`: NaN stays NaN.
        let c = if dot[i] < -1.0 { -1.0 } else { dot[i] };
        let c = if c > 1.0 { 1.0 } else { c };
        // `f32::max(x, 0)` is 0 for NaN `x`.
        let d = 1.0 - c * c;
        let s = (if d > 0.0 { d } else { 0.0 }).sqrt();
        let zero = a_zero[i] | b_zero[i];
        cos[i] = select_bits(zero, 0.0, c);
        sin[i] = select_bits(zero, 0.0, s);
    }
    (cos, sin)
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
    fn cos_sin_unit_lanes_are_single_calls_bit_for_bit() {
        lanes_bit_for_bit::<4>();
        lanes_bit_for_bit::<8>();
    }

    fn lanes_bit_for_bit<const N: usize>() {
        let mut rng = Lcg::new(44);
        for k in 0..3000 {
            let a = crate::shading::lanes::tests::lanes_n::<N>(&mut rng, k);
            let b = crate::shading::lanes::tests::lanes_n::<N>(&mut rng, k + 2);
            let unit = |v: [Vec3; N]| v.map(|v| if k % 2 == 0 { v.normalize_or_zero() } else { v });
            let (a, b) = (unit(a), unit(b));
            let (cos, sin) = cos_sin_unit_lanes(&Vec3xN::from_lanes(a), &Vec3xN::from_lanes(b));
            for i in 0..N {
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
