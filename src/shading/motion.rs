//! Bending beyond the thesis's wind (shading stage): gravity, the damped spring response of the fur
//! to the object's own motion along a path, and combing, all as one *lean*: a world-space vector
//! whose part tangent to the surface is the sine of the bend angle.
//!
//! The lean moves a shell layer like the wind of thesis 3.3 moves it (sideways by the lean times
//! the layer's height, pulled back along −normal so the strand keeps its length), and the
//! fragment stage reads the texel that lands there ([`super::wind_uv_offset`]) and bends the
//! tangent towards the lean ([`super::bend_tangent`]). When a scene has wind and a lean, the
//! wind's bend `ŵ·force` is added to the lean and the sum moves the layer.
//!
//! Time-addressable: the spring's state at `t` is a closed-form sum over the path's keyframes
//! (superposed impulse responses), never integrated frame by frame, so frame `k` of an
//! animation equals a render at `k/fps`.

use super::numeric::{finite_or_zero, saturate};
use core::f32::consts::TAU;
use glam::Vec3;

/// The lean of gravity: `ĝ·strength`. Where the fur stands at right angles to gravity its
/// tangent part is `strength`; where the fur points along gravity (or against it) it is 0.
/// A zero or non-finite direction gives zero; `strength` is saturated to `[0, 1]`.
#[inline]
pub fn gravity_lean(direction: Vec3, strength: f32) -> Vec3 {
    direction.normalize_or_zero() * saturate(strength)
}

/// The object's offset at `time` on a keyframed path `[t, x, y, z]` (times increasing): linear
/// between keyframes, the first keyframe's offset before it, the last one's after it. An empty
/// path gives zero.
pub fn path_position(path: &[[f32; 4]], time: f32) -> Vec3 {
    let at = |k: &[f32; 4]| Vec3::new(k[1], k[2], k[3]);
    let (Some(first), Some(last)) = (path.first(), path.last()) else {
        return Vec3::ZERO;
    };
    if time.is_nan() || time <= first[0] {
        return at(first);
    }
    if time >= last[0] {
        return at(last);
    }
    // The segment [k, k + 1] holding `time`: keyframe times increase, so the first keyframe
    // after `time` ends it.
    let next = path.partition_point(|k| k[0] <= time).min(path.len() - 1);
    let (a, b) = (&path[next - 1], &path[next]);
    let s = (time - a[0]) / (b[0] - a[0]);
    at(a) + (at(b) - at(a)) * s
}

/// The spring's unit impulse response: the displacement `τ` seconds after the root's velocity
/// changed by one unit, `g(τ) = −exp(−ζωτ)·sin(ω_d·τ)/ω_d` with `ω = 2π·frequency` and
/// `ω_d = ω·sqrt(1 − ζ²)` (the tip lags opposite to the change, swings back past rest and
/// settles); 0 for `τ ≤ 0`. `damping` ζ is clamped to `[0.01, 0.99]`, `frequency` to at least
/// 0.01 Hz. Uses `libm` `expf` and `sinf`.
#[inline]
pub fn spring_impulse_response(tau: f32, frequency: f32, damping: f32) -> f32 {
    if !tau.is_finite() || tau <= 0.0 {
        return 0.0;
    }
    let zeta = finite_or_zero(damping).clamp(0.01, 0.99);
    let omega = TAU * finite_or_zero(frequency).max(0.01);
    let omega_d = omega * (1.0 - zeta * zeta).sqrt();
    -libm::expf(-zeta * omega * tau) * libm::sinf(omega_d * tau) / omega_d
}

/// How far the fur tips lag behind their roots at `time` (world units) while the object follows
/// `path`: the solution of `x'' + 2ζωx' + ω²x = −a(t)` from rest, where `a` is the path's
/// acceleration. A piecewise-linear path accelerates only at its keyframes, by the change of
/// velocity `Δv_k` there (the object starts from rest and stops at the last keyframe), so
/// `x(t) = Σ_k Δv_k·g(t − t_k)` over the keyframes in order ([`spring_impulse_response`]).
pub fn spring_lag(path: &[[f32; 4]], time: f32, frequency: f32, damping: f32) -> Vec3 {
    let at = |k: &[f32; 4]| Vec3::new(k[1], k[2], k[3]);
    let velocity = |j: usize| -> Vec3 {
        match (path.get(j), path.get(j + 1)) {
            (Some(a), Some(b)) if b[0] > a[0] => (at(b) - at(a)) / (b[0] - a[0]),
            _ => Vec3::ZERO,
        }
    };
    let mut lag = Vec3::ZERO;
    let mut before = Vec3::ZERO;
    for (k, key) in path.iter().enumerate() {
        if time.is_nan() || key[0] >= time {
            break;
        }
        let after = velocity(k);
        let change = after - before;
        lag += change * spring_impulse_response(time - key[0], frequency, damping);
        before = after;
    }
    lag
}

