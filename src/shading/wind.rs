//! Wind (thesis 3.3; shading stage): a time-varying directional force (a push plus an elastic
//! return, so the strands sway back and forth, bend limited); the vertex-stage displacement of a
//! shell (along the wind's surface-tangent part, scaled by the layer, pulled back along −normal so
//! the strand keeps its length); the fragment-stage reverse lookup offset and the bent tangent.

use super::lanes::Vec3xN;
use super::numeric::{finite_or_zero, saturate};
use super::projection::{Axis, project_to_uv_dropping};
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

/// The strands' natural frequency in swings per gust cycle: the spring's undamped angular
/// frequency is `ω = 2π·VIBRATION_RATIO·frequency`.
pub const VIBRATION_RATIO: f32 = 3.0;

/// The part of each gust cycle the wind pushes (the rest of the cycle it is still).
pub const PUSH_FRACTION: f64 = 0.5;

/// The smallest damping ratio ζ of the spring: `elasticity` below `2π·VIBRATION_RATIO·0.02`
/// acts as that, so that an undamped spring (elasticity 0) driven at a whole number of its own
/// swings per cycle still has one steady motion.
pub const MIN_DAMPING_RATIO: f64 = 0.02;

/// The signed bend the wind gives at `time` (thesis 3.3: "two different forces acting upon a
/// single fur; one pushing it and the other producing the vibration. Furthermore, the force
/// that elasticity applies increases as the fur bends"), in `[−max_bend, max_bend]`: the
/// displacement `x` of a damped spring driven by gusts, then limited.
///
/// - The spring: `x″ + 2ζω·x′ + ω²·x = ω²·F(t)`, the return force growing with the bend (Hooke),
///   with `ω = 2π·VIBRATION_RATIO·frequency` and `ζ = max(elasticity / (2π·VIBRATION_RATIO),
///   MIN_DAMPING_RATIO)` (so `elasticity` is the decay rate of a swing per gust cycle, as
///   `exp(−elasticity·cycles)`; above `6π` the return is overdamped and creeps back).
/// - The gust: `F = strength` for the first [`PUSH_FRACTION`] of each cycle of length
///   `1/frequency`, 0 for the rest. Under the push the strand bends past `strength` and rings;
///   when the push drops it swings back past rest (the vibration) and settles.
/// - Time-addressable: `x(t)` is the motion the gusts repeat for ever (the periodic solution,
///   in closed form: the spring's state at the start of a cycle is the fixed point of one cycle's
///   linear map), so `--time t` alone gives the frame, and position and velocity are
///   continuous at every time, cycle boundaries included (the velocity has no jump; only the
///   acceleration steps where the push starts and stops).
/// - The limit: `max_bend·tanh(x/max_bend)`, a spring that stiffens as it bends; never above
///   `max_bend` in magnitude, nearly linear for small bends, smooth (so still continuous in
///   position and velocity).
///
/// `frequency` 0 is a steady wind: `x = strength`. Computed in f64 (once per frame, the same
/// value for the CPU and the GPU, whose shader receives it as a uniform) with `libm`; non-finite
/// `time`, `strength`, `frequency` or `elasticity` act as 0 (frequency by absolute value,
/// elasticity clamped to ≥ 0); `max_bend` is clamped to `[0, 1]` (NaN → 0, no wind).
pub fn wind_force(time: f32, params: &WindParams) -> f32 {
    let max_bend = saturate(params.max_bend);
    if max_bend == 0.0 {
        return 0.0;
    }
    let strength = f64::from(finite_or_zero(params.strength));
    let frequency = f64::from(finite_or_zero(params.frequency).abs());
    let elasticity = f64::from(finite_or_zero(params.elasticity).max(0.0));
    let x = gust_spring(
        f64::from(finite_or_zero(time)),
        strength,
        frequency,
        elasticity,
    );
    let limit = f64::from(max_bend);
    (limit * libm::tanh(x / limit)) as f32
}

