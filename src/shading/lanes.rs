//! Fragments side by side, one array per vector component (shading stage): the four lanes of a 2×2
//! quad ([`Vec3x4`]) or the lit lanes of a batch ([`Vec3x8`]; 32 lanes in the AVX2 copy, 16 in
//! the AVX-512 copy).
//! Operations are plain per-lane loops over the arrays, which LLVM turns into packed
//! instructions as wide as the level's copy of the hot path allows ([`crate::simd`]: 512 bits
//! with AVX-512, 256 with AVX2, 128 on SSE2 and NEON).
//!
//! Invariant: every operation here is, lane by lane, the same IEEE operations in the same
//! order as its scalar twin on glam's `Vec3` (named in each doc comment), so a lane gives the
//! same bits as the scalar code. No fused multiply-adds, no reassociation, no approximate
//! reciprocals: Rust never contracts or reorders float operations on its own, and only
//! correctly rounded operations are used (`+ − × ÷`, `sqrt`, comparisons and selects; never
//! `wide`'s `recip`, `recip_sqrt` or `mul_add`). The tests check the bits against the twins on
//! random, special and degenerate vectors, at 4, 8, 16 and 32 lanes.

// Lanes are indexed loops over several arrays at once: the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;

/// Lanes per quad: the four fragments of a 2×2 quad.
pub const LANES: usize = 4;

/// `N` 3-vectors, one array per component.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3xN<const N: usize> {
    /// The x components.
    pub x: [f32; N],
    /// The y components.
    pub y: [f32; N],
    /// The z components.
    pub z: [f32; N],
}

impl<const N: usize> Default for Vec3xN<N> {
    /// Zero in every lane.
    fn default() -> Self {
        Self::splat(Vec3::ZERO)
    }
}

/// The four lanes of a quad.
pub type Vec3x4 = Vec3xN<LANES>;

/// Eight lanes: a batch of lit fragments.
pub type Vec3x8 = Vec3xN<8>;

/// `f(a[i], b[i])` for each lane, as a plain loop that vectorises.
#[inline(always)]
fn zip_lanes<const N: usize>(a: [f32; N], b: [f32; N], f: impl Fn(f32, f32) -> f32) -> [f32; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = f(a[i], b[i]);
    }
    out
}

/// All bits set where `condition` holds, else none: a lane mask for [`select_bits`].
#[inline(always)]
pub(crate) fn lane_mask(condition: bool) -> u32 {
    u32::from(condition).wrapping_neg()
}

