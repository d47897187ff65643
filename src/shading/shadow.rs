//! Shell self-shadow (thesis 3.2.2, after Papaioannou; shading stage): from a texel, step towards
//! the light inside the current shell texture, and count how opaque the texels met are. The number
//! of steps shrinks from root to tip (`m = (N − i)/n`, the "height/n" of table 4.4).

use super::numeric::{finite_or_zero, saturate, saturate_select, saturate_x4};
use glam::{Vec2, Vec3};
use wide::f32x4;

/// Number of shadow lookups for a shell (thesis 3.2.2: "we divide the
/// (numberOfTotalShell − currentShell) with n, let this number be m"; table 4.4's
/// "height/n"): `m = (N − i) / n` with integer division.
///
/// With 30 shells and `n = 5` the bottom layer (`i = 0`) uses 6 lookups and the top
/// (`i = 29`) uses 0. A shell index above `N` gives 0 (saturating subtraction); a divisor of 0
/// gives 0 (shadow off) rather than dividing by zero.
#[inline]
pub fn shadow_lookup_count(number_of_shells: u32, shell_index: u32, divisor: u32) -> u32 {
    number_of_shells
        .saturating_sub(shell_index)
        .checked_div(divisor)
        .unwrap_or(0)
}

/// What one lookup of the shell self-shadow adds (thesis 3.2.2). Scene key
/// `shading.shadow_texel`.
///
/// The thesis: "check if the according pixel is transparent or not. If it is transparent; we
/// do not shade the current pixel. Else; shadowValue is increased": a count of the texels that
/// are not transparent ([`ShadowTexel::Opaque`]). Pelage's earlier convention adds the texel's
/// alpha instead ([`ShadowTexel::Alpha`]), the continuous form of the count: the two agree on
/// alpha 0 and 1. The default is [`ShadowTexel::Alpha`]; see [`shadow_of_opaque`] for why.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowTexel {
    /// 1 for a texel that is not transparent, else 0 ([`shadow_of_opaque`]).
    Opaque,
    /// The texel's alpha, saturated ([`shadow_of_alpha`]).
    #[default]
    Alpha,
}

/// Alpha below which a texel is transparent for [`shadow_of_opaque`]: half the smallest
/// non-zero 8-bit alpha, the threshold below which the fur fragment stage itself discards a
/// texel (`render::fragment::ALPHA_DISCARD`). A texel counts as opaque when its 8-bit alpha is
/// at least 1, i.e. when a strand's slice covers any of it.
pub const SHADOW_OPAQUE_ALPHA: f32 = 0.5 / 255.0;

/// One lookup as the thesis counts it (3.2.2, "shadowValue is increased" where the texel is not
/// transparent): 1 when `alpha ≥ SHADOW_OPAQUE_ALPHA`, else 0 (NaN gives 0).
///
/// Why it is not the default: the shell textures' alpha is an anti-aliased coverage times
/// Lengyel's Gaussian, so almost every texel is "not transparent", and mip levels merge texels
/// (the lookups read the level nearest the level of detail). Measured on `scenes/torus.toml`:
/// 85–93 % of the texels of layers 0–10 count at level 0 and 100 % from level 2 on; layer 20
/// goes from 42 % (level 0) to 94 % (level 2) while its mean alpha stays 0.14. The count thus
/// darkens every strand of a layer alike (Banks's ad-hoc shadow, which the thesis set aside)
/// and grows with distance; the alpha sum keeps its mean on every level (README, "Where pelage
/// departs from the thesis").
#[inline(always)]
pub fn shadow_of_opaque(alpha: f32) -> f32 {
    if alpha >= SHADOW_OPAQUE_ALPHA {
        1.0
    } else {
        0.0
    }
}

/// One lookup as its alpha, saturated to `[0, 1]` (NaN gives 0): the continuous form of
/// [`shadow_of_opaque`], equal to it on alpha 0 and 1, and the same on average over the texels
/// a mip level merges.
#[inline(always)]
pub fn shadow_of_alpha(alpha: f32) -> f32 {
    saturate(alpha)
}

/// One lookup's shadow as `texel` says: [`shadow_of_opaque`] or [`shadow_of_alpha`].
#[inline(always)]
pub fn shadow_texel(alpha: f32, texel: ShadowTexel) -> f32 {
    match texel {
        ShadowTexel::Opaque => shadow_of_opaque(alpha),
        ShadowTexel::Alpha => shadow_of_alpha(alpha),
    }
}