/// The spring's displacement `x(t)` of [`wind_force`] before the limit, f64.
fn gust_spring(time: f64, strength: f64, frequency: f64, elasticity: f64) -> f64 {
    let phase = frequency * time;
    if frequency == 0.0 || !phase.is_finite() {
        return strength;
    }
    let period = 1.0 / frequency;
    let omega = core::f64::consts::TAU * f64::from(VIBRATION_RATIO) * frequency;
    let zeta =
        (elasticity / (core::f64::consts::TAU * f64::from(VIBRATION_RATIO))).max(MIN_DAMPING_RATIO);
    let push = SpringStep::new(omega, zeta, PUSH_FRACTION * period);
    let rest = SpringStep::new(omega, zeta, (1.0 - PUSH_FRACTION) * period);
    // The state (x, v) at the start of a cycle, z₀, is the fixed point of one cycle:
    // z₀ = R·(P·(z₀ − s) + s), s = (strength, 0): (I − R·P)·z₀ = R·(I − P)·s.
    let rp = rest.matrix.mul(&push.matrix);
    let i_minus_p = Mat2::IDENTITY.sub(&push.matrix);
    let rhs = rest.matrix.apply(i_minus_p.apply([strength, 0.0]));
    let start = Mat2::IDENTITY.sub(&rp).solve(rhs);
    let c = (phase - libm::floor(phase)) * period;
    let push_time = PUSH_FRACTION * period;
    if c < push_time {
        let y = SpringStep::new(omega, zeta, c)
            .matrix
            .apply([start[0] - strength, start[1]]);
        y[0] + strength
    } else {
        let at_drop = push.matrix.apply([start[0] - strength, start[1]]);
        let at_drop = [at_drop[0] + strength, at_drop[1]];
        SpringStep::new(omega, zeta, c - push_time)
            .matrix
            .apply(at_drop)[0]
    }
}

/// A 2×2 matrix, rows first.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Mat2([[f64; 2]; 2]);

impl Mat2 {
    const IDENTITY: Mat2 = Mat2([[1.0, 0.0], [0.0, 1.0]]);

    fn mul(&self, o: &Mat2) -> Mat2 {
        let (a, b) = (self.0, o.0);
        Mat2([
            [
                a[0][0] * b[0][0] + a[0][1] * b[1][0],
                a[0][0] * b[0][1] + a[0][1] * b[1][1],
            ],
            [
                a[1][0] * b[0][0] + a[1][1] * b[1][0],
                a[1][0] * b[0][1] + a[1][1] * b[1][1],
            ],
        ])
    }

    fn sub(&self, o: &Mat2) -> Mat2 {
        let (a, b) = (self.0, o.0);
        Mat2([
            [a[0][0] - b[0][0], a[0][1] - b[0][1]],
            [a[1][0] - b[1][0], a[1][1] - b[1][1]],
        ])
    }

    fn apply(&self, v: [f64; 2]) -> [f64; 2] {
        let a = self.0;
        [
            a[0][0] * v[0] + a[0][1] * v[1],
            a[1][0] * v[0] + a[1][1] * v[1],
        ]
    }

    /// `M⁻¹·v` by Cramer's rule (the cycle map of a damped spring is never singular: its
    /// eigenvalues lie inside the unit circle).
    fn solve(&self, v: [f64; 2]) -> [f64; 2] {
        let a = self.0;
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        [
            (v[0] * a[1][1] - a[0][1] * v[1]) / det,
            (a[0][0] * v[1] - v[0] * a[1][0]) / det,
        ]
    }
}

/// The free spring's state map over a time `tau`: `(y, v) ↦ exp(A·tau)·(y, v)` with
/// `A = [[0, 1], [−ω², −2ζω]]`, written as `e^{μτ}·(C·I + S·(A − μI))`, `μ = −ζω`,
/// `q² = ω²(ζ² − 1)`: `C = cos, S = sin(·)/ω_d` when underdamped, `cosh, sinh(·)/q` when not
/// (as sums of decaying exponentials, which cannot overflow), `1, τ` at critical damping.
struct SpringStep {
    matrix: Mat2,
}

