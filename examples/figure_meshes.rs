//! Writes the meshes of the thesis figures that need a model pelage does not build itself:
//! `scenes/meshes/bull.obj` (figure 3.12, a bull) and `scenes/meshes/face.obj` (figure 3.10, a
//! human face, thickened and thinned). Run `cargo run --release --example figure_meshes` to
//! regenerate them; the committed files are its output, so their licence is pelage's own.
//! `tests/figure_meshes.rs` regenerates both in memory and checks that the committed files are
//! byte for byte this program's output, and that each loads, is closed and faces outward.
//!
//! - **Bull**: an implicit surface, the smooth union (polynomial smooth-min) of ellipsoids and
//!   round cones (barrel, chest, hump, rump, belly, dewlap, neck, skull, muzzle, ears, legs,
//!   hooves), sampled on a grid and polygonised by *surface nets* (one vertex per grid cell the
//!   surface crosses, one quad per grid edge it crosses), each vertex then moved onto the surface
//!   by Newton steps. Horns and tail are closed tubes of their own, their roots buried in the
//!   head and rump. Texture coordinates come from *charts*: each primitive belongs to a chart
//!   with an axis (the barrel's runs along the body, a leg's down the leg); a triangle takes the
//!   chart of the primitive nearest its centre and is mapped cylindrically around that axis (u =
//!   angle × the chart's radius, v = distance along the axis), or, where its normal lies within
//!   45° of the axis (the rump, the muzzle, the soles of the hooves), projected flat along it.
//!   The cylinder's seam lies on the hidden side (the belly, the inside of the legs). Every
//!   chart uses the same world length per unit of uv, so the fur's tile (`texture_repeat`) is one
//!   size all over the animal.
//! - **Face**: a deformed sphere (poles at the crown and under the chin, longitude seam at the back
//!   of the head): a head-shaped ellipsoid narrowed at the jaw, displaced along its radius by a
//!   height field of Gaussian bumps on the front (brow, eye sockets with eyeballs, nose and
//!   nostrils, lips, chin, cheekbones) and the sides (ears). The longitude and latitude steps are
//!   finer on the face than at the back; uv is the plain longitude/latitude, so the fur tile
//!   does not follow the finer steps, except over the crown and under the chin, where caps
//!   projected flat along the vertical keep the fur from converging on the poles.
//!
//! Everything is y-up, counter-clockwise seen from outside, and computed with `libm` and plain
//! IEEE arithmetic, so the files are the same bytes on every platform.

use glam::{Vec2, Vec3};
use std::collections::BTreeMap;
use std::f32::consts::{PI, TAU};
use std::path::Path;

/// Triangles with texture coordinates: what an OBJ file holds.
#[derive(Clone, Debug, Default)]
pub struct ObjMesh {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Texture coordinates, one per position.
    pub uvs: Vec<Vec2>,
    /// Counter-clockwise seen from outside.
    pub indices: Vec<[u32; 3]>,
}

impl ObjMesh {
    /// Appends `other`.
    fn append(&mut self, other: ObjMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend(other.positions);
        self.uvs.extend(other.uvs);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + base)));
    }

    /// The OBJ text: `header` lines as comments, then `v`, `vt` (4 decimals) and `f v/vt`.
    pub fn to_obj(&self, header: &[&str]) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        for line in header {
            let _ = writeln!(s, "# {line}");
        }
        let _ = writeln!(
            s,
            "# {} vertices, {} triangles",
            self.positions.len(),
            self.indices.len()
        );
        for p in &self.positions {
            let _ = writeln!(s, "v {} {} {}", fixed(p.x), fixed(p.y), fixed(p.z));
        }
        for t in &self.uvs {
            let _ = writeln!(s, "vt {} {}", fixed(t.x), fixed(t.y));
        }
        for [a, b, c] in &self.indices {
            let (a, b, c) = (a + 1, b + 1, c + 1);
            let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}");
        }
        s
    }
}

