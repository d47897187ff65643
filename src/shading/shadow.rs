//! Shell self-shadow (thesis 3.2.2, after Papaioannou): from a texel, step towards the light
//! inside the current shell texture, and count how opaque the texels met are. The number of
//! steps shrinks from root to tip (`m = (N − i)/n`, the "height/n" of table 4.4).

use super::numeric::{finite_or_zero, saturate, saturate_x4};
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

/// Shell self-shadow value (thesis 3.2.2): for `k` in `1..=m` sample the current shell's alpha
/// at `uv + shadow_lookup·(k/m)` and add it; the result is in `[0, m]`.
///
/// The thesis's rule is binary (a transparent texel adds nothing, an opaque one adds to
/// `shadowValue`); adding the sampled alpha is its continuous form, which agrees on alpha 0
/// and 1 and does not alias on filtered (bilinear, mipmapped) alpha. Samples are saturated to
/// `[0, 1]` (NaN counts as 0) and summed in order `k = 1, 2, …, m`. `m = 0` gives 0 without
/// sampling. A non-finite `uv` or `shadow_lookup` component is treated as 0.
#[inline]
pub fn shell_shadow(
    mut sample_alpha: impl FnMut(Vec2) -> f32,
    uv: Vec2,
    shadow_lookup: Vec2,
    lookups: u32,
) -> f32 {
    let path = LookupPath::new(uv, shadow_lookup, lookups);
    let mut shadow = 0.0;
    for k in 1..=lookups {
        shadow += saturate(sample_alpha(path.point(k)));
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
/// order, so the same bits. Lanes past the last lookup repeat it and add +0 (no change).
#[inline]
pub fn shell_shadow_x4(
    mut sample_alpha_x4: impl FnMut([f32; 4], [f32; 4]) -> [f32; 4],
    uv: Vec2,
    shadow_lookup: Vec2,
    lookups: u32,
) -> f32 {
    let path = LookupPath::new(uv, shadow_lookup, lookups);
    let mut shadow = 0.0;
    for first in (1..=lookups).step_by(4) {
        let k = [0, 1, 2, 3].map(|i| first.saturating_add(i).min(lookups));
        let (u, v) = path.points_x4(k);
        // Surplus lanes are multiplied by 0 and add +0, which leaves the sum's bits alone: it
        // starts at +0 and every saturated alpha is +0 or in (0, 1]. No branch on the count or
        // on the alphas.
        let counted = [0, 1, 2, 3].map(|i| f32::from(u8::from(first.saturating_add(i) <= lookups)));
        let alphas = saturate_x4(f32x4::new(sample_alpha_x4(u, v))) * f32x4::new(counted);
        for alpha in alphas.to_array() {
            shadow += alpha;
        }
    }
    shadow
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
            );
            assert_eq!(
                batched.to_bits(),
                shell_shadow(alpha, uv, offset, lookups).to_bits(),
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
            assert_eq!(
                shell_shadow_x4(
                    |u, v| std::array::from_fn(|i| alpha(Vec2::new(u[i], v[i]))),
                    uv,
                    Vec2::X,
                    5
                )
                .to_bits(),
                shell_shadow(alpha, uv, Vec2::X, 5).to_bits()
            );
        }
    }

    #[test]
    fn shadow_adds_alpha_and_handles_edges() {
        // Transparent texels add nothing, opaque ones 1, partial ones their alpha.
        assert_eq!(shell_shadow(|_| 0.0, Vec2::ZERO, Vec2::X, 6), 0.0);
        assert_eq!(
            shell_shadow(
                |p| if p.x > 0.5 { 1.0 } else { 0.0 },
                Vec2::ZERO,
                Vec2::X,
                4
            ),
            2.0
        );
        assert_eq!(shell_shadow(|_| 0.25, Vec2::ZERO, Vec2::X, 4), 1.0);
        // Out-of-range and NaN samples are saturated.
        assert_eq!(shell_shadow(|_| f32::NAN, Vec2::ZERO, Vec2::X, 4), 0.0);
        assert_eq!(shell_shadow(|_| 7.0, Vec2::ZERO, Vec2::X, 4), 4.0);
        // No lookups: the sampler is never called.
        assert_eq!(
            shell_shadow(|_| unreachable!(), Vec2::ZERO, Vec2::X, 0),
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
        );
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
