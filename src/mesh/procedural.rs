//! Procedural meshes (mesh stage): torus (the thesis's main object), UV sphere, open cylinder and a
//! bent "leg" (thesis fig. 3.11). All are y-up, centred near the origin, CCW seen from outside,
//! with `u` running around (the longitude, increasing counter-clockwise seen from +y) and `v` along
//! the other parameter, both over `[0, 1]`. Seam vertices are duplicated (`u = 1` next to `u = 0`)
//! with bit-identical positions, so their welded normals are identical too.
//!
//! `model_resolution` is the **triangle count** (thesis 4.1: "modelResolution is the number of
//! triangles"; 500 is the base). Segment counts are chosen by the *independent rounding rule*:
//! for a surface made of `a × b` quads (`2ab` triangles) whose quads should be roughly square,
//! with aspect `ρ = (length along u) / (length along v)`,
//!
//! ```text
//! a = max(min_a, round(sqrt(n · ρ / 2)))      b = max(min_b, round(sqrt(n / (2ρ))))
//! ```
//!
//! Each count is a non-decreasing function of `n`, so the triangle count never falls when
//! `model_resolution` grows; the relative error of `2ab` against `n` is at most about
//! `1/(2a) + 1/(2b)` (500 → within 5 %, exact for a torus with `R/r = 2.5`). Each count is
//! capped at [`MAX_SEGMENTS`]. Non-finite or non-positive sizes are treated as an aspect of 1.
//!
//! All trigonometry uses `libm` so vertices are identical on every platform.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::{Mesh, frame};

/// Upper bound on any segment count, whatever `model_resolution` asks for.
pub const MAX_SEGMENTS: u32 = 4096;

fn rounded(x: f64, min: u32) -> u32 {
    if !x.is_finite() {
        return min;
    }
    (x.round().clamp(0.0, MAX_SEGMENTS as f64) as u32).clamp(min, MAX_SEGMENTS)
}

fn aspect(along_u: f32, along_v: f32) -> f64 {
    let rho = along_u as f64 / along_v as f64;
    if rho.is_finite() && rho > 0.0 {
        rho
    } else {
        1.0
    }
}

/// Segment counts of the independent rounding rule: `(a, b)` with `2ab ≈ n`, `a/b ≈ ρ`.
fn quad_segments(n: u32, rho: f64, min_a: u32, min_b: u32) -> (u32, u32) {
    let n = n as f64;
    (
        rounded((n * rho / 2.0).sqrt(), min_a),
        rounded((n / (2.0 * rho)).sqrt(), min_b),
    )
}

/// `(major, minor)` segment counts of [`torus`]: aspect `ρ = R / r`, both at least 3;
/// the torus has `2 · major · minor` triangles.
pub fn torus_segments(major_radius: f32, minor_radius: f32, model_resolution: u32) -> (u32, u32) {
    quad_segments(model_resolution, aspect(major_radius, minor_radius), 3, 3)
}

/// `(slices, stacks)` of [`sphere`]: `slices ≈ √n` around, `stacks − 1 ≈ √n / 2` (aspect 2,
/// the equator being twice as long as a meridian), at least 3 and 2; the sphere has
/// `2 · slices · (stacks − 1)` triangles.
pub fn sphere_segments(model_resolution: u32) -> (u32, u32) {
    let (slices, bands) = quad_segments(model_resolution, 2.0, 3, 1);
    (slices, bands + 1)
}

/// `(around, along)` segment counts of [`cylinder`]: aspect `ρ = 2πr / h`, at least 3 and 1;
/// the cylinder has `2 · around · along` triangles.
pub fn cylinder_segments(radius: f32, height: f32, model_resolution: u32) -> (u32, u32) {
    quad_segments(model_resolution, aspect(TAU * radius, height), 3, 1)
}

/// Vertices and triangles under construction.
#[derive(Default)]
struct Builder {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<[u32; 3]>,
}

impl Builder {
    fn finish(self) -> Mesh {
        frame::build(&self.positions, &self.uvs, self.indices)
    }