/// `x` with 4 decimals, trailing zeros dropped and no negative zero.
fn fixed(x: f32) -> String {
    let s = format!("{:.4}", x);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() {
        "0".to_string()
    } else {
        s.to_string()
    }
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Polynomial smooth minimum (Quílez), blending over a band of width `k`.
fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// A unit vector orthogonal to `a` (unit), as close as possible to `hint`.
fn orthogonal(a: Vec3, hint: Vec3) -> Vec3 {
    let h = hint - a * hint.dot(a);
    h.try_normalize()
        .unwrap_or_else(|| a.any_orthonormal_vector())
}

// ---------------------------------------------------------------------------------------------
// The bull
// ---------------------------------------------------------------------------------------------

/// World length of one unit of uv on the bull (all charts alike).
const BULL_UV_SCALE: f32 = 3.2;
/// Grid step of the bull's surface nets.
const BULL_CELL: f32 = 0.045;

/// A shape of the bull's implicit surface.
#[derive(Clone, Copy, Debug)]
enum Shape {
    /// Centre and radii.
    Ellipsoid(Vec3, Vec3),
    /// A cone with rounded ends: from `a` (radius `ra`) to `b` (radius `rb`).
    RoundCone(Vec3, f32, Vec3, f32),
}

impl Shape {
    /// Signed distance (exact for round cones, the usual first-order bound for ellipsoids).
    fn distance(&self, p: Vec3) -> f32 {
        match *self {
            Shape::Ellipsoid(c, r) => {
                let q = (p - c) / r;
                let k0 = q.length();
                let k1 = ((p - c) / (r * r)).length();
                if k1 > 0.0 {
                    k0 * (k0 - 1.0) / k1
                } else {
                    -r.min_element()
                }
            }
            Shape::RoundCone(a, ra, b, rb) => round_cone(p, a, b, ra, rb),
        }
    }
}

/// Signed distance to a round cone (Quílez).
fn round_cone(p: Vec3, a: Vec3, b: Vec3, r1: f32, r2: f32) -> f32 {
    let ba = b - a;
    let l2 = ba.dot(ba);
    let rr = r1 - r2;
    let a2 = l2 - rr * rr;
    let il2 = 1.0 / l2;
    let pa = p - a;
    let y = pa.dot(ba);
    let z = y - l2;
    let x2 = (pa * l2 - ba * y).length_squared();
    let y2 = y * y * l2;
    let z2 = z * z * l2;
    let k = rr.signum() * rr * rr * x2;
    if z.signum() * a2 * z2 > k {
        return libm::sqrtf(x2 + z2) * il2 - r2;
    }
    if y.signum() * a2 * y2 < k {
        return libm::sqrtf(x2 + y2) * il2 - r1;
    }
    (libm::sqrtf(x2 * a2 * il2) + y * rr) * il2 - r1
}

/// A uv chart: a cylinder around `axis` through `origin`, the seam on the `−up` side.
#[derive(Clone, Copy, Debug)]
struct Chart {
    origin: Vec3,
    axis: Vec3,
    /// Direction of angle 0 (orthogonal to `axis`); the seam lies opposite.
    up: Vec3,
    /// Radius at which one radian of angle is this many world units of u.
    radius: f32,
}

impl Chart {
    fn new(origin: Vec3, towards: Vec3, up: Vec3, radius: f32) -> Chart {
        let axis = (towards - origin).normalize();
        Chart {
            origin,
            axis,
            up: orthogonal(axis, up),
            radius,
        }
    }

    /// `(angle, along)` of `p`: the angle in `(−π, π]` from `up` around `axis`.
    fn cylindrical(&self, p: Vec3) -> (f32, f32) {
        let d = p - self.origin;
        let side = self.axis.cross(self.up);
        (libm::atan2f(d.dot(side), d.dot(self.up)), d.dot(self.axis))
    }

    /// Flat projection along the axis, oriented so `T × B` points along `sign · axis`.
    fn flat(&self, p: Vec3, sign: f32) -> Vec2 {
        let d = p - self.origin;
        let side = self.axis.cross(self.up);
        if sign > 0.0 {
            Vec2::new(d.dot(self.up), d.dot(side))
        } else {
            Vec2::new(d.dot(side), d.dot(self.up))
        }
    }
}

/// The bull's shapes, each with the index of its chart and the smooth-min band it joins with.
struct Bull {
    shapes: Vec<(Shape, usize, f32)>,
    charts: Vec<Chart>,
}

fn v3(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

impl Bull {
    /// The bull faces +x, stands on y = 0, and is symmetric in z.
    fn new() -> Bull {
        use Shape::{Ellipsoid as E, RoundCone as C};
        let mut charts = vec![
            // 0: body, along the spine from rump to chest, seam along the belly.
            Chart::new(v3(-1.2, 1.02, 0.0), v3(1.0, 1.02, 0.0), Vec3::Y, 0.5),
            // 1: neck, from the withers to the poll, seam under the throat.
            Chart::new(v3(0.75, 1.1, 0.0), v3(1.35, 1.08, 0.0), Vec3::Y, 0.32),
            // 2: head, from the poll down to the muzzle, seam under the jaw.
            Chart::new(
                v3(1.3, 1.2, 0.0),
                v3(1.68, 0.66, 0.0),
                v3(1.0, 0.6, 0.0),
                0.17,
            ),
        ];
        let mut shapes = vec![
            (E(v3(-0.05, 1.04, 0.0), v3(0.98, 0.42, 0.4)), 0, 0.0),
            // Deep chest and shoulders.
            (E(v3(0.55, 0.98, 0.0), v3(0.46, 0.5, 0.41)), 0, 0.12),
            // Hump over the withers, and the crest running up the neck.
            (E(v3(0.5, 1.33, 0.0), v3(0.42, 0.26, 0.27)), 0, 0.12),
            (E(v3(0.82, 1.33, 0.0), v3(0.33, 0.18, 0.2)), 1, 0.1),
            // Rump and hips.
            (E(v3(-0.72, 1.12, 0.0), v3(0.36, 0.36, 0.37)), 0, 0.1),
            // Belly.
            (E(v3(-0.05, 0.86, 0.0), v3(0.68, 0.32, 0.42)), 0, 0.1),
            // Dewlap under the throat.
            (E(v3(0.98, 0.76, 0.0), v3(0.22, 0.28, 0.12)), 1, 0.1),
            // Neck.
            (
                C(v3(0.75, 1.1, 0.0), 0.37, v3(1.28, 1.06, 0.0), 0.21),
                1,
                0.1,
            ),
            // Skull, broad at the poll, and the muzzle.
            (E(v3(1.33, 1.11, 0.0), v3(0.14, 0.14, 0.17)), 2, 0.06),
            (
                C(v3(1.36, 1.08, 0.0), 0.14, v3(1.58, 0.78, 0.0), 0.1),
                2,
                0.06,
            ),
            (E(v3(1.6, 0.73, 0.0), v3(0.11, 0.11, 0.135)), 2, 0.05),
        ];
        for z in [-1.0f32, 1.0] {
            // Ears, sticking out sideways below the horns.
            let ear = charts.len();
            charts.push(Chart::new(
                v3(1.3, 1.07, 0.13 * z),
                v3(1.3, 1.07, 0.4 * z),
                Vec3::Y,
                0.05,
            ));
            shapes.push((
                E(v3(1.29, 1.06, 0.27 * z), v3(0.05, 0.065, 0.13)),
                ear,
                0.06,
            ));
            // Front leg: forearm, cannon and hoof.
            let fore = charts.len();
            charts.push(Chart::new(
                v3(0.56, 0.9, 0.2 * z),
                v3(0.58, 0.0, 0.21 * z),
                v3(0.0, 0.0, z),
                0.1,
            ));
            shapes.push((
                C(
                    v3(0.55, 0.85, 0.2 * z),
                    0.15,
                    v3(0.57, 0.42, 0.21 * z),
                    0.085,
                ),
                fore,
                0.12,
            ));
            shapes.push((
                C(
                    v3(0.57, 0.42, 0.21 * z),
                    0.08,
                    v3(0.58, 0.09, 0.21 * z),
                    0.06,
                ),
                fore,
                0.04,
            ));
            shapes.push((
                E(v3(0.6, 0.055, 0.21 * z), v3(0.075, 0.055, 0.068)),
                fore,
                0.025,
            ));
            // Hind leg: thigh (into the rump), hock, cannon and hoof.
            let thigh = charts.len();
            charts.push(Chart::new(
                v3(-0.68, 1.05, 0.21 * z),
                v3(-0.86, 0.45, 0.2 * z),
                v3(0.0, 0.0, z),
                0.16,
            ));
            shapes.push((
                C(
                    v3(-0.68, 0.98, 0.21 * z),
                    0.25,
                    v3(-0.86, 0.47, 0.2 * z),
                    0.085,
                ),
                thigh,
                0.12,
            ));
            let shin = charts.len();
            charts.push(Chart::new(
                v3(-0.86, 0.5, 0.2 * z),
                v3(-0.8, 0.0, 0.2 * z),
                v3(0.0, 0.0, z),
                0.08,
            ));
            shapes.push((
                C(
                    v3(-0.86, 0.47, 0.2 * z),
                    0.08,
                    v3(-0.8, 0.09, 0.2 * z),
                    0.06,
                ),
                shin,
                0.04,
            ));
            shapes.push((
                E(v3(-0.78, 0.055, 0.2 * z), v3(0.075, 0.055, 0.068)),
                shin,
                0.025,
            ));
        }
        Bull { shapes, charts }
    }

    /// The implicit function: negative inside.
    fn field(&self, p: Vec3) -> f32 {
        let mut d = f32::INFINITY;
        for (shape, _, k) in &self.shapes {
            let s = shape.distance(p);
            d = if d.is_infinite() || *k <= 0.0 {
                d.min(s)
            } else {
                smin(d, s, *k)
            };
        }
        d
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        let e = 1.0e-3;
        Vec3::new(
            self.field(p + Vec3::X * e) - self.field(p - Vec3::X * e),
            self.field(p + Vec3::Y * e) - self.field(p - Vec3::Y * e),
            self.field(p + Vec3::Z * e) - self.field(p - Vec3::Z * e),
        ) / (2.0 * e)
    }

    /// `p` moved onto the surface by a few Newton steps, each at most a cell long.
    fn project(&self, mut p: Vec3) -> Vec3 {
        for _ in 0..4 {
            let f = self.field(p);
            let g = self.gradient(p);
            let g2 = g.length_squared();
            if g2 < 1.0e-8 {
                break;
            }
            let step = g * (f / g2);
            p -= step.clamp_length_max(BULL_CELL);
        }
        p
    }

    /// The chart of the shape nearest `p`.
    fn chart_at(&self, p: Vec3) -> usize {
        let mut best = (f32::INFINITY, 0);
        for (shape, chart, _) in &self.shapes {
            let d = shape.distance(p);
            if d < best.0 {
                best = (d, *chart);
            }
        }
        best.1
    }
}

/// Surface nets over `field` on the grid `lo + cell · (i, j, k)`, `i < n.x` …: vertices on the
/// surface (after `project`) and counter-clockwise triangles (normals towards positive values).
fn surface_nets(
    field: impl Fn(Vec3) -> f32,
    project: impl Fn(Vec3) -> Vec3,
    lo: Vec3,
    cell: f32,
    n: [usize; 3],
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let [nx, ny, nz] = n;
    let at = |i: usize, j: usize, k: usize| lo + cell * Vec3::new(i as f32, j as f32, k as f32);
    let idx = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let mut values = vec![0.0f32; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                values[idx(i, j, k)] = field(at(i, j, k));
            }
        }
    }
    // One vertex per cell the surface crosses: the mean of its edges' crossings.
    let mut cell_vertex = vec![u32::MAX; nx * ny * nz];
    let mut positions = Vec::new();
    const CORNERS: [[usize; 3]; 8] = [
        [0, 0, 0],
        [1, 0, 0],
        [0, 1, 0],
        [1, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [0, 1, 1],
        [1, 1, 1],
    ];
    const EDGES: [[usize; 2]; 12] = [
        [0, 1],
        [2, 3],
        [4, 5],
        [6, 7],
        [0, 2],
        [1, 3],
        [4, 6],
        [5, 7],
        [0, 4],
        [1, 5],
        [2, 6],
        [3, 7],
    ];
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let f = CORNERS.map(|[a, b, c]| values[idx(i + a, j + b, k + c)]);
                let inside = f.iter().filter(|&&x| x < 0.0).count();
                if inside == 0 || inside == 8 {
                    continue;
                }
                let (mut sum, mut count) = (Vec3::ZERO, 0.0f32);
                for [e0, e1] in EDGES {
                    if (f[e0] < 0.0) != (f[e1] < 0.0) {
                        let t = f[e0] / (f[e0] - f[e1]);
                        let [a0, b0, c0] = CORNERS[e0];
                        let [a1, b1, c1] = CORNERS[e1];
                        let p0 = at(i + a0, j + b0, k + c0);
                        let p1 = at(i + a1, j + b1, k + c1);
                        sum += p0 + (p1 - p0) * t;
                        count += 1.0;
                    }
                }
                cell_vertex[idx(i, j, k)] = positions.len() as u32;
                positions.push(project(sum / count));
            }
        }
    }
    // One quad per grid edge the surface crosses, joining the four cells around it.
    let mut indices = Vec::new();
    for k in 1..nz - 1 {
        for j in 1..ny - 1 {
            for i in 1..nx - 1 {
                let here = values[idx(i, j, k)] < 0.0;
                // Edge along each axis; the cells around it, in the (a, b) order where
                // a × b = axis: (a−1, b−1), (a, b−1), (a, b), (a−1, b).
                let around: [([usize; 3], [[usize; 3]; 4]); 3] = [
                    (
                        [i + 1, j, k],
                        [[i, j - 1, k - 1], [i, j, k - 1], [i, j, k], [i, j - 1, k]],
                    ),
                    (
                        [i, j + 1, k],
                        [[i - 1, j, k - 1], [i - 1, j, k], [i, j, k], [i, j, k - 1]],
                    ),
                    (
                        [i, j, k + 1],
                        [[i - 1, j - 1, k], [i, j - 1, k], [i, j, k], [i - 1, j, k]],
                    ),
                ];
                for ([a, b, c], cells) in around {
                    if a >= nx || b >= ny || c >= nz {
                        continue;
                    }
                    let there = values[idx(a, b, c)] < 0.0;
                    if here == there {
                        continue;
                    }
                    let mut q = cells.map(|[x, y, z]| cell_vertex[idx(x, y, z)]);
                    if q.contains(&u32::MAX) {
                        continue;
                    }
                    if !here {
                        q.reverse();
                    }
                    // Split along the shorter diagonal.
                    let p = q.map(|v| positions[v as usize]);
                    if p[0].distance_squared(p[2]) <= p[1].distance_squared(p[3]) {
                        indices.push([q[0], q[1], q[2]]);
                        indices.push([q[0], q[2], q[3]]);
                    } else {
                        indices.push([q[0], q[1], q[3]]);
                        indices.push([q[1], q[2], q[3]]);
                    }
                }
            }
        }
    }
    (positions, indices)
}

