//! Wind (thesis 3.3; shading stage): a time-varying directional force (a push plus an elastic
//! return, so the strands sway back and forth, bend limited); the vertex-stage displacement of a
//! shell (along the wind's surface-tangent part, scaled by the layer, pulled back along −normal so
//! the strand keeps its length); the fragment-stage reverse lookup offset and the bent tangent.

use super::lanes::Vec3xN;
use super::numeric::{finite_or_zero, saturate};
use super::projection::{Axis, project_to_uv_dropping};
use core::f32::consts::TAU;
use glam::{Vec2, Vec3};

/// Parameters of the directional wind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindParams {
    /// Direction the wind blows towards (world space; normalised where used).
    pub direction: Vec3,
    /// Strength of the push: the bend (sine of the bend angle) a gust would give without the
    /// limit.
    pub strength: f32,
    /// Gusts per second.
    pub frequency: f32,
    /// Damping rate of the elastic return per gust cycle: higher is stiffer, the vibration dies
    /// out sooner.
    pub elasticity: f32,
    /// Largest bend, as the sine of the bend angle, in `[0, 1]` (clamped): the horizontal offset
    /// of a layer never exceeds `max_bend × its height`.
    pub max_bend: f32,
}

impl Default for WindParams {
    /// A moderate breeze along +x: strength 0.3, one gust every 2 s, elasticity 3, bend at
    /// most 0.5 (30°).
    fn default() -> Self {
        WindParams {
            direction: Vec3::X,
            strength: 0.3,
            frequency: 0.5,
            elasticity: 3.0,
            max_bend: 0.5,
        }
    }
}

/// Swings of the elastic return per gust cycle.
pub const VIBRATION_RATIO: f32 = 3.0;

/// The signed bend the wind gives at `time` (thesis 3.3: "two different forces acting upon a
/// single fur; one pushing it and the other producing the vibration. Furthermore, the force
/// that elasticity applies increases as the fur bends"), in `[−max_bend, max_bend]`.
///
/// With `c = frac(frequency·time)` the phase in the current gust cycle and `s = strength`:
/// - push: `s·(0.5 + 0.5·sin(2πc))`, gusts between 0 and `s`;
/// - elastic return: `−0.5·s·exp(−elasticity·c)·sin(2π·VIBRATION_RATIO·c)`, a damped
///   oscillation restarted each cycle (it is 0 at both ends of a cycle, so the sum is
///   continuous in time); it swings the strand back, past rest when the push is weak;
/// - the limit: `max_bend·tanh(raw/max_bend)`, a spring that stiffens as it bends; never above
///   `max_bend` in magnitude, nearly linear for small bends.
///
/// Non-finite `time`, `strength`, `frequency` or `elasticity` act as 0 (frequency and
/// elasticity by absolute value and clamp to ≥ 0 respectively); `max_bend` is clamped to
/// `[0, 1]` (NaN → 0, no wind). Uses `libm` (`sinf`, `expf`, `tanhf`, `floorf`).
#[inline]
pub fn wind_force(time: f32, params: &WindParams) -> f32 {
    let max_bend = saturate(params.max_bend);
    if max_bend == 0.0 {
        return 0.0;
    }
    let s = finite_or_zero(params.strength);
    let e = finite_or_zero(params.elasticity).max(0.0);
    let phase = finite_or_zero(params.frequency).abs() * finite_or_zero(time);
    let phase = finite_or_zero(phase);
    let c = phase - libm::floorf(phase);
    let push = s * (0.5 + 0.5 * libm::sinf(TAU * c));
    let spring = -0.5 * s * libm::expf(-e * c) * libm::sinf(TAU * VIBRATION_RATIO * c);
    max_bend * libm::tanhf((push + spring) / max_bend)
}

