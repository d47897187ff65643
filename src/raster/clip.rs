//! Clipping in homogeneous clip space, before the perspective divide (raster stage).
//!
//! Depth follows the wgpu/Vulkan/D3D convention: visible points satisfy `0 ≤ z ≤ w`. A triangle
//! is clipped against seven planes: `w ≥ W_MIN`, the near plane `z ≥ 0`, the far plane `z ≤ w`,
//! and a guard band `|x| ≤ GUARD_BAND·w`, `|y| ≤ GUARD_BAND·w` that keeps every snapped
//! coordinate inside the fixed-point range derived in [`super::setup`]. Pixels outside the
//! viewport but inside the guard band are discarded by the scissor of binning, not by clipping.
//!
//! Invariants: a vertex with a NaN or infinite coordinate drops its whole triangle; no output
//! vertex has `w < W_MIN` beyond rounding (and none has `w ≤ 0`: a polygon whose cut vertices
//! lose all precision, from coordinates near `f32::MAX`, is dropped); an edge shared by two
//! triangles is cut at bit-identical points, because the intersection is always computed from
//! the inside endpoint towards the outside one.

use super::varyings::Varyings;
use glam::Vec4;

/// Smallest `w` a clipped vertex may have; keeps `1/w` finite.
pub const W_MIN: f32 = 1.0e-5;

/// Half-extent of the guard band in normalised device coordinates: vertices are kept within
/// `|x/w| ≤ GUARD_BAND` and `|y/w| ≤ GUARD_BAND`.
pub const GUARD_BAND: f32 = 64.0;

/// Whether a clip-space position is one [`clip_triangle`] can emit: finite, in front of the eye
/// with a finite `1/w` (not a subnormal `w`), and inside the guard band (with a margin of one
/// for rounding). Setup refuses positions outside it, which keeps its fixed-point bound.
#[inline]
pub fn within_guard_band(p: Vec4) -> bool {
    let band = (GUARD_BAND + 1.0) * p.w;
    p.is_finite() && p.w > 0.0 && (1.0 / p.w).is_finite() && p.x.abs() <= band && p.y.abs() <= band
}

/// A vertex after the vertex stage: clip-space position and its varyings.
#[derive(Clone, Copy, Debug)]
pub struct ClipVertex<V> {
    /// Homogeneous clip-space position.
    pub position: Vec4,
    /// Values to interpolate.
    pub varyings: V,
}

const PLANE_COUNT: usize = 7;
/// A triangle gains at most one vertex per plane.
const MAX_POLYGON: usize = 3 + PLANE_COUNT;

/// Signed distance of `p` to each clip plane; inside when `>= 0`.
#[inline]
fn plane_distance(p: Vec4, plane: usize) -> f32 {
    match plane {
        0 => p.w - W_MIN,
        1 => p.z,
        2 => p.w - p.z,
        3 => GUARD_BAND * p.w + p.x,
        4 => GUARD_BAND * p.w - p.x,
        5 => GUARD_BAND * p.w + p.y,
        _ => GUARD_BAND * p.w - p.y,
    }
}

#[inline]
fn outcode(p: Vec4) -> u8 {
    let mut code = 0;
    for plane in 0..PLANE_COUNT {
        if plane_distance(p, plane) < 0.0 {
            code |= 1 << plane;
        }
    }
    code
}

/// Whether a clip-space position is finite and inside every plane: [`clip_triangle`] emits a
/// triangle of three such vertices itself, unchanged (the common case, whose vertices the
/// rasterizer keeps by index).
#[inline]
pub fn inside_clip_volume(position: Vec4) -> bool {
    position.is_finite() && outcode(position) == 0
}