/// Texture coordinates by charts (module docs): vertices are duplicated per chart, projection
/// and side of the cylinder's seam.
fn chart_uvs(
    positions: &[Vec3],
    indices: &[[u32; 3]],
    charts: &[Chart],
    chart_of: impl Fn(Vec3) -> usize,
) -> ObjMesh {
    let mut map: BTreeMap<(u32, usize, u8), u32> = BTreeMap::new();
    let mut out = ObjMesh::default();
    for tri in indices {
        let p = tri.map(|i| positions[i as usize]);
        let centre = (p[0] + p[1] + p[2]) / 3.0;
        let c = chart_of(centre);
        let chart = &charts[c];
        let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let along = normal.dot(chart.axis);
        // Projection: 0 around the cylinder, 1 flat facing +axis, 2 flat facing −axis; 3 around,
        // past the seam (angles below zero moved up by 2π).
        let (kind, uv): (u8, [Vec2; 3]) = if along.abs() > std::f32::consts::FRAC_1_SQRT_2 {
            let sign = along.signum();
            (
                if sign > 0.0 { 1 } else { 2 },
                p.map(|q| chart.flat(q, sign)),
            )
        } else {
            let cyl = p.map(|q| chart.cylindrical(q));
            let lo = cyl.iter().map(|c| c.0).fold(f32::INFINITY, f32::min);
            let hi = cyl.iter().map(|c| c.0).fold(f32::NEG_INFINITY, f32::max);
            let wrap = hi - lo > PI;
            let uv = cyl.map(|(angle, along)| {
                let angle = if wrap && angle < 0.0 {
                    angle + TAU
                } else {
                    angle
                };
                Vec2::new(angle * chart.radius, along)
            });
            (if wrap { 3 } else { 0 }, uv)
        };
        let face = [0, 1, 2].map(|k| {
            *map.entry((tri[k], c, kind)).or_insert_with(|| {
                out.positions.push(p[k]);
                out.uvs.push(uv[k]);
                (out.positions.len() - 1) as u32
            })
        });
        out.indices.push(face);
    }
    out
}

