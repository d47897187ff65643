//! Triangle setup (raster stage): the perspective divide, the viewport transform, snapping to fixed
//! point, and the three integer edge functions with the top-left fill rule folded into their
//! constants.
//!
//! Conventions (the numbers a GPU implementation must match):
//! - `ndc = clip.xyz · (1/w)`; screen `x = (ndc.x·0.5 + 0.5)·width`,
//!   `y = (0.5 − ndc.y·0.5)·height`: NDC +y is the top row of the image (row 0 of the PNG).
//! - Positions snap to [`SUBPIXEL_BITS`] = 8 fractional bits, rounding to nearest, ties to even.
//! - Pixel (px, py) is sampled at its centre (px + 0.5, py + 0.5).
//! - A triangle whose vertices run counter-clockwise in NDC (y up) is front-facing.
//! - Top-left rule: a sample exactly on an edge belongs to the triangle only if that edge is a
//!   top edge (horizontal, with the triangle below it) or a left edge. An edge shared by two
//!   triangles therefore covers each of its samples exactly once.
//!
//! Overflow bound: clipping keeps `|ndc| ≤ GUARD_BAND = 64` and images are at most 16384
//! pixels wide, so a snapped coordinate is below 65·16384·256 < 2^29 in magnitude. Edge
//! coefficients are differences (< 2^30), pixel-centre steps are 256× that (< 2^38), and an edge
//! value at any pixel of the image is a sum of products below 2^60: it fits in `i64`.

use super::clip::{ClipVertex, within_guard_band};
use super::varyings::Varyings;

/// Fractional bits of the fixed-point screen coordinates.
pub const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed-point units.
pub const SUBPIXEL_ONE: i64 = 1 << SUBPIXEL_BITS;
/// Largest image side the setup's overflow bound allows.
pub const MAX_DIMENSION: u32 = 16384;

/// Which faces a draw discards.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CullMode {
    /// Draw both faces.
    #[default]
    None,
    /// Discard triangles that run clockwise in NDC.
    Back,
    /// Discard triangles that run counter-clockwise in NDC.
    Front,
}

/// A screen position in fixed point, [`SUBPIXEL_BITS`] fractional bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Subpixel {
    /// x in 1/256 pixel.
    pub x: i64,
    /// y in 1/256 pixel, growing downwards.
    pub y: i64,
}

/// An edge function evaluated at pixel centres: `value(px, py) = step_x·px + step_y·py + offset`
/// is the edge's exact fixed-point cross product, minus one when the edge is not top-left, so
/// a pixel is covered exactly when all three values are `≥ 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeFunction {
    /// Change per pixel to the right.
    pub step_x: i64,
    /// Change per pixel downwards.
    pub step_y: i64,
    /// Value at pixel (0, 0), fill-rule bias included.
    pub offset: i64,
    /// 1 when the fill rule subtracted one from `offset` (not a top-left edge), else 0; add it
    /// back to get the exact edge value used for barycentrics.
    pub bias: i64,
}

impl EdgeFunction {
    /// The edge from `a` to `b`, for a triangle of positive area.
    fn new(a: Subpixel, b: Subpixel) -> EdgeFunction {
        let dx = b.x - a.x;
        let dy = b.y - a.y;
        // E(p) = dx·(p.y − a.y) − dy·(p.x − a.x), evaluated at p = pixel·256 + 128.
        let half = SUBPIXEL_ONE / 2;
        let top_left = (dy == 0 && dx > 0) || dy < 0;
        let bias = i64::from(!top_left);
        EdgeFunction {
            step_x: -dy * SUBPIXEL_ONE,
            step_y: dx * SUBPIXEL_ONE,
            offset: dx * (half - a.y) - dy * (half - a.x) - bias,
            bias,
        }
    }

    /// The biased value at pixel (px, py).
    #[inline]
    pub fn at(&self, px: i64, py: i64) -> i64 {
        self.step_x * px + self.step_y * py + self.offset
    }
}