    /// Adds a `cols × rows` quad grid of `(cols + 1) × (rows + 1)` vertices with
    /// `uv = (i / cols, j / rows)`; returns the first new vertex index. `position(i, j)` gets
    /// `i` in `0..=cols`, `j` in `0..=rows`; a closed direction must return the same position
    /// for `i = cols` as for `i = 0`.
    fn grid(&mut self, cols: u32, rows: u32, position: impl Fn(u32, u32) -> Vec3) -> u32 {
        let Builder {
            positions,
            uvs,
            indices,
        } = self;
        let base = positions.len() as u32;
        for j in 0..=rows {
            for i in 0..=cols {
                positions.push(position(i, j));
                uvs.push(Vec2::new(i as f32 / cols as f32, j as f32 / rows as f32));
            }
        }
        let at = |i: u32, j: u32| base + j * (cols + 1) + i;
        for j in 0..rows {
            for i in 0..cols {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                indices.push([a, b, c]);
                indices.push([a, c, d]);
            }
        }
        base
    }

    /// Adds `slices` pole vertices at `pole` with `uv = ((i + ½) / slices, v)` and the fan
    /// joining them to the ring of `slices + 1` vertices starting at `ring`. `top`: the pole
    /// lies at larger `v` than the ring.
    fn pole_fan(&mut self, pole: Vec3, v: f32, ring: u32, slices: u32, top: bool) {
        let Builder {
            positions,
            uvs,
            indices,
        } = self;
        for i in 0..slices {
            let p = positions.len() as u32;
            positions.push(pole);
            uvs.push(Vec2::new((i as f32 + 0.5) / slices as f32, v));
            if top {
                indices.push([ring + i, ring + i + 1, p]);
            } else {
                indices.push([p, ring + i + 1, ring + i]);
            }
        }
    }
}

/// `(cos, sin)` of the angle `TAU · (i mod n) / n`, so that `i = n` repeats `i = 0` exactly.
fn circle(i: u32, n: u32) -> (f32, f32) {
    let angle = TAU * (i % n) as f32 / n as f32;
    (libm::cosf(angle), libm::sinf(angle))
}

/// A torus around the y axis: `u` follows the major circle (angle φ), `v` the minor circle
/// (angle ψ, starting at the outer equator and going up):
/// `p = ((R + r cos ψ) cos φ, r sin ψ, −(R + r cos ψ) sin φ)`.
/// Segment counts: [`torus_segments`]. Both seams are duplicated vertices.
pub fn torus(major_radius: f32, minor_radius: f32, model_resolution: u32) -> Mesh {
    let (a, b) = torus_segments(major_radius, minor_radius, model_resolution);
    let mut m = Builder::default();
    m.grid(a, b, |i, j| {
        let (cp, sp) = circle(i, a);
        let (cs, ss) = circle(j, b);
        let ring = major_radius + minor_radius * cs;
        Vec3::new(ring * cp, minor_radius * ss, -ring * sp)
    });
    m.finish()
}

/// A UV sphere centred at the origin: `u` is the longitude, `v` runs from the south pole
/// (`v = 0`, y = −radius) to the north pole (`v = 1`):
/// `p = r (sin θ cos φ, −cos θ, −sin θ sin φ)`, `θ = π v`.
///
/// Each pole is one vertex per slice (same position, `u` at the slice centre), joined to the
/// nearest ring by a fan of triangles, so no face is degenerate and the poles get a finite
/// tangent frame (T along the slice's meridian-normal direction). Segment counts:
/// [`sphere_segments`].
pub fn sphere(radius: f32, model_resolution: u32) -> Mesh {
    let (slices, stacks) = sphere_segments(model_resolution);
    let mut m = Builder::default();
    let bands = stacks - 2; // quad bands between the first and last rings
    let ring = |i: u32, j: u32| {
        // ring j = 1..=stacks-1
        let theta = PI * j as f32 / stacks as f32;
        let (st, ct) = (libm::sinf(theta), libm::cosf(theta));
        let (cp, sp) = circle(i, slices);
        radius * Vec3::new(st * cp, -ct, -st * sp)
    };
    let first = if bands == 0 {
        // A single ring: grid of zero rows is not usable, so lay it out by hand.
        let base = m.positions.len() as u32;
        for i in 0..=slices {
            m.positions.push(ring(i, 1));
            m.uvs.push(Vec2::new(i as f32 / slices as f32, 0.5));
        }
        base
    } else {
        let base = m.grid(slices, bands, |i, j| ring(i, j + 1));
        // Rescale the grid's v from [0, 1] to the rings' [1/stacks, (stacks−1)/stacks].
        for t in &mut m.uvs[base as usize..] {
            t.y = (1.0 + t.y * bands as f32) / stacks as f32;
        }
        base
    };
    let last = first + bands * (slices + 1);
    m.pole_fan(Vec3::new(0.0, -radius, 0.0), 0.0, first, slices, false);
    m.pole_fan(Vec3::new(0.0, radius, 0.0), 1.0, last, slices, true);
    m.finish()
}