/// Clips one triangle and hands each resulting triangle (a fan over the clipped polygon, in
/// the input winding) to `emit`. Returns nothing; a fully outside or non-finite triangle emits
/// nothing.
pub fn clip_triangle<V: Varyings>(
    triangle: [ClipVertex<V>; 3],
    mut emit: impl FnMut([ClipVertex<V>; 3]),
) {
    if triangle.iter().any(|v| !v.position.is_finite()) {
        return;
    }
    let codes = triangle.map(|v| outcode(v.position));
    if codes[0] | codes[1] | codes[2] == 0 {
        emit(triangle);
        return;
    }
    if codes[0] & codes[1] & codes[2] != 0 {
        return;
    }

    let mut polygon = [triangle[0]; MAX_POLYGON];
    polygon[..3].copy_from_slice(&triangle);
    let mut count = 3;
    let mut scratch = [triangle[0]; MAX_POLYGON];
    let crossing = codes[0] | codes[1] | codes[2];
    for plane in (0..PLANE_COUNT).filter(|p| crossing & (1 << p) != 0) {
        let mut out = 0;
        for i in 0..count {
            let a = polygon[i];
            let b = polygon[(i + 1) % count];
            let da = plane_distance(a.position, plane);
            let db = plane_distance(b.position, plane);
            let a_inside = da >= 0.0;
            let b_inside = db >= 0.0;
            // A convex polygon gains at most one vertex per plane, but coordinates near f32's
            // limits round cut points off their plane and can make it non-convex: a polygon
            // that would outgrow its room is such a one, and is dropped (as below).
            if out + 2 > MAX_POLYGON {
                return;
            }
            if a_inside {
                scratch[out] = a;
                out += 1;
            }
            if a_inside != b_inside {
                // Always interpolate from the inside endpoint so a shared edge is cut at the
                // same point whichever triangle it belongs to.
                let (inside, outside, d_in, d_out) = if a_inside {
                    (a, b, da, db)
                } else {
                    (b, a, db, da)
                };
                let t = d_in / (d_in - d_out);
                scratch[out] = ClipVertex {
                    position: inside.position + (outside.position - inside.position) * t,
                    varyings: V::lerp(&inside.varyings, &outside.varyings, t),
                };
                out += 1;
            }
        }
        count = out;
        if count < 3 {
            return;
        }
        polygon[..count].copy_from_slice(&scratch[..count]);
    }
    // Coordinates near f32::MAX (where `GUARD_BAND·w` overflows or an intersection cancels)
    // can leave a cut vertex at w ≤ 0, NaN, or outside the guard band by more than rounding;
    // such a polygon is dropped so that setup's fixed-point bound holds. Ordinary input is never
    // near these thresholds (cut vertices are within rounding of their plane), so this never
    // changes an image.
    if !polygon[..count]
        .iter()
        .all(|v| within_guard_band(v.position))
    {
        return;
    }
    for i in 1..count - 1 {
        emit([polygon[0], polygon[i], polygon[i + 1]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32, w: f32) -> ClipVertex<f32> {
        ClipVertex {
            position: Vec4::new(x, y, z, w),
            varyings: z,
        }
    }

    fn collect(t: [ClipVertex<f32>; 3]) -> Vec<[ClipVertex<f32>; 3]> {
        let mut out = Vec::new();
        clip_triangle(t, |tri| out.push(tri));
        out
    }

    #[test]
    fn inside_triangle_passes_unchanged() {
        let out = collect([v(0., 0., 0.5, 1.), v(1., 0., 0.5, 1.), v(0., 1., 0.5, 1.)]);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0][1].position, Vec4::new(1., 0., 0.5, 1.));
    }

    #[test]
    fn triangle_behind_camera_is_dropped() {
        assert!(
            collect([
                v(0., 0., -1., -1.),
                v(1., 0., -1., -1.),
                v(0., 1., -2., -1.)
            ])
            .is_empty()
        );
    }

    #[test]
    fn near_plane_crossing_clips_at_z_zero() {
        let out = collect([v(0., 0., -1., 1.), v(0.5, 0., 1., 1.), v(0., 0.5, 1., 1.)]);
        assert_eq!(
            out.len(),
            2,
            "one vertex behind the near plane leaves a quad"
        );
        for tri in &out {
            for p in tri {
                assert!(p.position.z >= 0.0 && p.position.w >= W_MIN);
                // The varying (a copy of z) is interpolated with the position.
                assert!((p.varyings - p.position.z).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn non_finite_vertices_drop_the_triangle() {
        assert!(
            collect([
                v(f32::NAN, 0., 0.5, 1.),
                v(1., 0., 0.5, 1.),
                v(0., 1., 0.5, 1.)
            ])
            .is_empty()
        );
        assert!(
            collect([
                v(f32::INFINITY, 0., 0.5, 1.),
                v(1., 0., 0.5, 1.),
                v(0., 1., 0.5, 1.)
            ])
            .is_empty()
        );
    }

    #[test]
    fn huge_coordinates_are_pulled_into_the_guard_band() {
        let out = collect([
            v(-1e6, -1e6, 0.5, 1.),
            v(1e6, -1e6, 0.5, 1.),
            v(0., 1e6, 0.5, 1.),
        ]);
        assert!(!out.is_empty());
        for tri in &out {
            for p in tri {
                let q = p.position;
                assert!(q.x.abs() <= GUARD_BAND * q.w * 1.0001);
                assert!(q.y.abs() <= GUARD_BAND * q.w * 1.0001);
            }
        }
    }

    #[test]
    fn shared_edge_is_cut_identically_from_both_sides() {
        let a = v(-0.5, -0.5, -1.0, 1.0);
        let b = v(0.5, 0.5, 1.0, 1.0);
        let left = collect([a, b, v(-0.5, 0.5, 0.5, 1.0)]);
        let right = collect([b, a, v(0.5, -0.5, 0.5, 1.0)]);
        let cut = |tris: &Vec<[ClipVertex<f32>; 3]>| {
            tris.iter()
                .flatten()
                .filter(|p| p.position.z == 0.0)
                .map(|p| p.position)
                .collect::<Vec<_>>()
        };
        let (l, r) = (cut(&left), cut(&right));
        assert!(l.iter().any(|p| r.contains(p)), "{l:?} vs {r:?}");
    }

    #[test]
    fn extreme_coordinates_never_index_past_the_polygon() {
        // Regression for the `triangle` fuzz target's index-out-of-bounds: random triangles
        // whose coordinates mix f32's extremes, tiny values, zeros and ordinary numbers.
        const VALUES: [f32; 12] = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            1e-30,
            -1e-30,
            3.0e38,
            -3.0e38,
            f32::MAX,
            -f32::MAX,
            64.0,
            0.5,
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..200_000 {
            let mut pick = || {
                let r = next();
                if r % 3 == 0 {
                    f32::from_bits((r >> 8) as u32)
                } else {
                    VALUES[(r >> 8) as usize % VALUES.len()]
                }
            };
            let mut vertex = || v(pick(), pick(), pick(), pick());
            let triangle = [vertex(), vertex(), vertex()];
            clip_triangle(triangle, |out| {
                assert!(out.iter().all(|c| c.position.is_finite()));
            });
        }
    }
}
