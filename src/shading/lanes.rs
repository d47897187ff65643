//! Four fragments at once (the lanes of a 2×2 quad), one array per vector component; each
//! operation runs on packed 4-lane registers (`wide::f32x4`: SSE on x86-64, NEON on AArch64,
//! plain arrays elsewhere).
//!
//! Invariant: every operation here is, lane by lane, the same IEEE operations in the same
//! order as its scalar twin on glam's `Vec3` (named in each doc comment), so a lane gives the
//! same bits as the scalar code. No fused multiply-adds, no reassociation, no approximate
//! reciprocals: Rust never contracts or reorders float operations on its own, and only `wide`'s
//! correctly rounded operations are used (`+ − × ÷`, `sqrt`, comparisons and `select`; never
//! its `recip`, `recip_sqrt` or `mul_add`). The tests check
//! the bits against the twins on random, special and degenerate vectors.

use glam::Vec3;
use wide::f32x4;

/// Lanes per batch: the four fragments of a quad.
pub const LANES: usize = 4;

/// Four 3-vectors, one array per component.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3x4 {
    /// The x components.
    pub x: [f32; LANES],
    /// The y components.
    pub y: [f32; LANES],
    /// The z components.
    pub z: [f32; LANES],
}

impl Vec3x4 {
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Vec3x4 {
            x: [v.x; LANES],
            y: [v.y; LANES],
            z: [v.z; LANES],
        }
    }

    /// From four vectors, lane `i` = `v[i]`.
    #[inline(always)]
    pub fn from_lanes(v: [Vec3; LANES]) -> Self {
        Vec3x4 {
            x: v.map(|v| v.x),
            y: v.map(|v| v.y),
            z: v.map(|v| v.z),
        }
    }

    /// Lane `i` as a vector.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    /// The components as packed registers.
    #[inline(always)]
    pub(crate) fn packed(&self) -> [f32x4; 3] {
        [self.x, self.y, self.z].map(f32x4::new)
    }

    /// From packed components.
    #[inline(always)]
    pub(crate) fn from_packed([x, y, z]: [f32x4; 3]) -> Self {
        Vec3x4 {
            x: x.to_array(),
            y: y.to_array(),
            z: z.to_array(),
        }
    }

    /// `Vec3::dot`: `(x·x' + y·y') + z·z'`.
    #[inline(always)]
    pub fn dot(&self, o: &Self) -> [f32; LANES] {
        dot_packed(self.packed(), o.packed()).to_array()
    }

    /// `self + s·o` per lane (`Vec3 + f32 * Vec3`).
    #[inline(always)]
    pub fn add_scaled(&self, s: [f32; LANES], o: &Self) -> Self {
        let s = f32x4::new(s);
        let (a, b) = (self.packed(), o.packed());
        Self::from_packed(std::array::from_fn(|c| a[c] + s * b[c]))
    }

    /// `self·s − 1` per component (`v * s - Vec3::ONE`).
    #[inline(always)]
    pub fn scale_minus_one(&self, s: f32) -> Self {
        let s = f32x4::splat(s);
        Self::from_packed(self.packed().map(|c| c * s - f32x4::ONE))
    }

    /// `Vec3::normalize_or`: `r = 1 / sqrt(v·v)`; `v·r` where `r` is finite and positive, else
    /// the fallback's lane.
    #[inline(always)]
    pub fn normalize_or(&self, fallback: &Self) -> Self {
        let v = self.packed();
        let rcp = f32x4::ONE / dot_packed(v, v).sqrt();
        let keep = rcp.is_finite() & rcp.simd_gt(f32x4::ZERO);
        let fallback = fallback.packed();
        Self::from_packed(std::array::from_fn(|c| {
            keep.select(v[c] * rcp, fallback[c])
        }))
    }

    /// `Vec3::normalize_or_zero`.
    #[inline(always)]
    pub fn normalize_or_zero(&self) -> Self {
        self.normalize_or(&Vec3x4::splat(Vec3::ZERO))
    }

    /// `v == Vec3::ZERO` per lane (−0 counts as zero, NaN does not).
    #[inline(always)]
    pub fn is_zero(&self) -> [bool; LANES] {
        self.zero_mask().to_array().map(|m| m.to_bits() != 0)
    }

    /// [`Vec3x4::is_zero`] as a lane mask (all bits set where zero), for `select`.
    #[inline(always)]
    pub(crate) fn zero_mask(&self) -> f32x4 {
        let [x, y, z] = self.packed();
        x.simd_eq(f32x4::ZERO) & y.simd_eq(f32x4::ZERO) & z.simd_eq(f32x4::ZERO)
    }
}

