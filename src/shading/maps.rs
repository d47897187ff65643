//! Painted fur (shading stage): the shading-time terms of the length, density, direction and colour
//! maps (sampled in mesh uv space, see [`crate::render::maps`]).
//!
//! Where each map acts, and why:
//! - **length**: the vertex stage scales each shell's height by the length at the vertex; the
//!   fragment stage drops a layer whose height there exceeds the length sampled at the fragment
//!   ([`layer_within_length`]), so a sharp edge in the map stays sharp on a coarse mesh.
//! - **density**: strands are kept by a key fixed per strand id; the bake stores, per layer,
//!   the alpha of the strands in each quarter of keys ([`density_alpha`]): raising the density
//!   only adds strands, never moves one.
//! - **direction** (combing) acts at shading time as a lean, the same mechanism as wind and
//!   gravity ([`super::motion`]): the fur tile is baked once and repeated over the whole mesh,
//!   so a direction that differs per region cannot be baked into it.
//! - **colour** multiplies the texel's strand colour before spots and stripes are painted over
//!   it (their colours are absolute, as in thesis 3.2.4) and before charring.

use super::numeric::saturate;
use glam::{Vec2, Vec3, Vec4};

/// Number of density bands: strands are split by key into quarters.
pub const DENSITY_BANDS: u32 = 4;

/// Whether a shell layer shows at this fragment: the root layer always does; layer `i` at
/// `height_fraction = i/N` does while its height `height_fraction · vertex_length` (the vertex
/// stage placed it there) is below the fur length `local_length` sampled here. Both lengths are
/// fractions of `model_difference`; `local_length ≤ 0` leaves only the root layer.
#[inline]
pub fn layer_within_length(height_fraction: f32, vertex_length: f32, local_length: f32) -> bool {
    height_fraction <= 0.0 || height_fraction * vertex_length < local_length
}

/// The alpha of a texel with the fraction `density` of strands kept, from `bands`: the alphas
/// of the strands whose key falls in the first 1, 2, 3 and 4 quarters. With `x = 4·density`
/// (saturated), the result is linear between band `⌊x⌋ − 1` (0 below the first) and band `⌊x⌋`:
/// a band's strands fade in together as the density crosses its quarter, and the result is
/// continuous and non-decreasing in `density`.
#[inline]
pub fn density_alpha(bands: Vec4, density: f32) -> f32 {
    let x = saturate(density) * DENSITY_BANDS as f32;
    let k = libm::floorf(x);
    let f = x - k;
    let band = |i: i32| match i {
        0 => bands.x,
        1 => bands.y,
        2 => bands.z,
        3 => bands.w,
        _ if i < 0 => 0.0,
        _ => bands.w,
    };
    let k = k as i32;
    if k >= DENSITY_BANDS as i32 {
        return bands.w;
    }
    let below = band(k - 1);
    below + (band(k) - below) * f
}

/// The density band (0..[`DENSITY_BANDS`]) of strand `index` under `seed`: the top two bits of
/// a SplitMix64 hash of the two, independent of the strand generator's random stream (so
/// strands and their order stay those of the uniform fur).
#[inline]
pub fn density_band(seed: u32, index: u32) -> u32 {
    let mut z = (u64::from(seed) << 32 | u64::from(index)).wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 62) as u32
}

/// The combing lean in tangent space from a direction-map sample: `x = r·2 − 1` (along `u`),
/// `y = g·2 − 1` (along `v`), shortened to length 1 when longer; `z = 0`.
#[inline]
pub fn comb_lean(sample: Vec4) -> Vec3 {
    let v = Vec2::new(sample.x * 2.0 - 1.0, sample.y * 2.0 - 1.0);
    let length = v.length();
    let v = if length > 1.0 { v / length } else { v };
    if v.is_finite() {
        v.extend(0.0)
    } else {
        Vec3::ZERO
    }
}