/// [`shadow_texel`] on four alphas, lane by lane the same bits.
#[inline(always)]
fn shadow_texel_x4(alphas: f32x4, texel: ShadowTexel) -> f32x4 {
    match texel {
        // A NaN lane compares false: 0, as the scalar form.
        ShadowTexel::Opaque => alphas
            .simd_ge(f32x4::splat(SHADOW_OPAQUE_ALPHA))
            .select(f32x4::ONE, f32x4::ZERO),
        ShadowTexel::Alpha => saturate_x4(alphas),
    }
}

/// Shell self-shadow value (thesis 3.2.2): for `k` in `1..=m` sample the current shell's alpha
/// at `uv + shadow_lookup·(k/m)` and add what [`shadow_texel`] makes of it (1 per opaque
/// texel, or the alpha); the result is in `[0, m]`.
///
/// Lookups are summed in order `k = 1, 2, …, m`. `m = 0` gives 0 without sampling. A
/// non-finite `uv` or `shadow_lookup` component is treated as 0.
#[inline]
pub fn shell_shadow(
    mut sample_alpha: impl FnMut(Vec2) -> f32,
    uv: Vec2,
    shadow_lookup: Vec2,
    lookups: u32,
    texel: ShadowTexel,
) -> f32 {
    let path = LookupPath::new(uv, shadow_lookup, lookups);
    let mut shadow = 0.0;
    for k in 1..=lookups {
        shadow += shadow_texel(sample_alpha(path.point(k)), texel);
    }
    shadow
}

/// Where the lookups of [`shell_shadow`] land: `uv + shadow_lookup·(k/m)`, non-finite
/// components as 0.
struct LookupPath {
    uv: Vec2,
    step: Vec2,
    m: f32,
}

impl LookupPath {
    #[inline(always)]
    fn new(uv: Vec2, shadow_lookup: Vec2, lookups: u32) -> Self {
        let finite = |v: Vec2| Vec2::new(finite_or_zero(v.x), finite_or_zero(v.y));
        LookupPath {
            uv: finite(uv),
            step: finite(shadow_lookup),
            m: lookups as f32,
        }
    }

    /// Lookup `k`.
    #[inline(always)]
    fn point(&self, k: u32) -> Vec2 {
        self.uv + self.step * (k as f32 / self.m)
    }

    /// [`LookupPath::point`] of four lookups `k`, as packed u and v lanes: the same
    /// operations lane by lane (glam's `Vec2` arithmetic is per component).
    #[inline(always)]
    fn points_x4(&self, k: [u32; 4]) -> ([f32; 4], [f32; 4]) {
        let fraction = f32x4::new(k.map(|k| k as f32)) / f32x4::splat(self.m);
        let along = |start: f32, step: f32| {
            (f32x4::splat(start) + f32x4::splat(step) * fraction).to_array()
        };
        (along(self.uv.x, self.step.x), along(self.uv.y, self.step.y))
    }
}

/// [`shell_shadow`] with the lookups sampled four at a time (`sample_alpha_x4` gets the u and
/// v of four points and returns their alphas): the same points, and the same sum in the same
/// order, so the same bits. Lanes past the last lookup repeat it and add +0 (no change). The
/// quad stage does not pad like this: it takes lookup `k` of its four fragments together
/// ([`shell_shadow_lanes`]).
#[inline]
pub fn shell_shadow_x4(
    mut sample_alpha_x4: impl FnMut([f32; 4], [f32; 4]) -> [f32; 4],
    uv: Vec2,
    shadow_lookup: Vec2,
    lookups: u32,
    texel: ShadowTexel,
) -> f32 {
    let path = LookupPath::new(uv, shadow_lookup, lookups);
    let mut shadow = 0.0;
    for first in (1..=lookups).step_by(4) {
        let k = [0, 1, 2, 3].map(|i| first.saturating_add(i).min(lookups));
        let (u, v) = path.points_x4(k);
        // Surplus lanes are multiplied by 0 and add +0, which leaves the sum's bits alone: it
        // starts at +0 and every lookup's shadow is +0 or in (0, 1]. No branch on the count or
        // on the alphas.
        let counted = [0, 1, 2, 3].map(|i| f32::from(u8::from(first.saturating_add(i) <= lookups)));
        let alphas =
            shadow_texel_x4(f32x4::new(sample_alpha_x4(u, v)), texel) * f32x4::new(counted);
        for alpha in alphas.to_array() {
            shadow += alpha;
        }
    }
    shadow
}