/// A closed tube along the quadratic Bézier `a → b → c` with radius `radius(s)` (`s` in
/// `[0, 1]`), each end closed by a pole; uv as the charts' (angle × `uv_radius`, arc length).
fn tube(
    [a, b, c]: [Vec3; 3],
    radius: impl Fn(f32) -> f32,
    uv_radius: f32,
    around: u32,
    rings: u32,
) -> ObjMesh {
    let point = |s: f32| {
        let t = 1.0 - s;
        a * (t * t) + b * (2.0 * t * s) + c * (s * s)
    };
    let tangent = |s: f32| ((b - a) * (1.0 - s) + (c - b) * s).normalize();
    // Arc length by the midpoint rule.
    let steps = 256;
    let mut length = vec![0.0f32; steps + 1];
    for k in 0..steps {
        let (s0, s1) = (k as f32 / steps as f32, (k + 1) as f32 / steps as f32);
        length[k + 1] = length[k] + point(s0).distance(point(s1));
    }
    let arc = |s: f32| {
        let x = s * steps as f32;
        let k = (x as usize).min(steps - 1);
        length[k] + (length[k + 1] - length[k]) * (x - k as f32)
    };
    // A frame carried along the curve: n1 × n2 = tangent.
    let reference = tangent(0.0).any_orthonormal_vector();
    let mut m = ObjMesh::default();
    // Ring j at s = j / rings for j = 1..rings−1; poles at s = 0 and 1.
    for j in 1..rings {
        let s = j as f32 / rings as f32;
        let t = tangent(s);
        let n1 = orthogonal(t, reference);
        let n2 = t.cross(n1);
        let r = radius(s);
        for i in 0..=around {
            let angle = TAU * (i % around) as f32 / around as f32;
            let (cs, sn) = (libm::cosf(angle), libm::sinf(angle));
            m.positions.push(point(s) + r * (cs * n1 + sn * n2));
            let u = TAU * i as f32 / around as f32;
            m.uvs.push(Vec2::new(u * uv_radius, arc(s)));
        }
    }
    let row = around + 1;
    let at = |i: u32, j: u32| (j - 1) * row + i;
    for j in 1..rings - 1 {
        for i in 0..around {
            let (p, q, r, s) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            m.indices.push([p, q, r]);
            m.indices.push([p, r, s]);
        }
    }
    for (s, j, top) in [(0.0f32, 1, false), (1.0, rings - 1, true)] {
        for i in 0..around {
            let pole = m.positions.len() as u32;
            m.positions.push(point(s));
            let u = TAU * (i as f32 + 0.5) / around as f32;
            m.uvs.push(Vec2::new(u * uv_radius, arc(s)));
            let (p, q) = (at(i, j), at(i + 1, j));
            m.indices
                .push(if top { [p, q, pole] } else { [pole, q, p] });
        }
    }
    m
}