/// The strand colour under a colour map: component-wise `strand · tint` (tint saturated).
#[inline]
pub fn tint_strand(strand: Vec3, tint: Vec3) -> Vec3 {
    strand * Vec3::new(saturate(tint.x), saturate(tint.y), saturate(tint.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    #[test]
    fn length_cut_keeps_the_root_and_layers_below_the_local_length() {
        assert!(layer_within_length(0.0, 1.0, 0.0));
        assert!(layer_within_length(0.5, 1.0, 0.6));
        assert!(!layer_within_length(0.5, 1.0, 0.5));
        assert!(!layer_within_length(0.1, 1.0, 0.0));
        // The vertex already shortened the layer: 0.9 · 0.5 = 0.45 < 0.5.
        assert!(layer_within_length(0.9, 0.5, 0.5));
        assert!(!layer_within_length(0.1, 0.0, 0.0));
    }

    #[test]
    fn density_alpha_matches_f64_and_is_monotone() {
        let mut rng = Lcg::new(3);
        for _ in 0..2000 {
            let mut b = [rng.unit(), rng.unit(), rng.unit(), rng.unit()];
            b.sort_by(f32::total_cmp);
            let bands = Vec4::from_array(b);
            let d = rng.unit();
            let x = f64::from(d) * 4.0;
            let k = x.floor() as usize;
            let f = x - k as f64;
            let at = |i: isize| {
                if i < 0 {
                    0.0
                } else {
                    f64::from(b[(i as usize).min(3)])
                }
            };
            let expected = if k >= 4 {
                at(3)
            } else {
                at(k as isize - 1) * (1.0 - f) + at(k as isize) * f
            };
            assert_close(density_alpha(bands, d), expected, 1e-6, "density alpha");
            let mut last = 0.0;
            for j in 0..=100 {
                let a = density_alpha(bands, j as f32 / 100.0);
                assert!(a >= last - 1e-7, "monotone");
                last = a;
            }
        }
        let bands = Vec4::new(0.1, 0.2, 0.3, 0.4);
        assert_eq!(density_alpha(bands, 0.0), 0.0);
        assert_eq!(density_alpha(bands, 0.25), 0.1);
        assert_eq!(density_alpha(bands, 1.0), 0.4);
        assert_eq!(density_alpha(bands, 2.0), 0.4);
        assert_eq!(density_alpha(bands, f32::NAN), 0.0);
    }

    #[test]
    fn density_bands_are_even_and_fixed_per_strand() {
        let mut counts = [0u32; 4];
        for i in 0..40_000 {
            let b = density_band(1234, i);
            assert_eq!(b, density_band(1234, i));
            counts[b as usize] += 1;
        }
        for c in counts {
            assert!((9_500..=10_500).contains(&c), "{counts:?}");
        }
        assert_ne!(
            (0..64).map(|i| density_band(1, i)).collect::<Vec<_>>(),
            (0..64).map(|i| density_band(2, i)).collect::<Vec<_>>()
        );
    }

    #[test]
    fn comb_lean_decodes_and_limits() {
        assert_eq!(comb_lean(Vec4::new(0.5, 0.5, 0.0, 1.0)), Vec3::ZERO);
        assert_eq!(
            comb_lean(Vec4::new(0.75, 0.5, 0.0, 1.0)),
            Vec3::new(0.5, 0.0, 0.0)
        );
        let full = comb_lean(Vec4::new(1.0, 1.0, 0.0, 1.0));
        assert!((full.length() - 1.0).abs() < 1e-6 && full.x == full.y);
        assert_eq!(comb_lean(Vec4::NAN), Vec3::ZERO);
    }

    #[test]
    fn tint_multiplies() {
        assert_eq!(
            tint_strand(Vec3::new(0.5, 0.4, 1.0), Vec3::new(0.5, 2.0, f32::NAN)),
            Vec3::new(0.25, 0.4, 0.0)
        );
    }
}
