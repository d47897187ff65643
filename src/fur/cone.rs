//! Cones around strands (thesis 3.1.1, figures 3.3–3.4, 3.7) and the coverage of one projected cone
//! segment on a bake grid (fur bake).
//!
//! A strand sampled at `strand_resolution` segments becomes a chain of truncated cones, each with
//! `circle_resolution` flat facets around. The tangent of a facet is the direction of its slanted
//! centre line, from the middle of its base-circle chord to the middle of its top-circle chord:
//! `normalize(d + (r1 − r0)·cos(π/C)·(cos φ_j e1 + sin φ_j e2))`, with `d` the segment's axis
//! vector, `φ_j = (j + ½)·2π/C` the facet's middle angle and `(e1, e2)` the segment's frame. A
//! tapered cone therefore gives tangents that vary slightly around its circumference, quantised to
//! `C` facets — why the thesis calls `circle_resolution` the "lighting resolution". A point
//! inside the cone (exposed by slicing) takes the tangent of the outer facet at its angle
//! (figure 3.7).

use glam::{Vec2, Vec3};

use super::strand::{Strand, bezier_point};

/// Middle angles of the `C` facets, as cosines and sines, and the chord factor `cos(π/C)`.
pub(crate) struct FacetTable {
    cos_mid: Vec<f32>,
    sin_mid: Vec<f32>,
    chord: f32,
    step: f32,
}

impl FacetTable {
    /// Table for `facets ≥ 1` facets (validated parameters guarantee ≥ 3).
    pub fn new(facets: u32) -> Self {
        let n = facets.max(1);
        let step = core::f32::consts::TAU / n as f32;
        let mids = (0..n).map(|j| (j as f32 + 0.5) * step);
        Self {
            cos_mid: mids.clone().map(libm::cosf).collect(),
            sin_mid: mids.map(libm::sinf).collect(),
            chord: libm::cosf(0.5 * step),
            step,
        }
    }

    fn len(&self) -> usize {
        self.cos_mid.len()
    }
}

/// One truncated cone: axis from `p0` (radius `r0`) to `p1` (radius `r1`) with its frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ConeSegment {
    pub p0: Vec3,
    pub p1: Vec3,
    pub r0: f32,
    pub r1: f32,
    /// Unit axis, `+z` for a degenerate segment.
    pub axis: Vec3,
    /// Frame perpendicular to the axis: `e1` from `+x` (or `+y` when the axis is within
    /// `acos 0.9` of `x`), `e2 = axis × e1`.
    pub e1: Vec3,
    pub e2: Vec3,
}

impl ConeSegment {
    pub fn new(p0: Vec3, p1: Vec3, r0: f32, r1: f32) -> Self {
        let axis = (p1 - p0).normalize_or(Vec3::Z);
        let reference = if axis.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
        let e1 = (reference - axis * reference.dot(axis)).normalize_or(Vec3::X);
        let e2 = axis.cross(e1);
        Self {
            p0,
            p1,
            r0,
            r1,
            axis,
            e1,
            e2,
        }
    }

    /// Whether every value is finite (non-finite user strands are skipped, never panicked on).
    pub fn is_finite(&self) -> bool {
        self.p0.is_finite() && self.p1.is_finite() && self.r0.is_finite() && self.r1.is_finite()
    }

    /// The facet whose angle around the axis contains `offset` (a vector from the axis; its
    /// component along the axis is ignored). Angle 0 is `e1`, increasing towards `e2`; an offset
    /// on the axis falls in facet 0.
    pub fn facet(&self, offset: Vec3, table: &FacetTable) -> usize {
        let x = offset.dot(self.e1);
        let y = offset.dot(self.e2);
        let mut angle = libm::atan2f(y, x);
        if angle < 0.0 {
            angle += core::f32::consts::TAU;
        }
        let j = libm::floorf(angle / table.step);
        if j.is_nan() || j < 0.0 {
            return 0;
        }
        (j as usize).min(table.len() - 1)
    }

    /// Tangent of the outer facet `j`: its slanted centre line, root → tip (see the module doc).
    pub fn facet_tangent(&self, j: usize, table: &FacetTable) -> Vec3 {
        let (c, s) = (
            table.cos_mid.get(j).copied().unwrap_or(1.0),
            table.sin_mid.get(j).copied().unwrap_or(0.0),
        );
        let radial = self.e1 * c + self.e2 * s;
        ((self.p1 - self.p0) + radial * ((self.r1 - self.r0) * table.chord)).normalize_or(self.axis)
    }
}

/// Samples a strand at `segments` equal Bézier parameter steps `t_k = k / segments` into cone
/// segments with linearly interpolated radii.
pub(crate) fn strand_cones(strand: &Strand, segments: u32) -> Vec<ConeSegment> {
    let n = segments.max(1);
    let point = |k: u32| {
        let t = k as f32 / n as f32;
        (bezier_point(strand, t), strand.radius_at(t))
    };
    let mut out = Vec::with_capacity(n as usize);
    let (mut p0, mut r0) = point(0);
    for k in 1..=n {
        let (p1, r1) = point(k);
        out.push(ConeSegment::new(p0, p1, r0, r1));
        (p0, r0) = (p1, r1);
    }
    out
}

/// A bake grid's mapping from plane coordinates to subsample cells: cell `(ix, iy)` has its
/// centre at `((ix + ½)·sx, (iy + ½)·sy)`. `x` always wraps (periodic tile); `y` wraps for
/// shells and is clipped for fins.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GridMap {
    pub nx: usize,
    pub ny: usize,
    pub sx: f32,
    pub sy: f32,
    pub wrap_y: bool,
}