/// An open tube (no caps: a cap cannot carry the tube's seamless tiling `uv`, and fur on a cap
/// would be a second texture layout) around the y axis from `y = −height/2` (`v = 0`) to
/// `y = +height/2` (`v = 1`): `p = (r cos φ, y, −r sin φ)`. Segment counts:
/// [`cylinder_segments`].
pub fn cylinder(radius: f32, height: f32, model_resolution: u32) -> Mesh {
    let (a, b) = cylinder_segments(radius, height, model_resolution);
    let mut m = Builder::default();
    m.grid(a, b, |i, j| {
        let (c, s) = circle(i, a);
        let y = height * (j as f32 / b as f32 - 0.5);
        Vec3::new(radius * c, y, -radius * s)
    });
    m.finish()
}

/// Arc length of the leg's spine.
const LEG_LENGTH: f32 = 2.2;
/// Number of integration steps for the spine.
const LEG_STEPS: u32 = 512;
/// Where the rounded end starts, as a fraction of the spine.
const LEG_CAP_START: f32 = 1.0 - 0.13 / LEG_LENGTH;

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Spine direction at `s`: angle from −y towards +z (a slight knee bend, then the foot turns
/// forward).
fn leg_angle(s: f32) -> f32 {
    0.12 * libm::sinf(TAU * s) + 1.4 * smoothstep(0.68, 0.84, s)
}

/// Tube radius at `s` (thigh, knee, calf, ankle, foot), closing as a quarter circle over the
/// last 0.13 units of spine.
fn leg_radius(s: f32) -> f32 {
    const KEYS: [(f32, f32); 6] = [
        (0.0, 0.28),
        (0.42, 0.19),
        (0.56, 0.21),
        (0.7, 0.11),
        (0.86, 0.13),
        (LEG_CAP_START, 0.13),
    ];
    if s >= LEG_CAP_START {
        let x = ((s - LEG_CAP_START) / (1.0 - LEG_CAP_START)).min(1.0);
        return 0.13 * libm::sqrtf((1.0 - x * x).max(0.0));
    }
    for w in KEYS.windows(2) {
        let ((s0, r0), (s1, r1)) = (w[0], w[1]);
        if s <= s1 {
            return r0 + (r1 - r0) * smoothstep(s0, s1, s);
        }
    }
    0.13
}

/// `(around, rings)` of [`leg`]: the leg has `around · (2 · rings − 1)` triangles (quads
/// between `rings` rings, plus a fan to the tip). Aspect: mean circumference over length.
pub fn leg_segments(model_resolution: u32) -> (u32, u32) {
    let rho = aspect(TAU * 0.18, LEG_LENGTH);
    let n = model_resolution as f64;
    let around = rounded((n * rho / 2.0).sqrt(), 3);
    let rings = rounded(((2.0 * n / rho).sqrt() + 1.0) / 2.0, 2);
    (around, rings)
}

/// A procedural human-ish leg (thesis fig. 3.11): a tube whose spine runs down from the hip
/// (`y ≈ 1.1`, open end, `v = 0`) with a slight knee bend, tapering thigh → knee → calf →
/// ankle, then turning forward (+z) into a foot that closes in a rounded tip (`v = 1`, one
/// vertex per slice like a sphere pole). `u` runs around the tube. Segment counts:
/// [`leg_segments`].
pub fn leg(model_resolution: u32) -> Mesh {
    let (around, rings) = leg_segments(model_resolution);
    // Integrate the spine (midpoint rule) so samples are exact functions of the step index.
    let step = LEG_LENGTH / LEG_STEPS as f32;
    let mut spine = Vec::with_capacity(LEG_STEPS as usize + 1);
    let mut c = Vec3::new(0.0, 1.1, 0.0);
    spine.push(c);
    for k in 0..LEG_STEPS {
        let a = leg_angle((k as f32 + 0.5) / LEG_STEPS as f32);
        c += step * Vec3::new(0.0, -libm::cosf(a), libm::sinf(a));
        spine.push(c);
    }
    let centre = |s: f32| {
        let x = s * LEG_STEPS as f32;
        let k = (x as usize).min(LEG_STEPS as usize - 1);
        let f = x - k as f32;
        spine[k].lerp(spine[k + 1], f)
    };
    let s_of = |j: u32| j as f32 / rings as f32;
    let mut m = Builder::default();
    let base = m.grid(around, rings - 1, |i, j| {
        let s = s_of(j);
        let a = leg_angle(s);
        let t = Vec3::new(0.0, -libm::cosf(a), libm::sinf(a));
        let w = t.cross(Vec3::X);
        let (cp, sp) = circle(i, around);
        centre(s) + leg_radius(s) * (cp * Vec3::X + sp * w)
    });
    for t in &mut m.uvs[base as usize..] {
        t.y *= (rings - 1) as f32 / rings as f32;
    }
    let last = base + (rings - 1) * (around + 1);
    m.pole_fan(centre(1.0), 1.0, last, around, true);
    m.finish()
}

#[cfg(test)]
mod tests {
    use super::super::frame::tests::assert_orthonormal;
    use super::*;

    fn check_mesh(mesh: &Mesh) {
        mesh.validate().unwrap();
        for v in &mesh.vertices {
            assert_orthonormal(&v.frame, 1e-5);
            assert!(v.uv.x >= 0.0 && v.uv.x <= 1.0 && v.uv.y >= 0.0 && v.uv.y <= 1.0);
            assert!(v.frame.is_right_handed(), "{v:?}");
        }
        // Every face is CCW from outside: its normal agrees with its vertices' normals.
        for (f, tri) in mesh.indices.iter().enumerate() {
            let [a, b, c] = mesh.triangle(f).unwrap();
            let n = (b - a).cross(c - a);
            assert!(n.length() > 0.0, "degenerate face {f}");
            for &i in tri {
                assert!(n.dot(mesh.vertices[i as usize].normal) > 0.0, "face {f}");
            }
        }
    }

    /// Vertices with identical positions have identical normals (and, with `frames`, identical
    /// tangent frames and derivatives: wrap-around seams are invisible to shading).
    fn check_seams(mesh: &Mesh) {
        check_seams_with(mesh, false)
    }

    fn check_seams_with(mesh: &Mesh, frames: bool) {
        let weld = super::super::weld_by_position(
            &mesh.vertices.iter().map(|v| v.position).collect::<Vec<_>>(),
        );
        let mut dup = 0;
        for (i, &w) in weld.iter().enumerate() {
            if w as usize != i {
                dup += 1;
                let (a, b) = (&mesh.vertices[i], &mesh.vertices[w as usize]);
                assert_eq!(a.normal, b.normal);
                if frames {
                    assert_eq!((a.frame, a.dpdu, a.dpdv), (b.frame, b.dpdu, b.dpdv));
                }
            }
        }
        assert!(dup > 0);
    }

    #[test]
    fn torus_segment_rule() {
        assert_eq!(torus_segments(1.0, 0.4, 500), (25, 10));
        for ratio in [1.0f32, 1.5, 2.0, 2.5, 3.0, 4.0] {
            let (a, b) = torus_segments(ratio, 1.0, 500);
            let n = 2 * a * b;
            assert!(
                (n as f32 - 500.0).abs() <= 25.0,
                "ratio {ratio}: {a}×{b} = {n}"
            );
            assert!((a as f32 / b as f32 / ratio - 1.0).abs() < 0.2);
        }
        let mut last = 0;
        for n in (0..120_000).step_by(37) {
            let (a, b) = torus_segments(1.0, 0.3, n);
            assert!(a >= 3 && b >= 3);
            assert!(2 * a * b >= last, "n = {n}");
            last = 2 * a * b;
        }
        for n in [500, 1000, 2000, 5000, 25000, 50000, 100000] {
            let t = torus(1.0, 0.4, n).triangle_count() as f32;
            assert!((t / n as f32 - 1.0).abs() < 0.05, "{n}: {t}");
        }
        // Nonsense sizes do not panic.
        assert_eq!(torus_segments(f32::NAN, 0.0, 0), (3, 3));
        assert_eq!(torus_segments(1.0, 1.0, u32::MAX).0, MAX_SEGMENTS);
    }

    #[test]
    fn torus_geometry() {
        let mesh = torus(1.0, 0.4, 500);
        check_mesh(&mesh);
        check_seams_with(&mesh, true);
        let (a, b) = torus_segments(1.0, 0.4, 500);
        assert_eq!(mesh.vertices.len() as u32, (a + 1) * (b + 1));
        for v in &mesh.vertices {
            // Distance to the core circle is the minor radius; normal points away from it.
            let q = Vec3::new(v.position.x, 0.0, v.position.z).normalize();
            let d = v.position - q;
            assert!((d.length() - 0.4).abs() < 1e-5);
            assert!(d.normalize().dot(v.normal) > 0.99);
            // T follows the major circle (u), B the minor circle (v).
            assert!(v.frame.tangent.dot(Vec3::Y.cross(q)) > 0.99);
            // Eq. 3.3 on the raw derivatives: dpdu × dpdv is along the geometric normal.
            let c = v.dpdu.cross(v.dpdv).normalize().dot(v.normal);
            assert!(c > 0.99, "{c} {v:?}");
        }
    }

    #[test]
    fn sphere_geometry() {
        for n in [0, 10, 100, 500, 5000] {
            let mesh = sphere(2.0, n);
            check_mesh(&mesh);
            check_seams(&mesh);
            let (s, t) = sphere_segments(n);
            assert_eq!(mesh.triangle_count() as u32, 2 * s * (t - 1));
            for v in &mesh.vertices {
                assert!((v.position.length() - 2.0).abs() < 1e-5);
                let tol = if n < 100 { 0.8 } else { 0.99 };
                assert!(v.position.normalize().dot(v.normal) > tol, "{n}: {v:?}");
            }
        }
        let t = sphere(1.0, 500).triangle_count();
        assert!((t as f32 / 500.0 - 1.0).abs() < 0.05, "{t}");
    }

    #[test]
    fn cylinder_geometry() {
        let mesh = cylinder(0.5, 2.0, 500);
        check_mesh(&mesh);
        check_seams_with(&mesh, true);
        for v in &mesh.vertices {
            let radial = Vec3::new(v.position.x, 0.0, v.position.z);
            assert!((radial.length() - 0.5).abs() < 1e-5);
            // Open ends: the rim normals lean but stay outward.
            assert!(radial.normalize().dot(v.normal) > 0.99);
            assert!((v.frame.binormal - Vec3::Y).length() < 1e-5);
        }
        let t = mesh.triangle_count();
        assert!((t as f32 / 500.0 - 1.0).abs() < 0.05, "{t}");
    }

    #[test]
    fn leg_geometry() {
        let mut last = 0;
        for n in [100, 500, 2000, 10000] {
            let mesh = leg(n);
            check_mesh(&mesh);
            check_seams(&mesh);
            let (a, r) = leg_segments(n);
            assert_eq!(mesh.triangle_count() as u32, a * (2 * r - 1));
            assert!(mesh.triangle_count() >= last);
            last = mesh.triangle_count();
            let t = mesh.triangle_count() as f32;
            assert!((t / n as f32 - 1.0).abs() < 0.15, "{n}: {t}");
        }
        let mesh = leg(2000);
        let min = mesh
            .vertices
            .iter()
            .fold(Vec3::INFINITY, |m, v| m.min(v.position));
        let max = mesh
            .vertices
            .iter()
            .fold(Vec3::NEG_INFINITY, |m, v| m.max(v.position));
        assert!(max.y > 1.0 && min.y < -0.7, "{min} {max}");
        assert!(max.z > 0.3, "the foot points forward: {max}");
    }

    #[test]
    fn deterministic() {
        assert_eq!(torus(1.0, 0.4, 500), torus(1.0, 0.4, 500));
        assert_eq!(leg(700), leg(700));
    }
}