/// An inclusive-exclusive rectangle of pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelRect {
    /// The overlap of two rectangles, `None` when empty.
    pub fn intersect(&self, other: &PixelRect) -> Option<PixelRect> {
        let r = PixelRect {
            x0: self.x0.max(other.x0),
            y0: self.y0.max(other.y0),
            x1: self.x1.min(other.x1),
            y1: self.y1.min(other.y1),
        };
        (r.x0 < r.x1 && r.y0 < r.y1).then_some(r)
    }
}

/// A triangle ready for rasterization. Edge `i` is the edge opposite vertex `i`, so the exact
/// edge value `E_i` divided by twice the area is the screen-space barycentric `λ_i`.
#[derive(Clone, Copy, Debug)]
pub struct SetupTriangle {
    /// Edge functions opposite vertices 0, 1, 2.
    pub edges: [EdgeFunction; 3],
    /// Pixels that may be covered, clamped to the viewport.
    pub bounds: PixelRect,
    /// `1 / (2·area)` in fixed-point units squared.
    pub inv_area: f64,
    /// NDC depth `z/w` per vertex.
    pub depth: [f32; 3],
    /// `1/w` per vertex.
    pub inv_w: [f32; 3],
    /// Whether the triangle runs counter-clockwise in NDC.
    pub front_facing: bool,
}

/// `f32::round_ties_even`, the same value, without the library call it is on x86-64 without
/// SSE4.1 (`rintf`, about 1 % of a frame of 100,000 triangles × 30 shells): below `2^23` in
/// magnitude, adding and subtracting `2^23` rounds to the nearest integer, ties to even (the
/// default rounding of IEEE addition); from `2^23` on, and for infinities and NaN, `x` is
/// already its own rounding.
#[inline]
fn round_ties_even(x: f32) -> f32 {
    const TWO_POW_23: f32 = 8_388_608.0;
    let magnitude = x.abs();
    if magnitude < TWO_POW_23 {
        ((magnitude + TWO_POW_23) - TWO_POW_23).copysign(x)
    } else {
        x
    }
}

/// Snaps a clip-space position to the fixed-point screen grid; returns `(subpixel, ndc z, 1/w)`.
#[inline]
pub fn snap(position: glam::Vec4, width: u32, height: u32) -> (Subpixel, f32, f32) {
    let inv_w = 1.0 / position.w;
    let ndc = position.truncate() * inv_w;
    let sx = (ndc.x * 0.5 + 0.5) * width as f32;
    let sy = (0.5 - ndc.y * 0.5) * height as f32;
    let scale = SUBPIXEL_ONE as f32;
    let snapped = Subpixel {
        x: round_ties_even(sx * scale) as i64,
        y: round_ties_even(sy * scale) as i64,
    };
    (snapped, ndc.z, inv_w)
}

/// Sets up one clipped triangle for a `width`×`height` viewport. Returns `None` for
/// zero-area, culled or fully off-screen triangles, and for vertices outside the guard band
/// (unclipped input, see [`within_guard_band`]). The varyings are reordered with the
/// vertices when a front face is flipped to positive area.
pub fn setup_triangle<V: Varyings>(
    triangle: &[ClipVertex<V>; 3],
    width: u32,
    height: u32,
    cull: CullMode,
) -> Option<(SetupTriangle, [V; 3])> {
    setup_triangle_order(triangle, width, height, cull)
        .map(|(set_up, order)| (set_up, order.map(|i| triangle[i].varyings)))
}

/// [`setup_triangle`] giving, instead of the reordered varyings, which input vertex each of
/// the set-up triangle's corners is (`[0, 1, 2]` or, for a flipped front face, `[0, 2, 1]`):
/// the rasterizer keeps vertex indices rather than copies of the varyings.
pub fn setup_triangle_order<V: Varyings>(
    triangle: &[ClipVertex<V>; 3],
    width: u32,
    height: u32,
    cull: CullMode,
) -> Option<(SetupTriangle, [usize; 3])> {
    let screen = triangle.map(|v| ScreenVertex::new(v.position, width, height));
    setup_screen_triangle(&screen, width, height, cull)
}

/// What the set-up reads of one vertex, computed once per vertex of a draw rather than once
/// per triangle that uses it (a mesh vertex is shared by about six).
#[derive(Clone, Copy, Debug)]
pub struct ScreenVertex {
    /// [`snap`] of the position: meaningful only when `in_band`.
    snapped: (Subpixel, f32, f32),
    /// [`within_guard_band`] of the position.
    in_band: bool,
}