/// [`shell_shadow`] of `N` fragments of one layer (so one lookup count `m`), lookup `k` of
/// every lane in one batch: `sample_alpha` gets the u and v of lookup `k` of the lanes and
/// returns their alphas. Lane by lane the same points and the same sum in the same order
/// (`0 + s₁ + s₂ + … + s_m`), so the same bits as [`shell_shadow`] on each lane.
///
/// Why by lookup rather than by fragment ([`shell_shadow_x4`]): every lane of a layer has the
/// same `m`, so `m` batches serve all lanes with no padding, where four lookups a batch per
/// fragment pad `m` to a multiple of four (8 batches for `m = 6`, 4 for `m = 1`, against 6
/// and 1 here). The fraction `k/m` is computed once per batch for all lanes. Lanes the caller
/// does not need still run (give them any finite point; their sums are dropped).
#[inline(always)]
pub fn shell_shadow_lanes<const N: usize>(
    mut sample_alpha: impl FnMut([f32; N], [f32; N]) -> [f32; N],
    uv: [Vec2; N],
    shadow_lookup: [Vec2; N],
    lookups: u32,
    texel: ShadowTexel,
) -> [f32; N] {
    let mut sums = ShadowLanes::new(uv, shadow_lookup, lookups, texel);
    for k in 1..=lookups {
        let (u, v) = sums.point(k);
        sums.add(sample_alpha(u, v));
    }
    sums.shadow
}

/// [`shell_shadow_lanes`] step by step, for a caller whose sampler is too large to pass as a
/// closure (LLVM keeps a large closure out of line, outside the level's copy of the hot path):
/// for `k` in `1..=lookups`, sample the alphas at [`ShadowLanes::point`] and
/// [`ShadowLanes::add`] them; the sums are then in `shadow`.
#[derive(Clone, Copy, Debug)]
pub struct ShadowLanes<const N: usize> {
    u0: [f32; N],
    v0: [f32; N],
    du: [f32; N],
    dv: [f32; N],
    m: f32,
    texel: ShadowTexel,
    /// The sums so far, `0 + s₁ + …`.
    pub shadow: [f32; N],
}

impl<const N: usize> ShadowLanes<N> {
    /// The lanes' lookup paths, their sums at +0.
    #[inline(always)]
    pub fn new(uv: [Vec2; N], shadow_lookup: [Vec2; N], lookups: u32, texel: ShadowTexel) -> Self {
        let mut sums = ShadowLanes {
            u0: [0.0; N],
            v0: [0.0; N],
            du: [0.0; N],
            dv: [0.0; N],
            m: lookups as f32,
            texel,
            shadow: [0.0; N],
        };
        // `finite_or_zero` of each component, as `LookupPath::new`.
        for i in 0..N {
            sums.u0[i] = finite_or_zero(uv[i].x);
            sums.v0[i] = finite_or_zero(uv[i].y);
            sums.du[i] = finite_or_zero(shadow_lookup[i].x);
            sums.dv[i] = finite_or_zero(shadow_lookup[i].y);
        }
        sums
    }

    /// The u and v of lookup `k` of every lane: `LookupPath::point`, `uv + step·(k/m)`.
    #[inline(always)]
    pub fn point(&self, k: u32) -> ([f32; N], [f32; N]) {
        let fraction = k as f32 / self.m;
        let (mut u, mut v) = ([0.0f32; N], [0.0f32; N]);
        for i in 0..N {
            u[i] = self.u0[i] + self.du[i] * fraction;
            v[i] = self.v0[i] + self.dv[i] * fraction;
        }
        (u, v)
    }

    /// Adds what [`shadow_texel`] makes of the alphas of one lookup of every lane.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // an indexed loop over two arrays vectorises
    pub fn add(&mut self, alphas: [f32; N]) {
        for i in 0..N {
            self.shadow[i] += match self.texel {
                // A NaN lane compares false: 0, as the scalar form.
                ShadowTexel::Opaque => {
                    if alphas[i] >= SHADOW_OPAQUE_ALPHA {
                        1.0
                    } else {
                        0.0
                    }
                }
                ShadowTexel::Alpha => saturate_select(alphas[i]),
            };
        }
    }
}

/// Light directions closer to the surface than this cosine are treated as this cosine by
/// [`shadow_change`] (about 75.5° from the normal).
pub const SHADOW_MIN_COS: f32 = 0.25;