impl SpringStep {
    fn new(omega: f64, zeta: f64, tau: f64) -> SpringStep {
        let mu = -zeta * omega;
        let q2 = omega * omega * (zeta * zeta - 1.0);
        let (c, s) = if q2 < 0.0 {
            let wd = libm::sqrt(-q2);
            let decay = libm::exp(mu * tau);
            (
                decay * libm::cos(wd * tau),
                decay * libm::sin(wd * tau) / wd,
            )
        } else {
            let q = libm::sqrt(q2);
            let fast = libm::exp((mu - q) * tau);
            let slow = libm::exp((mu + q) * tau);
            let s = if q * tau < 1e-6 {
                libm::exp(mu * tau) * tau
            } else {
                0.5 * (slow - fast) / q
            };
            (0.5 * (slow + fast), s)
        };
        let zw = zeta * omega;
        SpringStep {
            matrix: Mat2([[c + s * zw, s], [-omega * omega * s, c - s * zw]]),
        }
    }
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
        .normalize_or_else(|| tangent.normalize_or_zero())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};
    use glam::DVec3;

    /// The spring of [`wind_force`] integrated from rest by classic Runge–Kutta (f64, 4000
    /// steps a cycle) for `cycles` cycles and then to `time`'s phase: an independent account of
    /// the periodic motion, which the damping makes the start forgotten.
    fn force64(time: f64, p: &WindParams, cycles: usize) -> f64 {
        let f = f64::from(p.frequency);
        let s = f64::from(p.strength);
        let omega = std::f64::consts::TAU * 3.0 * f;
        let zeta = (f64::from(p.elasticity) / (std::f64::consts::TAU * 3.0)).max(0.02);
        let period = 1.0 / f;
        // Classic RK4 over a span of constant drive `d`, 2000 steps a half cycle.
        let run = |(mut x, mut v): (f64, f64), d: f64, span: f64| {
            let steps = ((span / period * 4000.0).ceil() as usize).max(1);
            let h = span / steps as f64;
            let a = |x: f64, v: f64| omega * omega * (d - x) - 2.0 * zeta * omega * v;
            for _ in 0..steps {
                let (k1x, k1v) = (v, a(x, v));
                let (k2x, k2v) = (v + 0.5 * h * k1v, a(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
                let (k3x, k3v) = (v + 0.5 * h * k2v, a(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
                let (k4x, k4v) = (v + h * k3v, a(x + h * k3x, v + h * k3v));
                x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
                v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            }
            (x, v)
        };
        let mut state = (0.0, 0.0);
        for _ in 0..cycles {
            state = run(state, s, 0.5 * period);
            state = run(state, 0.0, 0.5 * period);
        }
        let into = (time * f).fract() * period;
        let (x, _) = if into < 0.5 * period {
            run(state, s, into)
        } else {
            run(run(state, s, 0.5 * period), 0.0, into - 0.5 * period)
        };
        let mb = f64::from(p.max_bend);
        mb * (x / mb).tanh()
    }

    fn random_params(rng: &mut Lcg) -> WindParams {
        WindParams {
            direction: rng.direction(),
            strength: rng.range(0.0, 3.0),
            frequency: rng.range(0.1, 2.0),
            elasticity: rng.range(0.0, 60.0),
            max_bend: rng.range(0.05, 1.0),
        }
    }

    #[test]
    fn force_is_the_periodic_motion_of_the_driven_spring() {
        // Against the ODE integrated from rest: after enough cycles for the start to be
        // forgotten (the slowest swing decays as exp(−ζω·t)), within the integrator's error.
        let mut rng = Lcg::new(70);
        for _ in 0..60 {
            let p = random_params(&mut rng);
            let t = rng.range(0.0, 20.0);
            let zeta = (f64::from(p.elasticity) / (std::f64::consts::TAU * 3.0)).max(0.02);
            // Decay per cycle of the slowest mode: exp(−ζ·6π) underdamped; overdamped, the slow
            // root ω(ζ − √(ζ²−1)) per second.
            let slow = if zeta < 1.0 {
                zeta * 6.0 * std::f64::consts::PI
            } else {
                6.0 * std::f64::consts::PI * (zeta - (zeta * zeta - 1.0).sqrt())
            };
            let cycles = ((30.0 / slow).ceil() as usize).clamp(2, 400);
            let got = wind_force(t, &p);
            let expected = force64(f64::from(t), &p, cycles);
            // The f32 time's phase error (6e-8·f·t) times the largest slope of the motion.
            let slope =
                4.0 * std::f64::consts::TAU * 3.0 * f64::from(p.frequency) * f64::from(p.strength);
            let tol = 2e-6 + 1.2e-7 * f64::from(p.frequency * t) / f64::from(p.frequency) * slope;
            assert_close(got, expected, tol, "wind force");
            assert!(got.abs() <= p.max_bend, "{got} > {}", p.max_bend);
        }
    }

    #[test]
    fn force_is_continuous_with_no_velocity_jump_and_overshoots_after_the_push() {
        // scenes/wind.toml's gusts, sampled every 0.2 ms over four cycles (8 s).
        let p = WindParams::default();
        let dt = 2e-4f64;
        let x: Vec<f64> = (0..40_000)
            .map(|k| f64::from(wind_force((k as f64 * dt) as f32, &p)))
            .collect();
        let v: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
        let v_max = v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // Position: no step larger than the fastest motion allows (plus f32 rounding).
        for (k, w) in x.windows(2).enumerate() {
            assert!(
                (w[1] - w[0]).abs() <= v_max * dt * 1.01 + 1e-6,
                "a jump at t = {}: {w:?}",
                k as f64 * dt
            );
        }
        // Velocity: changes by at most the largest acceleration the spring can have (ω²·the
        // bend range) over a step, cycle starts (t = 2, 4, 6 s) and push drops included. The
        // old gust cycle jumped from +0.89/s to −2.09/s at each wrap.
        let omega = std::f64::consts::TAU * 3.0 * 0.5;
        let a_max = omega * omega * 2.0 * f64::from(p.strength);
        for (k, w) in v.windows(2).enumerate() {
            assert!(
                (w[1] - w[0]).abs() <= a_max * dt + 2.0 * 2e-7 / dt,
                "velocity jumps at t = {}: {w:?}",
                k as f64 * dt
            );
        }
        for wrap in [2.0f64, 4.0, 6.0] {
            let k = (wrap / dt).round() as usize;
            assert!(
                (v[k] - v[k - 2]).abs() < 0.05,
                "velocity across the wrap at {wrap} s: {} → {}",
                v[k - 2],
                v[k]
            );
        }
        // The push bends the strand past its steady bend (strength 0.3 → tanh limit 0.5),
        // and after the push drops (the second half of each cycle) it swings back past rest.
        let cycle = |from: f64, to: f64| {
            let (a, b) = ((from / dt) as usize, (to / dt) as usize);
            x[a..b]
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)))
        };
        let (_, peak) = cycle(4.0, 5.0);
        let (trough, _) = cycle(5.0, 6.0);
        let steady = 0.5 * (0.3f64 / 0.5).tanh();
        assert!(
            peak > steady * 1.1,
            "rings past the steady bend: {peak} vs {steady}"
        );
        assert!(
            trough < -0.3 * peak,
            "overshoots rest after the push: {trough} vs {peak}"
        );
    }

    #[test]
    fn force_is_time_addressable_and_steady_without_gusts() {
        let p = WindParams::default();
        // The motion repeats every cycle: one time alone gives the frame.
        for t in [0.1f32, 0.7, 1.3, 1.9] {
            assert_close(
                wind_force(t, &p),
                f64::from(wind_force(t + 4.0, &p)),
                2e-6,
                "period",
            );
        }
        let steady = WindParams {
            frequency: 0.0,
            ..p
        };
        for t in [0.0f32, 1.0, 100.0] {
            assert_close(
                wind_force(t, &steady),
                0.5 * (0.3f64 / 0.5).tanh(),
                1e-7,
                "steady wind",
            );
        }
        // Elasticity 0 (the smallest damping) and a very stiff return stay bounded and finite.
        for elasticity in [0.0f32, 1000.0] {
            let p = WindParams { elasticity, ..p };
            for k in 0..200 {
                let f = wind_force(k as f32 * 0.013, &p);
                assert!(f.is_finite() && f.abs() <= p.max_bend, "{elasticity}: {f}");
            }
        }
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