impl ScreenVertex {
    /// The vertex at clip-space `position` on a `width` × `height` target.
    #[inline]
    pub fn new(position: glam::Vec4, width: u32, height: u32) -> Self {
        ScreenVertex {
            snapped: snap(position, width, height),
            in_band: within_guard_band(position),
        }
    }
}

/// [`setup_triangle_order`] of a triangle whose vertices are already [`ScreenVertex`]es: the
/// same result.
#[inline]
pub fn setup_screen_triangle(
    triangle: &[ScreenVertex; 3],
    width: u32,
    height: u32,
    cull: CullMode,
) -> Option<(SetupTriangle, [usize; 3])> {
    // Setup's overflow bound holds for clipped triangles; anything else (a caller that did not
    // clip) is refused rather than allowed to overflow the fixed-point arithmetic.
    if !triangle.iter().all(|v| v.in_band) {
        return None;
    }
    let snapped = triangle.map(|v| v.snapped);
    let [p0, p1, p2] = snapped.map(|s| s.0);
    let area = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
    if area == 0 {
        return None;
    }
    // With y growing downwards, positive area means clockwise as seen on screen (and in y-up
    // NDC): a back face under the counter-clockwise-front convention.
    let front_facing = area < 0;
    match cull {
        CullMode::Back if !front_facing => return None,
        CullMode::Front if front_facing => return None,
        _ => {}
    }
    // Rasterization wants positive area: counter-clockwise triangles swap two vertices.
    let order = if area > 0 { [0, 1, 2] } else { [0, 2, 1] };
    let p = order.map(|i| snapped[i].0);
    let bounds = pixel_bounds(&p, width, height)?;
    Some((
        SetupTriangle {
            edges: [
                EdgeFunction::new(p[1], p[2]),
                EdgeFunction::new(p[2], p[0]),
                EdgeFunction::new(p[0], p[1]),
            ],
            bounds,
            inv_area: 1.0 / area.unsigned_abs() as f64,
            depth: order.map(|i| snapped[i].1),
            inv_w: order.map(|i| snapped[i].2),
            front_facing,
        },
        order,
    ))
}