/// Calls `f(cell index, t, offset)` for every grid cell whose centre `q` lies within the
/// interpolated radius of the 2D segment `a → b`: with `t` the parameter of the closest point
/// `c = a + t(b − a)`, the cell is covered when `|q − c| ≤ ra + t(rb − ra)` (for a point-like
/// segment `t = 0` and the radius is `max(ra, rb)`); `offset = q − c`. Cells are visited row by row over the
/// segment's bounding box only; wrapped cells are reported at their wrapped index.
pub(crate) fn raster_capsule(
    map: &GridMap,
    a: Vec2,
    b: Vec2,
    ra: f32,
    rb: f32,
    mut f: impl FnMut(usize, f32, Vec2),
) {
    let rmax = ra.max(rb);
    if !(a.is_finite() && b.is_finite() && rmax.is_finite()) || rmax < 0.0 {
        return;
    }
    let lo = a.min(b) - Vec2::splat(rmax);
    let hi = a.max(b) + Vec2::splat(rmax);
    // Centres (i + ½)·s inside [lo, hi]: i from ceil(lo/s − ½) to floor(hi/s − ½).
    let first = |v: f32, s: f32| libm::ceilf(v / s - 0.5) as i64;
    let last = |v: f32, s: f32| libm::floorf(v / s - 0.5) as i64;
    let (nx, ny) = (map.nx as i64, map.ny as i64);
    let ix0 = first(lo.x, map.sx);
    // A box wider than two tiles is pathological; visiting it once per tile is enough.
    let ix1 = last(hi.x, map.sx).min(ix0.saturating_add(2 * nx));
    let (mut iy0, mut iy1) = (first(lo.y, map.sy), last(hi.y, map.sy));
    if map.wrap_y {
        iy1 = iy1.min(iy0.saturating_add(2 * ny));
    } else {
        iy0 = iy0.max(0);
        iy1 = iy1.min(ny - 1);
    }
    let ab = b - a;
    let len2 = ab.length_squared();
    if !len2.is_finite() {
        return;
    }
    let dr = rb - ra;
    for iy in iy0..=iy1 {
        let qy = (iy as f32 + 0.5) * map.sy;
        let row = iy.rem_euclid(ny) as usize * map.nx;
        for ix in ix0..=ix1 {
            let q = Vec2::new((ix as f32 + 0.5) * map.sx, qy);
            let t = if len2 > 0.0 {
                ((q - a).dot(ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let offset = q - (a + ab * t);
            let r = if len2 > 0.0 { ra + dr * t } else { rmax };
            if offset.length_squared() <= r * r {
                f(row + ix.rem_euclid(nx) as usize, t, offset);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facet_tangents_of_a_cylinder_are_the_axis() {
        let table = FacetTable::new(8);
        let seg = ConeSegment::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), 0.1, 0.1);
        for j in 0..8 {
            assert!((seg.facet_tangent(j, &table) - Vec3::Z).length() < 1e-6);
        }
    }

    #[test]
    fn tapered_cone_tangents_lean_inwards_per_facet() {
        let table = FacetTable::new(4);
        let seg = ConeSegment::new(Vec3::ZERO, Vec3::Z, 0.5, 0.0);
        // e1 = +x for a vertical axis; facet 0 spans 0..90° (middle 45°).
        let off = Vec3::new(1.0, 0.2, 0.0);
        let j = seg.facet(off, &table);
        assert_eq!(j, 0);
        let t = seg.facet_tangent(j, &table);
        // Side line from base chord middle to the apex: moves towards −x, −y while rising.
        let s = 0.5
            * libm::cosf(core::f32::consts::FRAC_PI_4)
            * libm::cosf(core::f32::consts::FRAC_PI_4);
        let expected = Vec3::new(-s, -s, 1.0).normalize();
        assert!((t - expected).length() < 1e-5, "{t} vs {expected}");
        assert_eq!(seg.facet(Vec3::new(-1.0, 0.1, 0.0), &table), 1);
        assert_eq!(seg.facet(Vec3::new(-1.0, -0.1, 0.0), &table), 2);
        assert_eq!(seg.facet(Vec3::new(1.0, -0.1, 0.0), &table), 3);
        assert_eq!(seg.facet(Vec3::ZERO, &table), 0);
    }

    #[test]
    fn capsule_covers_disc_and_wraps() {
        let map = GridMap {
            nx: 10,
            ny: 10,
            sx: 0.1,
            sy: 0.1,
            wrap_y: true,
        };
        let mut hits = Vec::new();
        // A point-like segment at the corner: centre (0.0, 0.0), radius 0.08 covers the four
        // cells around the corner, three of them wrapped.
        raster_capsule(&map, Vec2::ZERO, Vec2::ZERO, 0.08, 0.08, |i, _, _| {
            hits.push(i)
        });
        hits.sort_unstable();
        assert_eq!(hits, vec![0, 9, 90, 99]);
        // Clipped in y when not wrapping.
        let clip = GridMap {
            wrap_y: false,
            ..map
        };
        let mut hits = Vec::new();
        raster_capsule(&clip, Vec2::ZERO, Vec2::ZERO, 0.08, 0.08, |i, _, _| {
            hits.push(i)
        });
        hits.sort_unstable();
        assert_eq!(hits, vec![0, 9]);
        // Non-finite input visits nothing.
        let mut n = 0;
        raster_capsule(&map, Vec2::NAN, Vec2::ZERO, 0.1, 0.1, |_, _, _| n += 1);
        raster_capsule(&map, Vec2::ZERO, Vec2::splat(1e30), 0.1, 0.1, |_, _, _| {
            n += 1
        });
        assert!(n <= 10 * 10 * 9);
    }
}