/// Vertex-stage displacement of a shell vertex (thesis 3.3): with `ŵ`, `n̂` the normalised wind
/// and normal, `h = shell_fraction·strand_height` the layer's height (`shell_fraction = i/N`),
/// and `bend = force` clamped to `[−1, 1]`:
///
/// - horizontal offset `o = bend·h·(ŵ − (ŵ·n̂)n̂)`: along the wind's part tangent to the
///   surface, whose length is `sin(ŵ, n̂)` (the thesis: "the dot product gives the cosine, we
///   want the sine"), so a wind along the normal moves nothing;
/// - pull along −normal `h − sqrt(h² − |o|²)`, so the layer stays at distance `h` from its root:
///   `|o + (h − pull)·n̂| = h` (the thesis: "move the textures in the direction of the negative
///   normal of the surface, so the length of the fur will seem same").
///
/// Returns `o − pull·n̂`. `|o| ≤ |force|·h`, so with `force` from [`wind_force`]
/// `|o| ≤ max_bend·h`. `shell_fraction` is clamped to `[0, 1]` (NaN → 0), `strand_height` to be
/// non-negative and finite (else 0), a non-finite `force` acts as 0. A zero normal counts the
/// whole wind as tangent (and pulls nowhere); a zero wind gives zero.
#[inline]
pub fn wind_displacement(
    wind_dir: Vec3,
    normal: Vec3,
    force: f32,
    shell_fraction: f32,
    strand_height: f32,
) -> Vec3 {
    let w = wind_dir.normalize_or_zero();
    let n = normal.normalize_or_zero();
    let across = w - n * w.dot(n);
    let h = saturate(shell_fraction) * finite_or_zero(strand_height).max(0.0);
    let bend = finite_or_zero(force).clamp(-1.0, 1.0);
    let offset = across * (bend * h);
    let pull = h - (h * h - offset.length_squared()).max(0.0).sqrt();
    offset - n * pull
}

/// The part of a layer's displacement that the vertex stage applies (thesis 3.3): only the pull
/// back along the normal, `n̂·(displacement·n̂)`. The sideways part moves the texture instead
/// ([`wind_uv_offset`], "we choose to animate in texture space"); moving the vertices sideways as
/// well would move every layer twice its displacement and stretch the strands.
///
/// A zero normal gives zero (nothing is pulled).
#[inline]
pub fn vertex_pull(displacement: Vec3, normal: Vec3) -> Vec3 {
    let n = normal.normalize_or_zero();
    n * displacement.dot(n)
}

/// Fragment-stage reverse lookup (thesis 3.3: "as we are looking at the current pixel we have to
/// know which pixel will be there"): the texture offset of the displacement's part tangent to the
/// surface; the texel that lands at `uv` is read at `uv − offset`.
///
/// Uses the axis-dropping projection of 3.2.2, dropping "the axis that we moved the most" along
/// the negative normal, i.e. the axis of the largest `|normal|` component (ties to the lowest
/// index). Never NaN (see [`project_to_uv_dropping`]).
#[inline]
pub fn wind_uv_offset(displacement: Vec3, normal: Vec3, dpdu: Vec3, dpdv: Vec3) -> Vec2 {
    let n = normal.normalize_or_zero();
    let horizontal = displacement - n * displacement.dot(n);
    project_to_uv_dropping(horizontal, dpdu, dpdv, Axis::greatest(n))
}

/// The strand tangent bent by the wind (thesis 3.3.1: "we update the tangent value by adding a
/// fraction of the wind vector and normalizing the value"): `normalize(t + fraction·w)`, with `w`
/// the wind in tangent space.
///
/// If the sum has no direction (zero, or non-finite) the normalised `tangent` is returned (zero
/// if that is degenerate too). A non-finite `fraction` acts as 0.
#[inline]
pub fn bend_tangent(tangent: Vec3, wind_tangent_space: Vec3, fraction: f32) -> Vec3 {
    (tangent + finite_or_zero(fraction) * wind_tangent_space)
        .normalize_or(tangent.normalize_or_zero())
}