/// Moves every chart (a group of triangles sharing a uv layout) so that its uv start at 0, and
/// scales world units to uv.
fn normalise_uvs(mesh: &mut ObjMesh, scale: f32) {
    // Connected groups in uv: vertices linked by triangles.
    let n = mesh.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for tri in &mesh.indices {
        for k in 1..3 {
            let (a, b) = (
                find(&mut parent, tri[0] as usize),
                find(&mut parent, tri[k] as usize),
            );
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut low: BTreeMap<usize, Vec2> = BTreeMap::new();
    for i in 0..n {
        let r = find(&mut parent, i);
        let e = low.entry(r).or_insert(Vec2::splat(f32::INFINITY));
        *e = e.min(mesh.uvs[i]);
    }
    for i in 0..n {
        let r = find(&mut parent, i);
        mesh.uvs[i] = (mesh.uvs[i] - low[&r]) / scale;
    }
}

/// The bull of figure 3.12 (module docs).
pub fn bull() -> ObjMesh {
    let bull = Bull::new();
    let mut lo = Vec3::new(-1.3, -0.06, -0.62);
    let hi = Vec3::new(1.85, 1.72, 0.62);
    let n = ((hi - lo) / BULL_CELL).ceil().as_uvec3() + 1;
    // Grid points symmetric about z = 0, so the two sides are mirror images.
    lo.z = -0.5 * (n.z - 1) as f32 * BULL_CELL;
    let (positions, indices) = surface_nets(
        |p| bull.field(p),
        |p| bull.project(p),
        lo,
        BULL_CELL,
        [n.x as usize, n.y as usize, n.z as usize],
    );
    let mut mesh = chart_uvs(&positions, &indices, &bull.charts, |p| bull.chart_at(p));
    // Horns: out of the poll sideways, then forward and up, to a point.
    for z in [-1.0f32, 1.0] {
        let horn = tube(
            [
                v3(1.31, 1.2, 0.1 * z),
                v3(1.34, 1.24, 0.5 * z),
                v3(1.5, 1.45, 0.5 * z),
            ],
            |s| 0.065 * libm::powf(1.0 - s, 0.8) + 0.004,
            0.05,
            14,
            20,
        );
        mesh.append(horn);
    }
    // Tail: from the top of the rump, arching back and hanging down a little to the bull's
    // right (+z, the side scenes/bull.toml sees, so the tuft shows past the rump).
    let tail = tube(
        [
            v3(-0.95, 1.3, 0.0),
            v3(-1.27, 1.4, 0.06),
            v3(-1.22, 0.42, 0.2),
        ],
        |s| 0.035 + 0.045 * smoothstep(0.78, 0.9, s) * (1.0 - smoothstep(0.9, 1.0, s)).sqrt(),
        0.04,
        10,
        40,
    );
    mesh.append(tail);
    normalise_uvs(&mut mesh, BULL_UV_SCALE);
    mesh
}

// ---------------------------------------------------------------------------------------------
// The face
// ---------------------------------------------------------------------------------------------

/// A Gaussian bump of height `h` at `(x, y)` with radii `(rx, ry)`.
fn bump(p: Vec2, centre: Vec2, radii: Vec2, h: f32) -> f32 {
    let d = (p - centre) / radii;
    h * libm::expf(-d.length_squared())
}

/// Displacement of the face's front at `(x, y)` (head units: the head is about 2 tall).
fn face_relief(x: f32, y: f32) -> f32 {
    let p = Vec2::new(x, y);
    let ax = Vec2::new(x.abs(), y); // mirror-symmetric features
    let b = |c: (f32, f32), r: (f32, f32), h: f32, q: Vec2| {
        bump(q, Vec2::new(c.0, c.1), Vec2::new(r.0, r.1), h)
    };
    let mut h = 0.0;
    // Brow ridge and forehead.
    h += b((0.0, 0.3), (0.45, 0.08), 0.06, p);
    h += b((0.24, 0.26), (0.15, 0.05), 0.05, ax);
    // Eye sockets, and the eyeballs in them.
    h += b((0.27, 0.11), (0.15, 0.09), -0.2, ax);
    h += b((0.27, 0.1), (0.085, 0.055), 0.11, ax);
    // Nose: a ridge from between the eyes down to the tip, then the nostril wings.
    let along = smoothstep(0.2, -0.22, y); // 0 at the root, 1 at the tip
    let ridge_width = 0.05 + 0.06 * along;
    let under = smoothstep(-0.2, -0.3, y); // the underside falls away
    h += (0.04 + 0.32 * along * along)
        * libm::expf(-(x / ridge_width) * (x / ridge_width))
        * smoothstep(0.26, 0.16, y)
        * (1.0 - under);
    h += b((0.0, -0.235), (0.07, 0.055), 0.08, p);
    h += b((0.1, -0.25), (0.06, 0.05), 0.12, ax);
    // Philtrum and lips, with the mouth's line between them.
    h += b((0.0, -0.4), (0.18, 0.05), 0.11, p);
    h += b((0.0, -0.52), (0.16, 0.05), 0.11, p);
    h += b((0.0, -0.46), (0.21, 0.016), -0.08, p);
    h += b((0.21, -0.46), (0.04, 0.04), -0.05, ax);
    // Chin and the hollow above it.
    h += b((0.0, -0.62), (0.13, 0.04), -0.04, p);
    h += b((0.0, -0.78), (0.17, 0.1), 0.13, p);
    // Cheekbones, cheeks and temples.
    h += b((0.42, -0.06), (0.13, 0.1), 0.08, ax);
    h += b((0.36, -0.42), (0.12, 0.14), -0.04, ax);
    h += b((0.5, 0.35), (0.1, 0.15), -0.04, ax);
    h
}

/// A point of the head at longitude `phi` (0 = facing +z, the front) and latitude `theta`
/// (0 = under the chin, π = the crown).
fn head_point(phi: f32, theta: f32) -> Vec3 {
    let (st, ct) = (libm::sinf(theta), libm::cosf(theta));
    let d = Vec3::new(st * libm::sinf(phi), -ct, st * libm::cosf(phi));
    // Base: an ellipsoid, narrower at the jaw, the jaw and chin drawn forward and down, the back
    // of the skull rounder.
    let jaw = smoothstep(0.0, -0.9, d.y);
    let mut p = Vec3::new(
        0.74 * d.x * (1.0 - 0.22 * jaw),
        d.y * (1.0 + 0.04 * jaw),
        d.z * if d.z > 0.0 { 0.8 } else { 0.95 },
    );
    // A flatter face: the front pushed out where the ellipsoid falls back towards the sides.
    p.z += 0.16 * smoothstep(0.3, 0.75, d.z) * (1.0 - d.z);
    p.z += 0.12 * jaw * smoothstep(0.0, 0.8, d.z);
    // Front relief along the radius, faded out towards the sides.
    let front = smoothstep(0.25, 0.7, d.z);
    let mut h = front * face_relief(p.x, p.y);
    // Ears on the sides.
    let side = Vec2::new(d.z, d.y);
    h += smoothstep(0.6, 0.9, d.x.abs())
        * bump(side, Vec2::new(-0.05, 0.0), Vec2::new(0.13, 0.2), 0.12);
    p + d * h
}

/// Warped parameter: `t` in `[−1, 1]` to `[−1, 1]` with slope `a` at 0 (finer steps there when
/// `a < 1`) and `3 − 2a` at the ends.
fn warp(t: f32, a: f32) -> f32 {
    t * (a + (1.0 - a) * t * t)
}

/// Latitudes (radians) where the face's flat caps begin, over the crown and under the chin.
const FACE_CROWN_LATITUDE: f32 = 0.95;
const FACE_CHIN_LATITUDE: f32 = 1.1;
/// World length per unit of the caps' u and v (the scene repeats the fur 25 × 15 times).
const FACE_CAP_UV: Vec2 = Vec2::new(4.0, 2.4);

/// The face of figure 3.10 (module docs).
pub fn face() -> ObjMesh {
    let (slices, stacks) = (92u32, 56u32);
    // Longitude from the back (−π) round to the back (π), finer on the front.
    let phi = |i: u32| PI * warp(2.0 * i as f32 / slices as f32 - 1.0, 0.45);
    // Latitude from under the chin to the crown, finer over the face (centred a little low).
    let theta_of = |j: u32| {
        let t = warp(2.0 * j as f32 / stacks as f32 - 1.0, 0.5);
        0.5 * PI * (1.0 + t)
    };
    let mut m = ObjMesh::default();
    let mut thetas = Vec::new();
    // Rings j = 1..stacks−1, poles at j = 0 and stacks. u = longitude / 2π, v = latitude / π.
    for j in 1..stacks {
        let theta = theta_of(j);
        for i in 0..=slices {
            // The seam's two columns share bit-identical positions (longitude −π).
            m.positions.push(head_point(phi(i % slices), theta));
            m.uvs.push(Vec2::new((phi(i) + PI) / TAU, theta / PI));
            thetas.push(theta);
        }
    }
    let row = slices + 1;
    let at = |i: u32, j: u32| (j - 1) * row + i;
    for j in 1..stacks - 1 {
        for i in 0..slices {
            // u grows towards +x on the front and v upwards: right-handed seen from outside.
            let (p, q, r, s) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            m.indices.push([p, q, r]);
            m.indices.push([p, r, s]);
        }
    }
    for (theta, j, top) in [(0.0f32, 1, false), (PI, stacks - 1, true)] {
        for i in 0..slices {
            let pole = m.positions.len() as u32;
            m.positions.push(head_point(0.0, theta));
            let u = (0.5 * (phi(i) + phi(i + 1)) + PI) / TAU;
            m.uvs.push(Vec2::new(u, theta / PI));
            thetas.push(theta);
            let (p, q) = (at(i, j), at(i + 1, j));
            m.indices
                .push(if top { [p, q, pole] } else { [pole, q, p] });
        }
    }
    // The caps over the crown and under the chin are projected flat along y instead, so the
    // fur does not converge on the poles: world lengths FACE_CAP_UV per unit of uv (u along +z
    // and v along +x on the crown, u along +x and v along +z under the chin: never mirrored),
    // about the lat-long map's scale where the caps meet it.
    let (crown, chin) = (
        PI / 2.0 + FACE_CROWN_LATITUDE,
        PI / 2.0 - FACE_CHIN_LATITUDE,
    );
    let mut out = ObjMesh::default();
    let mut map: BTreeMap<(u32, u8), u32> = BTreeMap::new();
    for tri in &m.indices {
        let t = tri.map(|i| thetas[i as usize]);
        let cap = if t.iter().all(|&t| t >= crown) {
            1
        } else if t.iter().all(|&t| t <= chin) {
            2
        } else {
            0
        };
        out.indices.push(tri.map(|i| {
            *map.entry((i, cap)).or_insert_with(|| {
                let p = m.positions[i as usize];
                let uv = match cap {
                    1 => Vec2::new(0.5 + p.z / FACE_CAP_UV.x, 0.5 + p.x / FACE_CAP_UV.y),
                    2 => Vec2::new(0.5 + p.x / FACE_CAP_UV.x, 0.5 + p.z / FACE_CAP_UV.y),
                    _ => m.uvs[i as usize],
                };
                out.positions.push(p);
                out.uvs.push(uv);
                (out.positions.len() - 1) as u32
            })
        }));
    }
    out
}

/// The header of each file.
pub fn header(what: &str) -> Vec<String> {
    vec![
        what.to_string(),
        "Generated by examples/figure_meshes.rs (`cargo run --release --example figure_meshes`);"
            .to_string(),
        "do not edit by hand. Licensed like the rest of pelage.".to_string(),
    ]
}

/// `(file name, OBJ text)` of every mesh this program writes.
pub fn files() -> Vec<(&'static str, String)> {
    let bull_header =
        header("A bull for thesis figure 3.12: y up, facing +x, hooves on y = 0, about 3 long.");
    let face_header = header(
        "A human head for thesis figure 3.10: y up, facing +z, about 2 tall, centred at the origin.",
    );
    vec![
        (
            "bull.obj",
            bull().to_obj(&bull_header.iter().map(String::as_str).collect::<Vec<_>>()),
        ),
        (
            "face.obj",
            face().to_obj(&face_header.iter().map(String::as_str).collect::<Vec<_>>()),
        ),
    ]
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes");
    std::fs::create_dir_all(&dir)?;
    for (name, text) in files() {
        let path = dir.join(name);
        std::fs::write(&path, &text)?;
        println!("wrote {} ({} bytes)", path.display(), text.len());
    }
    Ok(())
}