/// The pixels whose centres lie in the bounding box of `p`, clamped to the viewport.
fn pixel_bounds(p: &[Subpixel; 3], width: u32, height: u32) -> Option<PixelRect> {
    let half = SUBPIXEL_ONE / 2;
    let first = |min: i64| (min - half + SUBPIXEL_ONE - 1).div_euclid(SUBPIXEL_ONE);
    let last = |max: i64| (max - half).div_euclid(SUBPIXEL_ONE);
    let x0 = first(p.iter().map(|q| q.x).min()?).max(0);
    let y0 = first(p.iter().map(|q| q.y).min()?).max(0);
    let x1 = (last(p.iter().map(|q| q.x).max()?) + 1).min(i64::from(width));
    let y1 = (last(p.iter().map(|q| q.y).max()?) + 1).min(i64::from(height));
    (x0 < x1 && y0 < y1).then_some(PixelRect {
        x0: x0 as u32,
        y0: y0 as u32,
        x1: x1 as u32,
        y1: y1 as u32,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn round_ties_even_is_the_library_rounding() {
        let specials = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.5,
            2.5,
            -2.5,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            16_777_215.0,
            1e30,
            -1e30,
            f32::MIN_POSITIVE,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let mut bits = 0x1234_5678u32;
        let randoms = (0..200_000).map(|_| {
            bits ^= bits << 13;
            bits ^= bits >> 17;
            bits ^= bits << 5;
            f32::from_bits(bits)
        });
        // Every half-integer and its neighbours up to 2^12.
        let halves = (0..8192).flat_map(|k| {
            let h = k as f32 * 0.5;
            [
                h,
                -h,
                f32::from_bits(h.to_bits() + 1),
                -f32::from_bits(h.to_bits() + 1),
            ]
        });
        for x in specials.into_iter().chain(randoms).chain(halves) {
            let (got, want) = (super::round_ties_even(x), x.round_ties_even());
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "{x:e}: {got:e} against {want:e}"
            );
        }
        assert!(super::round_ties_even(f32::NAN).is_nan());
    }

    use super::*;
    use glam::Vec4;

    fn screen_vertex(x: f32, y: f32, w: u32, h: u32) -> ClipVertex<()> {
        // Inverse of the viewport transform, so tests can speak in pixels.
        ClipVertex {
            position: Vec4::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0, 0.5, 1.0),
            varyings: (),
        }
    }

    fn covered(tri: &SetupTriangle, px: i64, py: i64) -> bool {
        tri.edges.iter().all(|e| e.at(px, py) >= 0)
    }

    #[test]
    fn counter_clockwise_in_ndc_is_front_facing() {
        let (w, h) = (16, 16);
        // Screen y grows down, so this triangle is counter-clockwise in NDC.
        let t = [
            screen_vertex(1., 9., w, h),
            screen_vertex(9., 9., w, h),
            screen_vertex(1., 1., w, h),
        ];
        let (s, _) = setup_triangle(&t, w, h, CullMode::None).expect("visible");
        assert!(s.front_facing);
        assert!(setup_triangle(&t, w, h, CullMode::Back).is_some());
        assert!(setup_triangle(&t, w, h, CullMode::Front).is_none());
        let flipped = [t[0], t[2], t[1]];
        assert!(setup_triangle(&flipped, w, h, CullMode::Back).is_none());
    }

    #[test]
    fn top_left_rule_on_axis_aligned_square() {
        // Two triangles covering the pixel square [2,6)×[2,6) exactly: 16 pixel centres, each
        // covered by exactly one triangle, including those on the shared diagonal.
        let (w, h) = (8, 8);
        let a = screen_vertex(2., 2., w, h);
        let b = screen_vertex(6., 2., w, h);
        let c = screen_vertex(6., 6., w, h);
        let d = screen_vertex(2., 6., w, h);
        let t1 = setup_triangle(&[a, d, c], w, h, CullMode::None)
            .expect("t1")
            .0;
        let t2 = setup_triangle(&[a, c, b], w, h, CullMode::None)
            .expect("t2")
            .0;
        for py in 0..8 {
            for px in 0..8 {
                let n = covered(&t1, px, py) as u32 + covered(&t2, px, py) as u32;
                let inside = (2..6).contains(&px) && (2..6).contains(&py);
                assert_eq!(n, inside as u32, "pixel ({px},{py})");
            }
        }
    }

    #[test]
    fn samples_on_top_and_left_edges_are_included() {
        // Edges through pixel centres: x = 2.5 (left edge) and y = 2.5 (top edge) include their
        // centres; x = 5.5 (right) and y = 5.5 (bottom) exclude theirs.
        let (w, h) = (8, 8);
        let a = screen_vertex(2.5, 2.5, w, h);
        let b = screen_vertex(5.5, 2.5, w, h);
        let c = screen_vertex(5.5, 5.5, w, h);
        let d = screen_vertex(2.5, 5.5, w, h);
        let t1 = setup_triangle(&[a, d, c], w, h, CullMode::None)
            .expect("t1")
            .0;
        let t2 = setup_triangle(&[a, c, b], w, h, CullMode::None)
            .expect("t2")
            .0;
        let n = |px, py| covered(&t1, px, py) as u32 + covered(&t2, px, py) as u32;
        assert_eq!(n(2, 2), 1);
        assert_eq!(n(2, 4), 1);
        assert_eq!(n(4, 2), 1);
        assert_eq!(n(5, 3), 0);
        assert_eq!(n(3, 5), 0);
    }

    #[test]
    fn offscreen_and_degenerate_triangles_are_dropped() {
        let (w, h) = (8, 8);
        let p = screen_vertex(1., 1., w, h);
        assert!(setup_triangle(&[p, p, p], w, h, CullMode::None).is_none());
        let t = [
            screen_vertex(-9., -9., w, h),
            screen_vertex(-5., -9., w, h),
            screen_vertex(-9., -5., w, h),
        ];
        assert!(setup_triangle(&t, w, h, CullMode::None).is_none());
    }
}