/// The `shadowChange` vector of thesis 3.2.2: the world vector from the current point towards
/// the light that climbs `height_above` along the normal,
/// `l̂ · height_above / max(l̂·n̂, 0.25)`.
///
/// The clamp keeps grazing light bounded (length at most `4·height_above`); light below the
/// surface (`l̂·n̂ ≤ 0`) uses the clamp too, so it still steps towards the light's side.
/// `light_dir_world` and `normal` are normalised inside (zero or NaN → zero vector, so the
/// result is zero for a zero light); `height_above` is clamped to be non-negative, and a
/// non-finite height gives zero.
#[inline]
pub fn shadow_change(light_dir_world: Vec3, normal: Vec3, height_above: f32) -> Vec3 {
    let l = light_dir_world.normalize_or_zero();
    let n = normal.normalize_or_zero();
    let h = finite_or_zero(height_above).max(0.0);
    let cos = l.dot(n).max(SHADOW_MIN_COS);
    l * (h / cos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    #[test]
    fn lookup_count_follows_table_4_4() {
        assert_eq!(shadow_lookup_count(30, 0, 5), 6);
        assert_eq!(shadow_lookup_count(30, 29, 5), 0);
        assert_eq!(shadow_lookup_count(30, 25, 5), 1);
        assert_eq!(shadow_lookup_count(30, 26, 5), 0);
        assert_eq!(shadow_lookup_count(30, 0, 1), 30);
        assert_eq!(shadow_lookup_count(30, 40, 5), 0);
        assert_eq!(shadow_lookup_count(30, 0, 0), 0);
        for i in 0..30 {
            assert_eq!(shadow_lookup_count(30, i, 3), (30 - i) / 3);
        }
    }

    #[test]
    fn shadow_samples_at_fractions_of_the_lookup() {
        let mut seen = Vec::new();
        let s = shell_shadow(
            |p| {
                seen.push(p);
                1.0
            },
            Vec2::new(0.25, 0.5),
            Vec2::new(0.3, -0.6),
            3,
            ShadowTexel::Alpha,
        );
        assert_eq!(s, 3.0);
        assert_eq!(seen.len(), 3);
        for (k, p) in seen.iter().enumerate() {
            let f = (k + 1) as f64 / 3.0;
            assert_close(p.x, 0.25 + 0.3 * f, 1e-7, "u");
            assert_close(p.y, 0.5 - 0.6 * f, 1e-7, "v");
        }
        // Last sample lands exactly on uv + shadow_lookup.
        assert_eq!(seen[2], Vec2::new(0.25, 0.5) + Vec2::new(0.3, -0.6));
    }

    #[test]
    fn four_at_a_time_is_the_same_sum_bit_for_bit() {
        let mut rng = Lcg::new(5);
        // A deterministic, position-dependent alpha with NaN and out-of-range values mixed in.
        let alpha = |p: Vec2| {
            let a = (p.x * 12.9898 + p.y * 78.233).sin() * 1.7;
            if a > 1.5 { f32::NAN } else { a }
        };
        for k in 0..3000 {
            let uv = Vec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            let offset = Vec2::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5));
            let lookups = k % 14;
            let texel = [ShadowTexel::Alpha, ShadowTexel::Opaque][k as usize % 2];
            let mut seen = Vec::new();
            let batched = shell_shadow_x4(
                |u, v| {
                    let points: [Vec2; 4] = std::array::from_fn(|i| Vec2::new(u[i], v[i]));
                    seen.extend(points);
                    points.map(alpha)
                },
                uv,
                offset,
                lookups,
                texel,
            );
            assert_eq!(
                batched.to_bits(),
                shell_shadow(alpha, uv, offset, lookups, texel).to_bits(),
                "{uv} {offset} {lookups}"
            );
            assert_eq!(seen.len(), lookups.div_ceil(4) as usize * 4);
            let mut scalar_points = Vec::new();
            shell_shadow(
                |p| {
                    scalar_points.push(p);
                    0.0
                },
                uv,
                offset,
                lookups,
                texel,
            );
            let bits = |points: &[Vec2]| {
                points
                    .iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&seen[..lookups as usize]),
                bits(&scalar_points),
                "{uv} {offset}"
            );
        }
        for bad in [f32::NAN, f32::INFINITY] {
            let uv = Vec2::new(bad, 0.5);
            for texel in [ShadowTexel::Alpha, ShadowTexel::Opaque] {
                assert_eq!(
                    shell_shadow_x4(
                        |u, v| std::array::from_fn(|i| alpha(Vec2::new(u[i], v[i]))),
                        uv,
                        Vec2::X,
                        5,
                        texel,
                    )
                    .to_bits(),
                    shell_shadow(alpha, uv, Vec2::X, 5, texel).to_bits()
                );
            }
        }
    }

    #[test]
    fn lanes_at_once_are_the_scalar_sums_bit_for_bit() {
        lanes_bit_for_bit::<4>();
        lanes_bit_for_bit::<8>();
    }

    fn lanes_bit_for_bit<const N: usize>() {
        let mut rng = Lcg::new(6);
        let alpha = |p: Vec2| {
            let a = (p.x * 12.9898 + p.y * 78.233).sin() * 1.7;
            if a > 1.5 { f32::NAN } else { a }
        };
        let specials = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, 1e30];
        for k in 0..3000u32 {
            let mut point = |scale: f32| {
                let mut p = Vec2::new(rng.range(-scale, scale), rng.range(-scale, scale));
                if k % 11 == 0 {
                    p.x = specials[(k / 11) as usize % specials.len()];
                }
                p
            };
            let uv: [Vec2; N] = std::array::from_fn(|_| point(3.0));
            let offset: [Vec2; N] = std::array::from_fn(|_| point(0.5));
            let lookups = k % 14;
            let texel = [ShadowTexel::Alpha, ShadowTexel::Opaque][k as usize % 2];
            let mut batches = 0;
            let lanes = shell_shadow_lanes(
                |u, v| {
                    batches += 1;
                    std::array::from_fn(|i| alpha(Vec2::new(u[i], v[i])))
                },
                uv,
                offset,
                lookups,
                texel,
            );
            // One batch per lookup, none padded.
            assert_eq!(batches, lookups);
            for i in 0..N {
                assert_eq!(
                    lanes[i].to_bits(),
                    shell_shadow(alpha, uv[i], offset[i], lookups, texel).to_bits(),
                    "lane {i}: {} {} {lookups}",
                    uv[i],
                    offset[i]
                );
            }
        }
    }

    #[test]
    fn shadow_adds_alpha_and_handles_edges() {
        let alpha = ShadowTexel::Alpha;
        // Transparent texels add nothing, opaque ones 1, partial ones their alpha.
        assert_eq!(shell_shadow(|_| 0.0, Vec2::ZERO, Vec2::X, 6, alpha), 0.0);
        let half = |p: Vec2| if p.x > 0.5 { 1.0 } else { 0.0 };
        assert_eq!(shell_shadow(half, Vec2::ZERO, Vec2::X, 4, alpha), 2.0);
        assert_eq!(shell_shadow(|_| 0.25, Vec2::ZERO, Vec2::X, 4, alpha), 1.0);
        // Out-of-range and NaN samples are saturated.
        assert_eq!(
            shell_shadow(|_| f32::NAN, Vec2::ZERO, Vec2::X, 4, alpha),
            0.0
        );
        assert_eq!(shell_shadow(|_| 7.0, Vec2::ZERO, Vec2::X, 4, alpha), 4.0);
        // No lookups: the sampler is never called.
        assert_eq!(
            shell_shadow(|_| unreachable!(), Vec2::ZERO, Vec2::X, 0, alpha),
            0.0
        );
        // Non-finite coordinates are replaced by 0 before sampling.
        shell_shadow(
            |p| {
                assert!(p.is_finite());
                1.0
            },
            Vec2::new(f32::NAN, 0.0),
            Vec2::splat(f32::INFINITY),
            2,
            alpha,
        );
    }

    #[test]
    fn shadow_counts_opaque_texels_as_the_thesis() {
        let opaque = ShadowTexel::Opaque;
        // Any texel with an 8-bit alpha of at least 1 counts in full; alpha 0 and NaN do not.
        assert_eq!(shell_shadow(|_| 0.25, Vec2::ZERO, Vec2::X, 4, opaque), 4.0);
        assert_eq!(
            shell_shadow(|_| 1.0 / 255.0, Vec2::ZERO, Vec2::X, 3, opaque),
            3.0
        );
        assert_eq!(shell_shadow(|_| 0.0, Vec2::ZERO, Vec2::X, 6, opaque), 0.0);
        assert_eq!(
            shell_shadow(|_| f32::NAN, Vec2::ZERO, Vec2::X, 6, opaque),
            0.0
        );
        let below = SHADOW_OPAQUE_ALPHA.next_down();
        assert_eq!(shadow_of_opaque(below), 0.0);
        assert_eq!(shadow_of_opaque(SHADOW_OPAQUE_ALPHA), 1.0);
        assert_eq!(shadow_of_opaque(f32::INFINITY), 1.0);
        assert_eq!(shadow_of_opaque(-1.0), 0.0);
        assert_eq!(ShadowTexel::default(), ShadowTexel::Alpha);
    }

    #[test]
    fn shadow_texels_match_f64() {
        // Every 8-bit alpha and random ones: the count is exact, the alpha sum within 4 ulps of
        // 4 per lookup (2e-6 over six lookups).
        let mut rng = Lcg::new(41);
        for k in 0..3000u32 {
            let lookups = k % 7;
            let alphas: Vec<f32> = (0..lookups)
                .map(|i| {
                    if (k + i) % 3 == 0 {
                        ((k * 7 + i * 31) % 256) as f32 / 255.0
                    } else {
                        rng.range(-0.2, 1.2)
                    }
                })
                .collect();
            let run = |texel| {
                let mut next = alphas.iter();
                let sample = |_| next.next().copied().unwrap_or(f32::NAN);
                shell_shadow(sample, Vec2::ZERO, Vec2::X, lookups, texel)
            };
            let (count, sum) = (run(ShadowTexel::Opaque), run(ShadowTexel::Alpha));
            let transparent = 0.5 / 255.0;
            let expected_count = alphas
                .iter()
                .filter(|&&a| f64::from(a) >= transparent)
                .count() as f64;
            let expected_sum: f64 = alphas.iter().map(|&a| f64::from(a).clamp(0.0, 1.0)).sum();
            assert_close(count, expected_count, 0.0, "opaque count");
            assert_close(sum, expected_sum, 2e-6, "alpha sum");
            for &a in &alphas {
                assert_eq!(shadow_texel(a, ShadowTexel::Opaque), shadow_of_opaque(a));
                assert_eq!(shadow_texel(a, ShadowTexel::Alpha), shadow_of_alpha(a));
            }
        }
    }

    #[test]
    fn shadow_change_matches_f64() {
        // Bound: 1e-6·(1 + length of the result) (normalisation, one dot, one division).
        let mut rng = Lcg::new(40);
        for _ in 0..2000 {
            let (l, n, h) = (rng.cube(), rng.cube(), rng.range(0.0, 2.0));
            let (ld, nd) = (l.as_dvec3().normalize(), n.as_dvec3().normalize());
            let expected = ld * f64::from(h) / ld.dot(nd).max(0.25);
            let got = shadow_change(l, n, h);
            for k in 0..3 {
                assert_close(
                    got[k],
                    expected[k],
                    1e-6 * (1.0 + expected.length()),
                    "change",
                );
            }
            // Climbs exactly h along the normal when the light is not grazing.
            if ld.dot(nd) >= 0.25 {
                assert_close(
                    got.dot(n.normalize()),
                    f64::from(h),
                    1e-5 * (1.0 + f64::from(h)),
                    "climb",
                );
            }
            assert!(f64::from(got.length()) <= 4.0 * f64::from(h) * (1.0 + 1e-6));
        }
    }

    #[test]
    fn shadow_change_edge_cases() {
        // Straight overhead: the change is h along the normal.
        assert_eq!(shadow_change(Vec3::Y * 3.0, Vec3::Y, 0.5), Vec3::Y * 0.5);
        // Grazing and below-surface light use the clamp: length 4h.
        assert_eq!(shadow_change(Vec3::X, Vec3::Y, 0.5), Vec3::X * 2.0);
        assert_eq!(shadow_change(-Vec3::Y, Vec3::Y, 0.5), -Vec3::Y * 2.0);
        // Degenerate inputs give finite results.
        assert_eq!(shadow_change(Vec3::ZERO, Vec3::Y, 0.5), Vec3::ZERO);
        assert!(shadow_change(Vec3::X, Vec3::ZERO, 0.5).is_finite());
        assert!(shadow_change(Vec3::splat(f32::NAN), Vec3::Y, 0.5).is_finite());
        assert_eq!(shadow_change(Vec3::Y, Vec3::Y, f32::NAN), Vec3::ZERO);
        assert_eq!(shadow_change(Vec3::Y, Vec3::Y, f32::INFINITY), Vec3::ZERO);
        assert_eq!(shadow_change(Vec3::Y, Vec3::Y, -1.0), Vec3::ZERO);
    }
}
