//! Tile rasterization: 2×2 quad traversal, perspective-correct interpolation, the depth test,
//! the fragment closure and blending, for one triangle inside one tile.
//!
//! Invariant: every pixel of a tile is written by exactly one thread, and a tile's triangles are
//! processed strictly in submission order, so the result is independent of the thread count and
//! of the tile size.
//!
//! Interpolation (what a GPU comparison must match): with exact integer edge values `E_i` and
//! `A = E_0 + E_1 + E_2` (twice the area), `λ_i = E_i·(1/A)` in f64, rounded to f32. Depth is
//! linear in screen space: `z = (λ0·z0 + λ1·z1) + λ2·z2`. Varyings are perspective-correct:
//! `p_i = λ_i·(1/w_i)`, `b_i = p_i·(1/((p0 + p1) + p2))`, `v = (b0·v0 + b1·v1) + b2·v2`. Helper
//! lanes (outside the triangle, shaded only for derivatives) whose extrapolated `Σp` is not
//! positive fall back to the affine weights `λ_i`.

use super::framebuffer::TileTarget;
use super::pipeline::{BlendMode, DepthCompare, DrawState};
use super::setup::SetupTriangle;
use super::varyings::Varyings;
use glam::Vec4;

/// What the fragment closure sees of one pixel.
///
/// Lanes of a quad are numbered 0 = (x, y), 1 = (x+1, y), 2 = (x, y+1), 3 = (x+1, y+1) with
/// (x, y) even. Derivatives are *coarse*, as most GPUs compute them: the same for all four
/// lanes, `ddx = f(lane 1) − f(lane 0)`, `ddy = f(lane 2) − f(lane 0)`.
pub struct Fragment<'q, V> {
    /// Pixel column.
    pub x: u32,
    /// Pixel row (0 at the top).
    pub y: u32,
    /// Interpolated NDC depth `z/w`.
    pub depth: f32,
    /// Whether the triangle runs counter-clockwise in NDC.
    pub front_facing: bool,
    lane: usize,
    quad: &'q [V; 4],
}

impl<'q, V: Varyings> Fragment<'q, V> {
    /// Builds a fragment by hand, for testing fragment closures without rasterizing.
    pub fn new(x: u32, y: u32, depth: f32, quad: &'q [V; 4], lane: usize) -> Self {
        Fragment {
            x,
            y,
            depth,
            front_facing: true,
            lane: lane.min(3),
            quad,
        }
    }

    /// The interpolated varyings at this pixel centre.
    #[inline]
    pub fn varyings(&self) -> &V {
        &self.quad[self.lane]
    }

    /// Coarse screen-space derivatives `(d/dx, d/dy)` of any function of the varyings.
    #[inline]
    pub fn derivatives<T: Varyings>(&self, f: impl Fn(&V) -> T) -> (T, T) {
        let origin = f(&self.quad[0]);
        (
            T::difference(&f(&self.quad[1]), &origin),
            T::difference(&f(&self.quad[2]), &origin),
        )
    }
}

/// Counters kept per tile and summed in tile order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Triangles handed to the rasterizer after clipping and culling.
    pub triangles: u64,
    /// Fragments that passed the depth test and ran the fragment closure.
    pub fragments_shaded: u64,
    /// Fragments the closure did not discard, written to the framebuffer.
    pub fragments_written: u64,
}

impl std::ops::AddAssign for RasterStats {
    fn add_assign(&mut self, o: Self) {
        self.triangles += o.triangles;
        self.fragments_shaded += o.fragments_shaded;
        self.fragments_written += o.fragments_written;
    }
}

