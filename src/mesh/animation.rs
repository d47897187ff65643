//! Animation clips (mesh stage): keyframed node transforms sampled at the scene time, which
//! [`super::skin`] turns into the posed body.
//!
//! Conventions (numeric conventions, "Animation"), following glTF 2.0 §3.11:
//! - **Clip time**: `t_clip = time·speed`; with `loop` it is wrapped into `[0, end)` by
//!   `t − end·floor(t / end)` (in f64, then rounded to f32), where `end` is the last key time
//!   of any channel; without `loop` it is clamped to `[0, end]`. Before a channel's first key
//!   its first value holds, after its last key its last value.
//! - **Keys** are found by binary search: the interval `k` with `t_k ≤ t < t_{k+1}`, and
//!   `u = (t − t_k) / (t_{k+1} − t_k)`.
//! - **LINEAR**: translations and scales `a + (b − a)·u` per component; rotations by
//!   **slerp**, as the specification intends for rotations: the shorter arc (`b` negated when
//!   `a·b < 0`), `θ = acos(a·b)` and weights `sin((1 − u)θ)/sin θ`, `sin(uθ)/sin θ` (libm's
//!   `acosf`/`sinf`), falling back to the normalised lerp when `a·b > 0.9995`; the result is
//!   normalised.
//! - **STEP**: the value of key `k`.
//! - **CUBICSPLINE**: the Hermite form of §C.4 with the tangents scaled by the interval
//!   `t_{k+1} − t_k`; rotations normalised after.

use glam::{Quat, Vec3, Vec4};

use super::skin::LocalTransform;

/// How a sampler interpolates between keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Linear (slerp for rotations).
    Linear,
    /// The earlier key's value.
    Step,
    /// Cubic Hermite spline with in and out tangents.
    CubicSpline,
}

/// Which property of a node a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// Translation.
    Translation,
    /// Rotation.
    Rotation,
    /// Scale.
    Scale,
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node.
    pub node: usize,
    /// The property.
    pub property: Property,
    /// The interpolation.
    pub interpolation: Interpolation,
    /// Key times, seconds, strictly increasing (checked at load).
    pub times: Vec<f32>,
    /// Values: one per key (three per key for CUBICSPLINE: in-tangent, value, out-tangent);
    /// vec3 properties use `x, y, z` and leave `w` zero.
    pub values: Vec<Vec4>,
}

/// A named clip.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Its name in the file (may be empty).
    pub name: String,
    /// Its channels.
    pub channels: Vec<Channel>,
}

impl Clip {
    /// The last key time of any channel, seconds (0 for a clip without keys).
    pub fn end(&self) -> f32 {
        self.channels
            .iter()
            .filter_map(|c| c.times.last().copied())
            .fold(0.0, f32::max)
    }

    /// The clip time of scene time `time` (module docs).
    pub fn clip_time(&self, time: f32, speed: f32, looping: bool) -> f32 {
        let t = f64::from(time) * f64::from(speed);
        let end = f64::from(self.end());
        if end <= 0.0 {
            return 0.0;
        }
        let t = if looping {
            t - end * (t / end).floor()
        } else {
            t.clamp(0.0, end)
        };
        (t as f32).clamp(0.0, self.end())
    }

    /// The nodes' local transforms at clip time `t`: `rest` with every channel applied.
    pub fn sample(&self, rest: &[LocalTransform], t: f32) -> Vec<LocalTransform> {
        let mut locals = rest.to_vec();
        for channel in &self.channels {
            let Some(LocalTransform::Trs {
                translation,
                rotation,
                scale,
            }) = locals.get_mut(channel.node)
            else {
                continue;
            };
            let value = channel.sample(t);
            match channel.property {
                Property::Translation => *translation = value.truncate(),
                Property::Scale => *scale = value.truncate(),
                Property::Rotation => *rotation = Quat::from_vec4(value),
            }
        }
        locals
    }
}