/// `Vec3::dot` of packed components: `(x·x' + y·y') + z·z'`.
#[inline(always)]
fn dot_packed([x, y, z]: [f32x4; 3], [x2, y2, z2]: [f32x4; 3]) -> f32x4 {
    (x * x2 + y * y2) + z * z2
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::shading::test_support::Lcg;

    /// Random lanes with specials mixed in: zero, −0, NaN, infinite, tiny and huge vectors.
    pub(crate) fn lanes(rng: &mut Lcg, k: usize) -> [Vec3; LANES] {
        let special = [
            Vec3::ZERO,
            Vec3::new(-0.0, 0.0, -0.0),
            Vec3::splat(f32::NAN),
            Vec3::new(f32::INFINITY, 0.0, 1.0),
            Vec3::splat(1e-30),
            Vec3::splat(3e38),
            Vec3::X,
        ];
        std::array::from_fn(|i| {
            if (k + i).is_multiple_of(9) {
                special[(k / 9 + i) % special.len()]
            } else {
                rng.cube() * [1.0, 1e-3, 40.0][(k + i) % 3]
            }
        })
    }

    fn bits(v: Vec3) -> [u32; 3] {
        v.to_array().map(f32::to_bits)
    }

    #[test]
    fn lane_operations_are_the_scalar_twins_bit_for_bit() {
        let mut rng = Lcg::new(41);
        for k in 0..5000 {
            let (a, b, c) = (
                lanes(&mut rng, k),
                lanes(&mut rng, k + 3),
                lanes(&mut rng, k + 5),
            );
            let s: [f32; LANES] = std::array::from_fn(|i| rng.range(-2.0, 2.0) * (i as f32));
            let (va, vb, vc) = (
                Vec3x4::from_lanes(a),
                Vec3x4::from_lanes(b),
                Vec3x4::from_lanes(c),
            );
            let dot = va.dot(&vb);
            let sum = va.add_scaled(s, &vb);
            let decoded = va.scale_minus_one(2.0);
            let normal_or = va.normalize_or(&vc);
            let normal = va.normalize_or_zero();
            let zero = va.is_zero();
            for i in 0..LANES {
                assert_eq!(bits(va.lane(i)), bits(a[i]));
                assert_eq!(
                    dot[i].to_bits(),
                    a[i].dot(b[i]).to_bits(),
                    "dot {a:?} {b:?}"
                );
                assert_eq!(bits(sum.lane(i)), bits(a[i] + s[i] * b[i]), "add_scaled");
                assert_eq!(
                    bits(decoded.lane(i)),
                    bits(a[i] * 2.0 - Vec3::ONE),
                    "decode"
                );
                assert_eq!(
                    bits(normal_or.lane(i)),
                    bits(a[i].normalize_or(c[i])),
                    "normalize_or {:?}",
                    a[i]
                );
                assert_eq!(
                    bits(normal.lane(i)),
                    bits(a[i].normalize_or_zero()),
                    "normalize_or_zero {:?}",
                    a[i]
                );
                assert_eq!(zero[i], a[i] == Vec3::ZERO, "is_zero {:?}", a[i]);
            }
        }
    }
}