/// `if mask { a } else { b }` for a [`lane_mask`], as bit operations, which loops over lanes
/// vectorise (LLVM keeps a float `if` in a loop as a branch).
#[inline(always)]
pub(crate) fn select_bits(mask: u32, a: f32, b: f32) -> f32 {
    f32::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

impl<const N: usize> Vec3xN<N> {
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Vec3xN {
            x: [v.x; N],
            y: [v.y; N],
            z: [v.z; N],
        }
    }

    /// From `N` vectors, lane `i` = `v[i]`.
    #[inline(always)]
    pub fn from_lanes(v: [Vec3; N]) -> Self {
        Vec3xN {
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

    /// `Vec3::dot`: `(x·x' + y·y') + z·z'`.
    #[inline(always)]
    pub fn dot(&self, o: &Self) -> [f32; N] {
        let mut out = [0.0; N];
        for i in 0..N {
            out[i] = (self.x[i] * o.x[i] + self.y[i] * o.y[i]) + self.z[i] * o.z[i];
        }
        out
    }

    /// `self + s·o` per lane (`Vec3 + f32 * Vec3`).
    #[inline(always)]
    pub fn add_scaled(&self, s: [f32; N], o: &Self) -> Self {
        let mut out = *self;
        for i in 0..N {
            out.x[i] = self.x[i] + s[i] * o.x[i];
            out.y[i] = self.y[i] + s[i] * o.y[i];
            out.z[i] = self.z[i] + s[i] * o.z[i];
        }
        out
    }

    /// `self·s − 1` per component (`v * s - Vec3::ONE`).
    #[inline(always)]
    pub fn scale_minus_one(&self, s: f32) -> Self {
        let mut out = *self;
        for i in 0..N {
            out.x[i] = self.x[i] * s - 1.0;
            out.y[i] = self.y[i] * s - 1.0;
            out.z[i] = self.z[i] * s - 1.0;
        }
        out
    }

    /// `Vec3::normalize_or`: `r = 1 / sqrt(v·v)`; `v·r` where `r` is finite and positive, else
    /// the fallback's lane.
    #[inline(always)]
    pub fn normalize_or(&self, fallback: &Self) -> Self {
        let mut rcp = self.dot(self);
        for r in &mut rcp {
            *r = 1.0 / r.sqrt();
        }
        let mut out = *fallback;
        for i in 0..N {
            // Finite and positive (NaN is neither): the bits from 1 to those of `f32::MAX`. An
            // integer compare, because LLVM does not vectorise a loop that combines float
            // compares into a bool.
            let r = rcp[i];
            let keep = lane_mask(r.to_bits().wrapping_sub(1) < f32::MAX.to_bits());
            out.x[i] = select_bits(keep, self.x[i] * r, fallback.x[i]);
            out.y[i] = select_bits(keep, self.y[i] * r, fallback.y[i]);
            out.z[i] = select_bits(keep, self.z[i] * r, fallback.z[i]);
        }
        out
    }

    /// [`Vec3xN::normalize_or`] with the fallback computed only where a lane takes it: the same
    /// lanes, without the fallback's work in the common batch where none does (a fallback that
    /// is itself a normalisation costs as much as the vector's own).
    #[inline(always)]
    pub fn normalize_or_else(&self, fallback: impl FnOnce() -> Self) -> Self {
        let mut rcp = self.dot(self);
        for r in &mut rcp {
            *r = 1.0 / r.sqrt();
        }
        let mut out = *self;
        let mut keep = [0u32; N];
        let mut every = u32::MAX;
        for i in 0..N {
            // As in `normalize_or`: finite and positive, one integer compare.
            let r = rcp[i];
            keep[i] = lane_mask(r.to_bits().wrapping_sub(1) < f32::MAX.to_bits());
            every &= keep[i];
            out.x[i] = self.x[i] * r;
            out.y[i] = self.y[i] * r;
            out.z[i] = self.z[i] * r;
        }
        if every == 0 {
            let fallback = fallback();
            for i in 0..N {
                out.x[i] = select_bits(keep[i], out.x[i], fallback.x[i]);
                out.y[i] = select_bits(keep[i], out.y[i], fallback.y[i]);
                out.z[i] = select_bits(keep[i], out.z[i], fallback.z[i]);
            }
        }
        out
    }

    /// `Vec3::normalize_or_zero`.
    #[inline(always)]
    pub fn normalize_or_zero(&self) -> Self {
        self.normalize_or(&Self::splat(Vec3::ZERO))
    }

    /// `v == Vec3::ZERO` per lane (−0 counts as zero, NaN does not).
    #[inline(always)]
    pub fn is_zero(&self) -> [bool; N] {
        self.zero_mask().map(|m| m != 0)
    }

    /// [`Vec3xN::is_zero`] as a [`lane_mask`]: every component's bits but the sign are 0.
    #[inline(always)]
    pub(crate) fn zero_mask(&self) -> [u32; N] {
        let mut mask = [0; N];
        for i in 0..N {
            let bits = self.x[i].to_bits() | self.y[i].to_bits() | self.z[i].to_bits();
            mask[i] = lane_mask(bits << 1 == 0);
        }
        mask
    }

    /// The per-lane product `s·v` (`f32 * Vec3`).
    #[inline(always)]
    pub fn scaled(&self, s: [f32; N]) -> Self {
        Vec3xN {
            x: zip_lanes(s, self.x, |s, c| s * c),
            y: zip_lanes(s, self.y, |s, c| s * c),
            z: zip_lanes(s, self.z, |s, c| s * c),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::shading::test_support::Lcg;

    /// Random lanes with specials mixed in: zero, −0, NaN, infinite, tiny and huge vectors.
    pub(crate) fn lanes_n<const N: usize>(rng: &mut Lcg, k: usize) -> [Vec3; N] {
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
        twins_bit_for_bit::<4>();
        twins_bit_for_bit::<8>();
        twins_bit_for_bit::<16>();
        twins_bit_for_bit::<32>();
    }

    fn twins_bit_for_bit<const N: usize>() {
        let mut rng = Lcg::new(41);
        for k in 0..5000 {
            let (a, b, c) = (
                lanes_n::<N>(&mut rng, k),
                lanes_n::<N>(&mut rng, k + 3),
                lanes_n::<N>(&mut rng, k + 5),
            );
            let s: [f32; N] = std::array::from_fn(|i| rng.range(-2.0, 2.0) * (i as f32));
            let (va, vb, vc) = (
                Vec3xN::from_lanes(a),
                Vec3xN::from_lanes(b),
                Vec3xN::from_lanes(c),
            );
            let dot = va.dot(&vb);
            let sum = va.add_scaled(s, &vb);
            let decoded = va.scale_minus_one(2.0);
            let normal_or = va.normalize_or(&vc);
            let mut fell_back = false;
            let normal_or_else = va.normalize_or_else(|| {
                fell_back = true;
                vc
            });
            let normal = va.normalize_or_zero();
            let zero = va.is_zero();
            let scaled = va.scaled(s);
            for i in 0..N {
                assert_eq!(bits(scaled.lane(i)), bits(s[i] * a[i]), "scaled");
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
                    bits(normal_or_else.lane(i)),
                    bits(a[i].normalize_or(c[i])),
                    "normalize_or_else {:?}",
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
            // The fallback is computed exactly where a lane takes it.
            let takes = (0..N).any(|i| {
                let rcp = 1.0 / a[i].length();
                !(rcp.is_finite() && rcp > 0.0)
            });
            assert_eq!(fell_back, takes, "fallback computed {fell_back} {a:?}");
        }
    }
}