/// Rasterizes one set-up triangle into the part of it that lies in `target`.
#[inline]
pub(crate) fn rasterize_triangle<V, F>(
    tri: &SetupTriangle,
    varyings: &[V; 3],
    state: &DrawState,
    shader: &F,
    target: &mut TileTarget,
    stats: &mut RasterStats,
) where
    V: Varyings,
    F: Fn(&Fragment<V>) -> Option<Vec4>,
{
    let Some(r) = tri.bounds.intersect(&target.rect) else {
        return;
    };
    let tile = target.rect;
    let [e0, e1, e2] = tri.edges;
    let lane_offsets: [(u32, u32); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];
    let mut quad = [varyings[0]; 4];
    for qy in ((r.y0 & !1)..r.y1).step_by(2) {
        let row = [
            [
                e0.at(0, i64::from(qy)),
                e1.at(0, i64::from(qy)),
                e2.at(0, i64::from(qy)),
            ],
            [
                e0.at(0, i64::from(qy) + 1),
                e1.at(0, i64::from(qy) + 1),
                e2.at(0, i64::from(qy) + 1),
            ],
        ];
        for qx in ((r.x0 & !1)..r.x1).step_by(2) {
            let mut edge = [[0i64; 3]; 4];
            let mut mask = 0u32;
            for (lane, &(dx, dy)) in lane_offsets.iter().enumerate() {
                let px = i64::from(qx + dx);
                let base = &row[dy as usize];
                edge[lane] = [
                    base[0] + e0.step_x * px,
                    base[1] + e1.step_x * px,
                    base[2] + e2.step_x * px,
                ];
                let inside_image = qx + dx < tile.x1 && qy + dy < tile.y1;
                if inside_image && (edge[lane][0] | edge[lane][1] | edge[lane][2]) >= 0 {
                    mask |= 1 << lane;
                }
            }
            if mask == 0 {
                continue;
            }
            let mut depth = [0.0f32; 4];
            for lane in 0..4 {
                let l = [
                    ((edge[lane][0] + e0.bias) as f64 * tri.inv_area) as f32,
                    ((edge[lane][1] + e1.bias) as f64 * tri.inv_area) as f32,
                    ((edge[lane][2] + e2.bias) as f64 * tri.inv_area) as f32,
                ];
                depth[lane] = (l[0] * tri.depth[0] + l[1] * tri.depth[1]) + l[2] * tri.depth[2];
                let p = [
                    l[0] * tri.inv_w[0],
                    l[1] * tri.inv_w[1],
                    l[2] * tri.inv_w[2],
                ];
                let sum = (p[0] + p[1]) + p[2];
                let b = if sum > 0.0 && sum.is_finite() {
                    let inv = 1.0 / sum;
                    [p[0] * inv, p[1] * inv, p[2] * inv]
                } else {
                    l
                };
                quad[lane] =
                    V::weighted_sum(&varyings[0], b[0], &varyings[1], b[1], &varyings[2], b[2]);
            }
            for (lane, &(dx, dy)) in lane_offsets.iter().enumerate() {
                if mask & (1 << lane) == 0 {
                    continue;
                }
                let (x, y) = (qx + dx, qy + dy);
                let index = target.index(x, y);
                let z = depth[lane];
                let stored = target.depth[index];
                let pass = match state.depth_compare {
                    DepthCompare::Always => true,
                    DepthCompare::Less => z < stored,
                    DepthCompare::LessEqual => z <= stored,
                };
                if !pass {
                    continue;
                }
                stats.fragments_shaded += 1;
                let fragment = Fragment {
                    x,
                    y,
                    depth: z,
                    front_facing: tri.front_facing,
                    lane,
                    quad: &quad,
                };
                let Some(colour) = shader(&fragment) else {
                    continue;
                };
                stats.fragments_written += 1;
                if state.depth_write {
                    target.depth[index] = z;
                }
                let dst = &mut target.colour[index];
                *dst = blend(state.blend, colour, *dst);
            }
        }
    }
}

/// The blend equation. `Alpha` is `src·a + dst·(1 − a)` on all four channels with `a` the
/// source alpha (OpenGL's `SRC_ALPHA, ONE_MINUS_SRC_ALPHA` applied to colour and alpha alike).
#[inline]
pub fn blend(mode: BlendMode, src: Vec4, dst: Vec4) -> Vec4 {
    match mode {
        BlendMode::Replace => src,
        BlendMode::Alpha => {
            let a = src.w;
            src * a + dst * (1.0 - a)
        }
        BlendMode::Add => src + dst,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_blend_matches_the_formula() {
        let src = Vec4::new(1.0, 0.5, 0.0, 0.25);
        let dst = Vec4::new(0.0, 0.5, 1.0, 1.0);
        let out = blend(BlendMode::Alpha, src, dst);
        let expect = [0.25, 0.5, 0.75, 0.8125];
        for (o, e) in out.to_array().iter().zip(expect) {
            assert!((o - e).abs() < 1e-7, "{out:?}");
        }
        assert_eq!(blend(BlendMode::Replace, src, dst), src);
    }

    #[test]
    fn coarse_derivatives_are_lane_differences() {
        let quad = [1.0f32, 3.0, 7.0, 20.0];
        for lane in 0..4 {
            let f = Fragment::new(0, 0, 0.5, &quad, lane);
            assert_eq!(f.derivatives(|v| *v * 2.0), (4.0, 12.0));
        }
        assert_eq!(*Fragment::new(0, 0, 0.5, &quad, 3).varyings(), 20.0);
    }
}