/// Vertex-stage displacement of a shell vertex by a lean: with `n̂` the normalised normal,
/// `h = shell_fraction·strand_height` and `b = lean − (lean·n̂)n̂` the lean's part tangent to the
/// surface, shortened to length 1 when longer (a strand cannot lean past the surface):
/// offset `o = b·h`, pull along −normal `h − sqrt(h² − |o|²)` so the layer stays at distance
/// `h` from its root, as [`super::wind_displacement`] does. Returns `o − pull·n̂`.
/// `shell_fraction` is saturated, `strand_height` made finite and non-negative; a non-finite
/// lean gives zero.
#[inline]
pub fn lean_displacement(
    lean: Vec3,
    normal: Vec3,
    shell_fraction: f32,
    strand_height: f32,
) -> Vec3 {
    if !lean.is_finite() {
        return Vec3::ZERO;
    }
    let n = normal.normalize_or_zero();
    let across = lean - n * lean.dot(n);
    let length = across.length();
    let across = if length > 1.0 {
        across / length
    } else {
        across
    };
    let h = saturate(shell_fraction) * finite_or_zero(strand_height).max(0.0);
    let offset = across * h;
    let pull = h - (h * h - offset.length_squared()).max(0.0).sqrt();
    offset - n * pull
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};
    use glam::DVec3;

    fn response64(tau: f64, f: f64, zeta: f64) -> f64 {
        if tau <= 0.0 {
            return 0.0;
        }
        let w = std::f64::consts::TAU * f;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        -(-zeta * w * tau).exp() * (wd * tau).sin() / wd
    }

    #[test]
    fn impulse_response_matches_f64_and_solves_the_spring() {
        // Bound: f32 rounding of ω·τ (≤ 1.2e-7 relative) times the slope 1 of sin, over ω_d.
        let mut rng = Lcg::new(91);
        for _ in 0..2000 {
            let (f, z, tau) = (
                rng.range(0.1, 5.0),
                rng.range(0.02, 0.9),
                rng.range(0.0, 6.0),
            );
            let got = spring_impulse_response(tau, f, z);
            let w = std::f64::consts::TAU * f64::from(f);
            let tol = 1e-6 + 4e-7 * (1.0 + w * f64::from(tau)) / w;
            assert_close(
                got,
                response64(f64::from(tau), f64::from(f), f64::from(z)),
                tol,
                "g",
            );
        }
        // g solves g'' + 2ζωg' + ω²g = 0 with g(0) = 0, g'(0) = −1 (finite differences in f64).
        let (f, z) = (1.5f64, 0.2f64);
        let w = std::f64::consts::TAU * f;
        let d = 1e-4;
        for k in 1..50 {
            let t = k as f64 * 0.05;
            let g = |t| response64(t, f, z);
            let g1 = (g(t + d) - g(t - d)) / (2.0 * d);
            let g2 = (g(t + d) - 2.0 * g(t) + g(t - d)) / (d * d);
            assert!(
                (g2 + 2.0 * z * w * g1 + w * w * g(t)).abs() < 1e-3,
                "ODE at {t}"
            );
        }
        assert!(((response64(d, f, z) - response64(0.0, f, z)) / d + 1.0).abs() < 1e-3);
        assert_eq!(spring_impulse_response(0.0, 1.0, 0.2), 0.0);
        assert_eq!(spring_impulse_response(-1.0, 1.0, 0.2), 0.0);
        assert_eq!(spring_impulse_response(f32::NAN, 1.0, 0.2), 0.0);
    }

    #[test]
    fn path_is_linear_between_keyframes_and_held_outside() {
        let path = [
            [0.0, 0.0, 0.0, 0.0],
            [1.0, 2.0, 0.0, 0.0],
            [3.0, 2.0, 4.0, 0.0],
        ];
        assert_eq!(path_position(&path, -5.0), Vec3::ZERO);
        assert_eq!(path_position(&path, 0.5), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(path_position(&path, 1.0), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(path_position(&path, 2.0), Vec3::new(2.0, 2.0, 0.0));
        assert_eq!(path_position(&path, 9.0), Vec3::new(2.0, 4.0, 0.0));
        assert_eq!(path_position(&[], 1.0), Vec3::ZERO);
        assert_eq!(path_position(&path, f32::NAN), Vec3::ZERO);
    }

    #[test]
    fn spring_lag_superposes_the_keyframe_impulses() {
        // Start moving at 2 units/s along x at t = 1, stop at t = 2: impulses +2 at 1, −2 at 2.
        let path = [[1.0, 0.0, 0.0, 0.0], [2.0, 2.0, 0.0, 0.0]];
        let (f, z) = (1.5, 0.2);
        for k in 0..80 {
            let t = k as f32 * 0.05;
            let expected = 2.0 * response64(f64::from(t) - 1.0, f, z)
                - 2.0 * response64(f64::from(t) - 2.0, f, z);
            let got = spring_lag(&path, t, f as f32, z as f32);
            assert_close(got.x, expected, 2e-6, "lag x");
            assert_eq!((got.y, got.z), (0.0, 0.0));
        }
        // At rest before the motion starts; lags behind (−x) just after it starts.
        assert_eq!(spring_lag(&path, 0.5, 1.5, 0.2), Vec3::ZERO);
        assert!(spring_lag(&path, 1.1, 1.5, 0.2).x < 0.0);
        // Long after the stop the fur is back at rest.
        assert!(spring_lag(&path, 30.0, 1.5, 0.2).length() < 1e-6);
    }

    #[test]
    fn lean_displacement_keeps_strand_length_and_matches_f64() {
        let mut rng = Lcg::new(17);
        for _ in 0..3000 {
            let lean = rng.cube() * rng.range(0.0, 1.5);
            let normal = rng.direction();
            let (s, h) = (rng.unit(), rng.range(0.0, 3.0));
            let got = lean_displacement(lean, normal, s, h);
            let (l, n) = (lean.as_dvec3(), normal.as_dvec3().normalize());
            let mut b = l - n * l.dot(n);
            if b.length() > 1.0 {
                b /= b.length();
            }
            let hh = f64::from(s) * f64::from(h);
            let o = b * hh;
            let pull = hh - (hh * hh - o.length_squared()).max(0.0).sqrt();
            let expected: DVec3 = o - n * pull;
            // Bound: 2e-6 relative to h, plus the pull's cancellation near a full bend (the
            // square root of a difference of nearly equal squares).
            let near_full = if b.length() > 0.999 { 2e-3 * hh } else { 0.0 };
            let tol = 2e-6 * (1.0 + hh) + near_full;
            assert!(
                (got.as_dvec3() - expected).length() <= tol,
                "{got} vs {expected}"
            );
            // The layer stays at its height from the root (the strand keeps its length).
            let moved = (got.as_dvec3() + n * hh).length();
            assert!((moved - hh).abs() <= 1e-5 * (1.0 + hh) + near_full);
        }
        assert_eq!(lean_displacement(Vec3::NAN, Vec3::Z, 1.0, 1.0), Vec3::ZERO);
        // A lean along the normal moves nothing.
        assert_eq!(
            lean_displacement(Vec3::Z * 0.5, Vec3::Z, 1.0, 1.0),
            Vec3::ZERO
        );
    }

    #[test]
    fn gravity_lean_is_direction_times_saturated_strength() {
        assert_eq!(
            gravity_lean(Vec3::new(0.0, -2.0, 0.0), 0.4),
            Vec3::new(0.0, -0.4, 0.0)
        );
        assert_eq!(gravity_lean(Vec3::ZERO, 0.4), Vec3::ZERO);
        assert_eq!(gravity_lean(Vec3::X, 3.0), Vec3::X);
        assert_eq!(gravity_lean(Vec3::X, f32::NAN), Vec3::ZERO);
    }
}