/// [`bend_tangent`] on `N` lanes with one fraction, lane by lane the same bits.
#[inline(always)]
pub fn bend_tangent_lanes<const N: usize>(
    tangent: &Vec3xN<N>,
    wind_tangent_space: &Vec3xN<N>,
    fraction: f32,
) -> Vec3xN<N> {
    tangent
        .add_scaled([finite_or_zero(fraction); N], wind_tangent_space)
        .normalize_or(&tangent.normalize_or_zero())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};
    use glam::DVec3;

    fn force64(time: f64, p: &WindParams) -> f64 {
        let mb = f64::from(p.max_bend);
        let s = f64::from(p.strength);
        let phase = f64::from(p.frequency).abs() * time;
        let c = phase - phase.floor();
        let tau = std::f64::consts::TAU;
        let push = s * (0.5 + 0.5 * (tau * c).sin());
        let spring = -0.5 * s * (-f64::from(p.elasticity) * c).exp() * (tau * 3.0 * c).sin();
        mb * ((push + spring) / mb).tanh()
    }

    fn random_params(rng: &mut Lcg) -> WindParams {
        WindParams {
            direction: rng.direction(),
            strength: rng.range(0.0, 3.0),
            frequency: rng.range(0.1, 2.0),
            elasticity: rng.range(0.0, 6.0),
            max_bend: rng.range(0.05, 1.0),
        }
    }

    #[test]
    fn force_matches_f64_and_is_bounded() {
        // Bound: the phase f·t is rounded in f32 (|err| ≤ 6e-8·phase) before the slopes
        // 2π·(1 + VIBRATION_RATIO)·s of the sines; plus 1e-6 for libm's last-bit errors.
        let mut rng = Lcg::new(70);
        for _ in 0..3000 {
            let p = random_params(&mut rng);
            let t = rng.range(0.0, 20.0);
            let phase = f64::from(p.frequency) * f64::from(t);
            let slope = std::f64::consts::TAU * 4.0 * (1.0 + f64::from(p.strength));
            let tol = 1e-6 + 1.2e-7 * (1.0 + phase) * slope;
            let got = wind_force(t, &p);
            assert_close(got, force64(f64::from(t), &p), tol, "wind force");
            assert!(got.abs() <= p.max_bend, "{got} > {}", p.max_bend);
        }
    }

    #[test]
    fn force_sways_both_ways_and_is_continuous() {
        let p = WindParams {
            elasticity: 0.5,
            strength: 0.4,
            ..WindParams::default()
        };
        let samples: Vec<f32> = (0..400).map(|k| wind_force(k as f32 * 0.01, &p)).collect();
        let (lo, hi) = samples
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &f| (lo.min(f), hi.max(f)));
        assert!(lo < 0.0 && hi > 0.0, "sways both ways: [{lo}, {hi}]");
        for pair in samples.windows(2) {
            assert!((pair[1] - pair[0]).abs() < 0.05, "continuous: {pair:?}");
        }
        // Across the cycle wrap (t = 2 s for 0.5 Hz) the force is continuous too.
        let before = wind_force(f32::from_bits(2.0f32.to_bits() - 1), &p);
        assert!((before - wind_force(2.0, &p)).abs() < 1e-4);
    }

    #[test]
    fn force_degenerate_parameters() {
        let p = WindParams::default();
        for t in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30] {
            assert!(wind_force(t, &p).is_finite());
        }
        let still = WindParams { max_bend: 0.0, ..p };
        assert_eq!(wind_force(1.0, &still), 0.0);
        let nan = WindParams {
            strength: f32::NAN,
            frequency: f32::NAN,
            elasticity: f32::NAN,
            max_bend: f32::NAN,
            direction: Vec3::splat(f32::NAN),
        };
        assert_eq!(wind_force(1.0, &nan), 0.0);
        let huge = WindParams {
            strength: f32::MAX,
            max_bend: 5.0,
            ..p
        };
        let f = wind_force(0.3, &huge);
        assert!(f.is_finite() && f.abs() <= 1.0);
    }

    fn displacement64(w: Vec3, n: Vec3, force: f32, fraction: f32, height: f32) -> DVec3 {
        let (w, n) = (w.as_dvec3().normalize(), n.as_dvec3().normalize());
        let h = f64::from(fraction) * f64::from(height);
        let o = (w - n * w.dot(n)) * f64::from(force) * h;
        let pull = h - (h * h - o.length_squared()).max(0.0).sqrt();
        o - n * pull
    }

    #[test]
    fn displacement_matches_f64_keeps_length_and_bend_bound() {
        let mut rng = Lcg::new(71);
        for _ in 0..3000 {
            let p = random_params(&mut rng);
            let n = rng.direction();
            let force = wind_force(rng.range(0.0, 10.0), &p);
            let fraction = rng.unit();
            let height = rng.range(0.1, 2.0);
            let got = wind_displacement(p.direction, n, force, fraction, height);
            let expected = displacement64(p.direction, n, force, fraction, height);
            let h = f64::from(fraction) * f64::from(height);
            for k in 0..3 {
                // The pull's square root is ill-conditioned at full bend: 1e-3·h there.
                assert_close(got[k], expected[k], 1e-6 + 1e-3 * h, "displacement");
            }
            // Length kept: |d + h·n| = h.
            let tip = got.as_dvec3() + n.as_dvec3() * h;
            assert!((tip.length() - h).abs() <= 1e-5 * (1.0 + h), "length kept");
            // Horizontal bound: |o| ≤ max_bend·h.
            let nd = n.as_dvec3();
            let horizontal = got.as_dvec3() - nd * got.as_dvec3().dot(nd);
            let bound = f64::from(p.max_bend) * h;
            assert!(
                horizontal.length() <= bound * (1.0 + 1e-5) + 1e-7,
                "{} > {bound}",
                horizontal.length()
            );
        }
    }

    #[test]
    fn displacement_edge_cases() {
        // Wind along the normal: nothing moves.
        assert_eq!(
            wind_displacement(Vec3::Y, Vec3::Y, 0.5, 1.0, 1.0),
            Vec3::ZERO
        );
        // Wind across the normal at full bend: offset h, pulled down by h.
        assert_eq!(
            wind_displacement(Vec3::X, Vec3::Y, 1.0, 0.5, 2.0),
            Vec3::new(1.0, -1.0, 0.0)
        );
        // The root layer never moves.
        assert_eq!(
            wind_displacement(Vec3::X, Vec3::Y, 0.5, 0.0, 2.0),
            Vec3::ZERO
        );
        // Negative force swings the other way.
        let back = wind_displacement(Vec3::X, Vec3::Y, -0.5, 1.0, 1.0);
        assert!(back.x < 0.0 && back.y <= 0.0);
        // Degenerate inputs stay finite.
        let nan = Vec3::splat(f32::NAN);
        assert_eq!(wind_displacement(nan, Vec3::Y, 0.5, 1.0, 1.0), Vec3::ZERO);
        assert_eq!(
            wind_displacement(Vec3::ZERO, Vec3::Y, 0.5, 1.0, 1.0),
            Vec3::ZERO
        );
        assert!(wind_displacement(Vec3::X, nan, 0.5, 1.0, 1.0).is_finite());
        assert!(wind_displacement(Vec3::X, Vec3::Y, f32::NAN, f32::NAN, f32::NAN).is_finite());
        assert!(wind_displacement(Vec3::X, Vec3::Y, 9.0, 9.0, f32::INFINITY).is_finite());
    }

    #[test]
    fn uv_offset_drops_the_normal_axis() {
        // Flat patch, normal +z, u along x (×2), v along y (×0.5).
        let (du, dv) = (Vec3::X * 2.0, Vec3::Y * 0.5);
        let d = Vec3::new(0.2, 0.1, -0.05);
        let off = wind_uv_offset(d, Vec3::Z, du, dv);
        assert_close(off.x, 0.1, 1e-7, "u offset");
        assert_close(off.y, 0.2, 1e-7, "v offset");
        // Tilted surface: the in-plane part of a random displacement is recovered.
        let mut rng = Lcg::new(72);
        for _ in 0..500 {
            let (du, dv) = (rng.cube(), rng.cube());
            let n = du.cross(dv);
            if n.length() < 0.2 * du.length() * dv.length() {
                continue;
            }
            let (a, b) = (rng.range(-0.3, 0.3), rng.range(-0.3, 0.3));
            let d = du * a + dv * b + n.normalize() * rng.range(-0.2, 0.0);
            let off = wind_uv_offset(d, n, du, dv);
            assert_close(off.x, f64::from(a), 1e-4, "a");
            assert_close(off.y, f64::from(b), 1e-4, "b");
        }
        assert_eq!(
            wind_uv_offset(Vec3::splat(f32::NAN), Vec3::Z, du, dv),
            Vec2::ZERO
        );
    }

    #[test]
    fn bend_tangent_lanes_are_single_bends_bit_for_bit() {
        bends_bit_for_bit::<4>();
        bends_bit_for_bit::<8>();
    }

    fn bends_bit_for_bit<const N: usize>() {
        let mut rng = Lcg::new(43);
        for k in 0..3000 {
            let t = crate::shading::lanes::tests::lanes_n::<N>(&mut rng, k);
            let w = crate::shading::lanes::tests::lanes_n::<N>(&mut rng, k + 4);
            let fraction = [rng.range(0.0, 1.0), 0.0, f32::NAN, -3.0][k % 4];
            let bent = bend_tangent_lanes(&Vec3xN::from_lanes(t), &Vec3xN::from_lanes(w), fraction);
            for i in 0..N {
                assert_eq!(
                    bent.lane(i).to_array().map(f32::to_bits),
                    bend_tangent(t[i], w[i], fraction)
                        .to_array()
                        .map(f32::to_bits),
                    "{:?} {:?} {fraction}",
                    t[i],
                    w[i]
                );
            }
        }
    }

    #[test]
    fn bend_tangent_matches_f64() {
        let mut rng = Lcg::new(73);
        for _ in 0..1000 {
            let (t, w, f) = (rng.direction(), rng.cube(), rng.unit());
            let sum = t.as_dvec3() + f64::from(f) * w.as_dvec3();
            if sum.length() < 1e-2 {
                continue;
            }
            let expected = sum.normalize();
            let got = bend_tangent(t, w, f);
            for k in 0..3 {
                assert_close(got[k], expected[k], 1e-6 / sum.length(), "bent tangent");
            }
        }
        assert_eq!(bend_tangent(Vec3::X, -Vec3::X, 1.0), Vec3::X);
        assert_eq!(bend_tangent(Vec3::X * 2.0, Vec3::Y, 0.0), Vec3::X);
        assert_eq!(bend_tangent(Vec3::X, Vec3::splat(f32::NAN), 0.5), Vec3::X);
        assert_eq!(bend_tangent(Vec3::X, Vec3::Y, f32::NAN), Vec3::X);
        assert_eq!(bend_tangent(Vec3::ZERO, Vec3::ZERO, 1.0), Vec3::ZERO);
    }

    #[test]
    fn vertex_pull_and_uv_offset_split_the_displacement_once() {
        // The vertex stage's pull and the texture's sideways part add up to the displacement,
        // and the pull keeps the strand's length: |sideways + (h − pull)·n̂| = h (f64 check).
        let mut rng = Lcg::new(71);
        for _ in 0..2000 {
            let n = rng.direction();
            let w = rng.direction();
            let h = rng.range(0.01, 2.0);
            let force = rng.range(-1.0, 1.0);
            let d = wind_displacement(w, n, force, 1.0, h);
            let pull = vertex_pull(d, n);
            let sideways = d - pull;
            let (n64, side64, pull64) = (n.as_dvec3(), sideways.as_dvec3(), pull.as_dvec3());
            assert!(
                side64.dot(n64).abs() < 1e-5,
                "sideways part has no normal part"
            );
            assert!(
                pull64.cross(n64).length() < 1e-5,
                "the pull is along the normal"
            );
            let tip = side64 + n64 * f64::from(h) + pull64;
            assert_close(
                tip.length() as f32,
                f64::from(h),
                1e-5 * (1.0 + f64::from(h)),
                "strand length kept",
            );
        }
        assert_eq!(vertex_pull(Vec3::ONE, Vec3::ZERO), Vec3::ZERO);
    }
}