impl Channel {
    /// The channel's value at clip time `t` (module docs).
    pub fn sample(&self, t: f32) -> Vec4 {
        let n = self.times.len();
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| {
            if cubic {
                self.values[3 * k + 1]
            } else {
                self.values[k]
            }
        };
        let last = n - 1;
        let normalise = |v: Vec4| {
            if self.property == Property::Rotation {
                Vec4::from_array(super::skin::normalised_quat(v.to_array()))
            } else {
                v
            }
        };
        if t <= self.times[0] {
            return normalise(value(0));
        }
        if t >= self.times[last] {
            return normalise(value(last));
        }
        // The interval k with t_k ≤ t < t_{k+1}.
        let k = self.times.partition_point(|&key| key <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let u = (t - t0) / dt;
        match self.interpolation {
            Interpolation::Step => normalise(value(k)),
            Interpolation::Linear => {
                let (a, b) = (value(k), value(k + 1));
                if self.property == Property::Rotation {
                    slerp(a, b, u)
                } else {
                    a + (b - a) * u
                }
            }
            Interpolation::CubicSpline => {
                let v0 = self.values[3 * k + 1];
                let b0 = self.values[3 * k + 2] * dt;
                let v1 = self.values[3 * (k + 1) + 1];
                let a1 = self.values[3 * (k + 1)] * dt;
                let (u2, u3) = (u * u, u * u * u);
                let h00 = (2.0 * u3 - 3.0 * u2) + 1.0;
                let h10 = (u3 - 2.0 * u2) + u;
                let h01 = 3.0 * u2 - 2.0 * u3;
                let h11 = u3 - u2;
                normalise(((v0 * h00 + b0 * h10) + v1 * h01) + a1 * h11)
            }
        }
    }
}

/// Spherical linear interpolation of unit quaternions `a`, `b` (module docs), normalised.
pub fn slerp(a: Vec4, b: Vec4, u: f32) -> Vec4 {
    let dot = |p: Vec4, q: Vec4| ((p.x * q.x + p.y * q.y) + p.z * q.z) + p.w * q.w;
    let mut d = dot(a, b);
    let b = if d < 0.0 {
        d = -d;
        -b
    } else {
        b
    };
    let (wa, wb) = if d > 0.9995 {
        (1.0 - u, u)
    } else {
        let theta = libm::acosf(d);
        let s = libm::sinf(theta);
        (libm::sinf((1.0 - u) * theta) / s, libm::sinf(u * theta) / s)
    };
    Vec4::from_array(super::skin::normalised_quat((a * wa + b * wb).to_array()))
}

/// The glTF value of a property as a `Vec4` (vec3 properties with `w = 0`).
pub fn vec3_value(v: Vec3) -> Vec4 {
    v.extend(0.0)
}

// Matrix entries are indexed as the formulas write them.
#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    fn channel(interpolation: Interpolation, property: Property, values: Vec<Vec4>) -> Channel {
        Channel {
            node: 0,
            property,
            interpolation,
            times: vec![0.0, 1.0, 3.0],
            values,
        }
    }

    #[test]
    fn linear_and_step_between_keys_and_held_outside() {
        let values = vec![
            Vec4::new(0.0, 0.0, 0.0, 0.0),
            Vec4::new(2.0, 4.0, -2.0, 0.0),
            Vec4::new(6.0, 4.0, -2.0, 0.0),
        ];
        let linear = channel(Interpolation::Linear, Property::Translation, values.clone());
        assert_eq!(linear.sample(0.5), Vec4::new(1.0, 2.0, -1.0, 0.0));
        assert_eq!(linear.sample(2.0), Vec4::new(4.0, 4.0, -2.0, 0.0));
        assert_eq!(linear.sample(-1.0), values[0]);
        assert_eq!(linear.sample(9.0), values[2]);
        assert_eq!(linear.sample(1.0), values[1]);
        let step = channel(Interpolation::Step, Property::Translation, values.clone());
        assert_eq!(step.sample(0.999), values[0]);
        assert_eq!(step.sample(2.9), values[1]);
    }

    #[test]
    fn slerp_matches_double_precision_and_takes_the_short_arc() {
        let a = Quat::from_rotation_y(0.2);
        let b = Quat::from_rotation_y(1.4);
        for u in [0.0f32, 0.25, 0.5, 0.9, 1.0] {
            let got = slerp(Vec4::from(a), Vec4::from(b), u);
            let angle = 0.2 + (1.4 - 0.2) * f64::from(u);
            let want = [0.0, (angle / 2.0).sin(), 0.0, (angle / 2.0).cos()];
            for k in 0..4 {
                assert!((f64::from(got[k]) - want[k]).abs() < 2e-6, "u {u}: {got:?}");
            }
        }
        // −b is the same rotation: the result is the same.
        let flipped = slerp(Vec4::from(a), -Vec4::from(b), 0.5);
        let direct = slerp(Vec4::from(a), Vec4::from(b), 0.5);
        assert_eq!(flipped, direct);
    }

    #[test]
    fn cubic_spline_passes_through_its_keys_with_their_slopes() {
        // x(t) = t² on keys 0, 1, 3: tangents (slopes) 0, 2, 6.
        let key = |v: f32, slope: f32| {
            [
                Vec4::new(slope, 0.0, 0.0, 0.0),
                Vec4::new(v, 0.0, 0.0, 0.0),
                Vec4::new(slope, 0.0, 0.0, 0.0),
            ]
        };
        let values = [key(0.0, 0.0), key(1.0, 2.0), key(9.0, 6.0)].concat();
        let c = channel(Interpolation::CubicSpline, Property::Translation, values);
        assert_eq!(c.sample(1.0).x, 1.0);
        // A cubic Hermite reproduces a quadratic exactly.
        for t in [0.25f32, 0.5, 1.5, 2.0, 2.75] {
            let got = f64::from(c.sample(t).x);
            let want = f64::from(t) * f64::from(t);
            assert!((got - want).abs() < 1e-5, "t {t}: {got} vs {want}");
        }
    }

    #[test]
    fn clip_time_loops_or_clamps() {
        let clip = Clip {
            name: "walk".into(),
            channels: vec![channel(
                Interpolation::Linear,
                Property::Translation,
                vec![Vec4::ZERO; 3],
            )],
        };
        assert_eq!(clip.end(), 3.0);
        assert_eq!(clip.clip_time(4.0, 1.0, true), 1.0);
        assert_eq!(clip.clip_time(-1.0, 1.0, true), 2.0);
        assert_eq!(clip.clip_time(2.0, 2.0, true), 1.0);
        assert_eq!(clip.clip_time(4.0, 1.0, false), 3.0);
        assert_eq!(clip.clip_time(-4.0, 1.0, false), 0.0);
        // Frame k of an animation is its own instant: the same time gives the same pose.
        assert_eq!(
            clip.clip_time(7.25, 1.0, true),
            clip.clip_time(7.25, 1.0, true)
        );
    }
}
