//! Tile rasterization (raster stage): 2×2 quad traversal, perspective-correct interpolation, the
//! depth test, the fragment stage (one [`QuadShader`] call per quad) and blending, for one triangle
//! inside one tile.
//!
//! Invariant: every pixel of a tile is written by exactly one thread, and a tile's triangles are
//! processed strictly in submission order, so the result is independent of the thread count and
//! of the tile size.
//!
//! Interpolation (what a GPU comparison must match): with exact integer edge values `E_i` and
//! `A = E_0 + E_1 + E_2` (twice the area), at the quad's first pixel `λ_i = E_i·(1/A)` in f64,
//! rounded to f32; the other lanes add the per-pixel steps `s_x = (∂E_i/∂x·(1/A))` and
//! `s_y` (f64, rounded to f32 once per triangle): lane 1 `λ + s_x`, lane 2 `λ + s_y`, lane 3
//! `(λ + s_x) + s_y`. Depth is
//! linear in screen space: `z = (λ0·z0 + λ1·z1) + λ2·z2`. Varyings are perspective-correct:
//! `p_i = λ_i·(1/w_i)`, `b_i = p_i·(1/((p0 + p1) + p2))`, `v = (b0·v0 + b1·v1) + b2·v2`. Helper
//! lanes (outside the triangle, shaded only for derivatives) whose extrapolated `Σp` is not
//! positive fall back to the affine weights `λ_i`.

use super::framebuffer::TileTarget;
use super::setup::{EdgeFunction, PixelRect, SetupTriangle};
use super::state::{BlendMode, DepthCompare, DrawState};
use super::varyings::Varyings;
use glam::Vec4;

/// Where the lanes of a quad take their varyings from.
#[derive(Clone, Copy)]
enum LaneSource<'q, V> {
    /// Values given by hand ([`Fragment::new`]).
    Given(&'q [V; 4]),
    /// The triangle's corners and each lane's perspective-correct weights `b_i`: a lane is
    /// interpolated when the fragment stage asks for it, so helper lanes cost only what the
    /// derivatives read of them.
    Corners {
        corners: [&'q V; 3],
        weights: [[f32; 4]; 3],
    },
}

impl<'q, V: Varyings> LaneSource<'q, V> {
    /// Coarse derivatives of `f` (lane 1 − lane 0, lane 2 − lane 0).
    #[inline]
    fn derivatives<T: Varyings>(&self, f: impl Fn(&V) -> T) -> (T, T) {
        let origin = f(&self.lane(0));
        (
            T::difference(&f(&self.lane(1)), &origin),
            T::difference(&f(&self.lane(2)), &origin),
        )
    }

    #[inline(always)]
    fn lane(&self, lane: usize) -> V {
        match self {
            LaneSource::Given(values) => values[lane],
            LaneSource::Corners { corners, weights } => V::weighted_sum(
                corners[0],
                weights[0][lane],
                corners[1],
                weights[1][lane],
                corners[2],
                weights[2][lane],
            ),
        }
    }
}

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
    varyings: V,
    lanes: LaneSource<'q, V>,
}

impl<'q, V: Varyings> Fragment<'q, V> {
    /// Builds a fragment by hand, for testing fragment closures without rasterizing.
    pub fn new(x: u32, y: u32, depth: f32, quad: &'q [V; 4], lane: usize) -> Self {
        Fragment {
            x,
            y,
            depth,
            front_facing: true,
            varyings: quad[lane.min(3)],
            lanes: LaneSource::Given(quad),
        }
    }

    /// The interpolated varyings at this pixel centre.
    #[inline]
    pub fn varyings(&self) -> &V {
        &self.varyings
    }

    /// Coarse screen-space derivatives `(d/dx, d/dy)` of any function of the varyings.
    #[inline]
    pub fn derivatives<T: Varyings>(&self, f: impl Fn(&V) -> T) -> (T, T) {
        self.lanes.derivatives(f)
    }
}

/// One 2×2 quad as the fragment stage sees it: the four lanes' varyings (helper lanes outside
/// the triangle included, for derivatives), interpolated on request, and their depths.
pub struct Quad<'q, V> {
    /// Pixel column of lane 0 (even).
    pub x: u32,
    /// Pixel row of lane 0 (even).
    pub y: u32,
    /// Interpolated NDC depth of each lane.
    pub depth: [f32; 4],
    /// Whether the triangle runs counter-clockwise in NDC.
    pub front_facing: bool,
    corners: [&'q V; 3],
    weights: [[f32; 4]; 3],
}

impl<'q, V: Varyings> Quad<'q, V> {
    /// A quad of the triangle `corners` whose lane `l` has the perspective-correct weights
    /// `weights[k][l]` (corner `k`), for testing quad shaders without rasterizing. Like the
    /// rasterizer's, the corners must stay unchanged while a shader's
    /// [`QuadShader::Deferred`] that saw them lives: a shader may know a triangle by the
    /// addresses of its corners.
    pub fn new(
        x: u32,
        y: u32,
        depth: [f32; 4],
        corners: [&'q V; 3],
        weights: [[f32; 4]; 3],
    ) -> Self {
        Quad {
            x: x & !1,
            y: y & !1,
            depth,
            front_facing: true,
            corners,
            weights,
        }
    }

    /// The triangle's corners, which every lane is interpolated from.
    #[inline(always)]
    pub fn corners(&self) -> [&'q V; 3] {
        self.corners
    }

    /// Each lane's weights: `weights()[k][l]` weighs corner `k` in lane `l`.
    #[inline(always)]
    pub fn weights(&self) -> &[[f32; 4]; 3] {
        &self.weights
    }

    #[inline(always)]
    fn source(&self) -> LaneSource<'q, V> {
        LaneSource::Corners {
            corners: self.corners,
            weights: self.weights,
        }
    }

    /// The interpolated varyings of every lane.
    #[inline]
    pub fn varyings(&self) -> [V; 4] {
        std::array::from_fn(|lane| self.lane(lane))
    }

    /// The interpolated varyings of lane `lane` (0..4).
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> V {
        self.field(lane, |v| v)
    }

    /// One field of lane `lane`'s varyings, interpolated on its own: the same bits as that
    /// field of [`Quad::lane`], since interpolation weights each component alone, for a
    /// fraction of the work. `field` returns a reference so that it can only pick a part of
    /// the varyings, not compute from them.
    #[inline(always)]
    pub fn field<T: Varyings>(&self, lane: usize, field: impl Fn(&V) -> &T) -> T {
        let lane = lane.min(3);
        let (corners, weights) = (&self.corners, &self.weights);
        T::weighted_sum(
            field(corners[0]),
            weights[0][lane],
            field(corners[1]),
            weights[1][lane],
            field(corners[2]),
            weights[2][lane],
        )
    }

    /// Lane `lane` (0..4) as a single fragment.
    #[inline]
    pub fn fragment(&self, lane: usize) -> Fragment<'q, V> {
        let lane = lane.min(3);
        Fragment {
            x: self.x + (lane as u32 & 1),
            y: self.y + (lane as u32 >> 1),
            depth: self.depth[lane],
            front_facing: self.front_facing,
            varyings: self.lane(lane),
            lanes: self.source(),
        }
    }

    /// Coarse screen-space derivatives, the same for every lane (see [`Fragment::derivatives`]).
    #[inline]
    pub fn derivatives<T: Varyings>(&self, f: impl Fn(&V) -> T) -> (T, T) {
        self.source().derivatives(f)
    }
}

/// Where the colour of one shaded lane goes: a pixel of the tile that the triangle covers and
/// whose depth test passed, with the lane's depth. Only the rasterizer makes them, one per
/// shaded lane, and writing one consumes it (it is neither `Copy` nor `Clone`), so a shader
/// reaches no pixel the triangle does not cover and writes none twice, whether it writes
/// during [`QuadShader::shade_quad`] or keeps the slot until [`QuadShader::finish`].
#[derive(Debug)]
pub struct PixelSlot {
    /// Index into the tile's pixels.
    index: u32,
    depth: f32,
}

/// The slots of one quad's shaded lanes ([`PixelSlot`]), handed out once each.
#[derive(Debug)]
pub struct QuadSlots {
    /// Tile pixel index of lane 0.
    origin: u32,
    /// Tile width: lanes 2 and 3 are one row down.
    row: u32,
    depth: [f32; 4],
    /// Lanes whose slot has not been taken.
    open: u32,
}

impl QuadSlots {
    /// The lanes to shade (bit k = lane k is covered and passed the depth test), less those
    /// whose slot was taken.
    #[inline(always)]
    pub fn lanes(&self) -> u32 {
        self.open
    }

    /// Lane `lane`'s slot: `None` for a lane not shaded, or taken before.
    #[inline(always)]
    pub fn take(&mut self, lane: usize) -> Option<PixelSlot> {
        let bit = 1u32.checked_shl(lane as u32).unwrap_or(0);
        if self.open & bit == 0 {
            return None;
        }
        self.open &= !bit;
        let offset = (lane as u32 & 1) + (lane as u32 >> 1) * self.row;
        Some(PixelSlot {
            index: self.origin + offset,
            depth: self.depth[lane],
        })
    }

    /// Closes the lanes outside `mask` (bit k for lane k): their slots are never taken, so
    /// those lanes are discarded.
    #[inline(always)]
    pub fn keep_lanes(&mut self, mask: u32) {
        self.open &= mask;
    }

    /// The slots of all four lanes, when all four are open (the common quad, inside its
    /// triangle): [`QuadSlots::take`] of lanes 0 to 3 in one step. `None`, taking nothing,
    /// when any lane is not open.
    #[inline(always)]
    pub fn take_whole(&mut self) -> Option<[PixelSlot; 4]> {
        if self.open != 0b1111 {
            return None;
        }
        self.open = 0;
        let (origin, row) = (self.origin, self.row);
        let index = [origin, origin + 1, origin + row, origin + row + 1];
        Some(std::array::from_fn(|lane| PixelSlot {
            index: index[lane],
            depth: self.depth[lane],
        }))
    }
}

/// The fragment stage of a draw, one quad at a time, so a shader can share per-quad work (the
/// level of detail of coarse derivatives) and batch independent lanes through its costliest
/// terms.
///
/// A shader may also keep lanes of several quads in [`QuadShader::Deferred`] and shade them
/// together, across triangles. The rasterizer keeps every pixel's blend order: it calls
/// [`QuadShader::finish`] before it hands over a lane whose pixel it handed over since the last
/// `finish` (in a draw without depth writes it keeps one bit per pixel of the tile for this),
/// after each triangle of a draw that writes depth (a later triangle's depth test reads what
/// it wrote), and at the end of each tile's draw. The lanes held are therefore always distinct
/// pixels, and their order does not matter to the blend: in a closed mesh, where each pixel is
/// covered once per draw, the shader's batches run full across the triangles. The corners a
/// quad is interpolated from ([`Quad::corners`], the draw's vertex stage output) stay in place
/// and unchanged while a `Deferred` lives, so a shader may know a triangle by their addresses.
///
/// Contract: the colour given for a lane depends only on its quad and the lane — never on
/// which other lanes are shaded, nor on which lanes share a batch — so a quad shader gives the
/// same pixels as shading each lane alone.
///
/// Speed: the rasterizer runs a tile's quads in a copy compiled for the frame's
/// [`crate::simd::SimdLevel`]; mark `shade_quad`, `finish` and what they call hot
/// `#[inline(always)]` so that the fragment stage lands in that copy too, rather than in
/// baseline functions out of line. `#[inline]` alone, a large closure, or the `write` closure
/// passed on by value (through `&mut F`'s `FnMut`) can stay out of line: pass it on as
/// `&mut impl FnMut` (docs/performance.md, "Lit lanes in batches of 8").
pub trait QuadShader<V>: Send + Sync {
    /// What the shader keeps between quads (`()` for none), in the hot path's copy whose
    /// batches hold `BATCH` lanes ([`crate::simd::Kernel::run`]). One is made per tile and
    /// draw, and it is empty again after each [`QuadShader::finish`].
    type Deferred<const BATCH: usize>: Default;

    /// Shades the lanes of `slots` ([`QuadSlots::lanes`]) and writes the colour of each lane
    /// it keeps to the lane's slot, now or by [`QuadShader::finish`]; a lane never
    /// written is discarded.
    fn shade_quad<const BATCH: usize>(
        &self,
        deferred: &mut Self::Deferred<BATCH>,
        quad: &Quad<'_, V>,
        slots: QuadSlots,
        write: impl FnMut(PixelSlot, Vec4),
    );

    /// Writes what `deferred` still holds (see the trait's doc for when it is called).
    #[inline(always)]
    fn finish<const BATCH: usize>(
        &self,
        deferred: &mut Self::Deferred<BATCH>,
        write: impl FnMut(PixelSlot, Vec4),
    ) {
        let _ = (deferred, write);
    }
}

/// A per-fragment closure as a [`QuadShader`]: called once per lane in the mask.
pub struct PerFragment<F>(pub F);

impl<V, F> QuadShader<V> for PerFragment<F>
where
    V: Varyings,
    F: Fn(&Fragment<V>) -> Option<Vec4> + Send + Sync,
{
    type Deferred<const BATCH: usize> = ();

    #[inline(always)]
    fn shade_quad<const BATCH: usize>(
        &self,
        _: &mut (),
        quad: &Quad<'_, V>,
        mut slots: QuadSlots,
        mut write: impl FnMut(PixelSlot, Vec4),
    ) {
        for lane in 0..4 {
            if slots.lanes() & (1 << lane) != 0
                && let Some(colour) = (self.0)(&quad.fragment(lane))
                && let Some(slot) = slots.take(lane)
            {
                write(slot, colour);
            }
        }
    }
}

/// Counters kept per tile and summed in tile order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Triangles handed to the rasterizer after clipping and culling.
    pub triangles: u64,
    /// Fragments that passed the depth test and ran the fragment stage.
    pub fragments_shaded: u64,
    /// Fragments the fragment stage did not discard, written to the framebuffer.
    pub fragments_written: u64,
}

impl std::ops::AddAssign for RasterStats {
    fn add_assign(&mut self, o: Self) {
        self.triangles += o.triangles;
        self.fragments_shaded += o.fragments_shaded;
        self.fragments_written += o.fragments_written;
    }
}

/// The pixels of one tile that a draw without depth writes handed to its shader since the
/// shader's last [`QuadShader::finish`], one bit each: lanes it may still hold. Each tile row
/// starts a word, so a quad's two lanes in a row (its column is even, as tiles start on even
/// pixels) are two adjacent bits of one word.
pub(crate) struct HeldPixels {
    words: Vec<u64>,
    row_words: usize,
}

/// Whether a shader may hold lanes past a triangle: its [`QuadShader::Deferred`] can hold
/// anything and the draw does not write depth. Otherwise the rasterizer asks for the lanes at
/// the end of each triangle and keeps no [`HeldPixels`].
#[inline(always)]
pub(crate) fn holds_across_triangles<V, S: QuadShader<V>, const BATCH: usize>(
    writes_depth: bool,
) -> bool {
    size_of::<S::Deferred<BATCH>>() != 0 && !writes_depth
}

impl HeldPixels {
    /// None held, for a tile of `rect`'s size (no room at all for a draw whose shader does
    /// not hold lanes across triangles).
    pub(crate) fn new(rect: PixelRect, holds: bool) -> Self {
        if !holds {
            return HeldPixels {
                words: Vec::new(),
                row_words: 0,
            };
        }
        let row_words = (rect.x1 - rect.x0 + 1).div_ceil(64) as usize;
        // One row more: the lower lanes of a quad on a last, odd row (masked off) still index.
        let rows = (rect.y1 - rect.y0 + 1) as usize;
        HeldPixels {
            words: vec![0; row_words * rows],
            row_words,
        }
    }

    /// The word of the quad's upper lanes and the shift of its column within it; the lower
    /// lanes are `row_words` further. `column` and `row` are tile coordinates, `column` even.
    #[inline(always)]
    fn locate(&self, column: u32, row: u32) -> (usize, u32) {
        (
            row as usize * self.row_words + (column >> 6) as usize,
            column & 63,
        )
    }

    /// Whether any lane of `lanes` (bit k = lane k) of the quad at (`column`, `row`) is held.
    #[inline(always)]
    fn any(&self, column: u32, row: u32, lanes: u32) -> bool {
        let (word, shift) = self.locate(column, row);
        let upper = u64::from(lanes & 3) << shift;
        let lower = u64::from((lanes >> 2) & 3) << shift;
        (self.words[word] & upper) | (self.words[word + self.row_words] & lower) != 0
    }

    /// Marks the lanes of `lanes` of the quad at (`column`, `row`) held.
    #[inline(always)]
    fn mark(&mut self, column: u32, row: u32, lanes: u32) {
        let (word, shift) = self.locate(column, row);
        self.words[word] |= u64::from(lanes & 3) << shift;
        self.words[word + self.row_words] |= u64::from((lanes >> 2) & 3) << shift;
    }

    #[inline(always)]
    fn clear(&mut self) {
        self.words.fill(0);
    }
}

/// Ends one draw in one tile: the shader writes what it still holds.
#[inline(always)]
pub(crate) fn finish_tile<V, S, const BATCH: usize>(
    state: &DrawState,
    shader: &S,
    deferred: &mut S::Deferred<BATCH>,
    target: &mut TileTarget,
    stats: &mut RasterStats,
) where
    V: Varyings,
    S: QuadShader<V>,
{
    let mut written = 0u64;
    match (state.blend, state.depth_write) {
        (BlendMode::Alpha, false) => shader.finish(deferred, |slot, colour| {
            written += 1;
            write_slot::<ALPHA, NO>(state, target, slot, colour);
        }),
        _ => shader.finish(deferred, |slot, colour| {
            written += 1;
            write_slot::<DYNAMIC, DYNAMIC>(state, target, slot, colour);
        }),
    }
    stats.fragments_written += written;
}

/// Rasterizes one set-up triangle into the part of it that lies in `target`.
///
/// The common fixed-function states are compiled into their own copies of the quad loop, so the
/// per-fragment depth test, depth write and blend carry no run-time dispatch; every other state
/// takes the general copy. All copies compute the same values.
/// `#[inline(always)]`, as is the quad loop: the whole path lands in each [`crate::simd`] level's
/// copy of the tile replay.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the triangle, the draw, and the tile's state and counters
pub(crate) fn rasterize_triangle<V, S, const BATCH: usize>(
    tri: &SetupTriangle,
    varyings: [&V; 3],
    state: &DrawState,
    shader: &S,
    deferred: &mut S::Deferred<BATCH>,
    held: &mut HeldPixels,
    target: &mut TileTarget,
    stats: &mut RasterStats,
) where
    V: Varyings,
    S: QuadShader<V>,
{
    use {BlendMode as B, DepthCompare as D};
    match (state.depth_compare, state.blend, state.depth_write) {
        // Blended layers over an opaque base (shells, fins): test, no write.
        (D::LessEqual, B::Alpha, false) => rasterize_quads::<V, S, BATCH, LESS_EQUAL, ALPHA, NO>(
            tri, varyings, state, shader, deferred, held, target, stats,
        ),
        // Opaque geometry.
        (D::Less, B::Replace, true) => rasterize_quads::<V, S, BATCH, LESS, REPLACE, YES>(
            tri, varyings, state, shader, deferred, held, target, stats,
        ),
        _ => rasterize_quads::<V, S, BATCH, DYNAMIC, DYNAMIC, DYNAMIC>(
            tri, varyings, state, shader, deferred, held, target, stats,
        ),
    }
}

/// Const parameters of [`rasterize_quads`]: a fixed choice, or `DYNAMIC` (read the state).
const DYNAMIC: u8 = 0;
const LESS: u8 = 1;
const LESS_EQUAL: u8 = 2;
const ALPHA: u8 = 1;
const REPLACE: u8 = 2;
const NO: u8 = 1;
const YES: u8 = 2;

#[inline(always)]
#[allow(clippy::too_many_arguments)] // as `rasterize_triangle`
fn rasterize_quads<V, S, const BATCH: usize, const DEPTH: u8, const BLEND: u8, const WRITE: u8>(
    tri: &SetupTriangle,
    varyings: [&V; 3],
    state: &DrawState,
    shader: &S,
    deferred: &mut S::Deferred<BATCH>,
    held: &mut HeldPixels,
    target: &mut TileTarget,
    stats: &mut RasterStats,
) where
    V: Varyings,
    S: QuadShader<V>,
{
    let Some(r) = tri.bounds.intersect(&target.rect) else {
        return;
    };
    let tile = target.rect;
    let tile_width = (tile.x1 - tile.x0) as usize;
    let edges = tri.edges;
    // Barycentric steps per pixel, rounded to f32 once per triangle.
    let step_x = edges.map(|e| (e.step_x as f64 * tri.inv_area) as f32);
    let step_y = edges.map(|e| (e.step_y as f64 * tri.inv_area) as f32);
    let inv_w = tri.inv_w.map(Vec4::splat);
    let depth = tri.depth.map(Vec4::splat);
    let lowest = edges.map(|e| e.step_x.min(0) + e.step_y.min(0));
    let highest = edges.map(|e| e.step_x.max(0) + e.step_y.max(0));
    let x_start = r.x0 & !1;
    let (mut shaded, mut written) = (0u64, 0u64);
    let writes_depth = match WRITE {
        NO => false,
        YES => true,
        _ => state.depth_write,
    };
    // Without depth writes the shader may hold lanes past this triangle (`HeldPixels`).
    let tracks = holds_across_triangles::<V, S, BATCH>(writes_depth);
    for qy in ((r.y0 & !1)..r.y1).step_by(2) {
        // Lanes 2 and 3 fall off the image when it has an odd number of rows.
        let rows_mask = if qy + 1 < tile.y1 { 0b1111 } else { 0b0011 };
        let mut e = edges.map(|e| e.at(i64::from(x_start), i64::from(qy)));
        // The quads of this row that no single edge rejects (`e + highest < 0` below), from
        // each edge's value and step: the loop starts at the first and stops after the last,
        // so what it skips are exactly quads it would have rejected. Thin and slanted
        // triangles (fins, shells seen edge-on) leave most of their bounding box empty.
        let Some((first, last)) = quad_span(&e, &highest, &edges, (r.x1 - x_start).div_ceil(2))
        else {
            continue;
        };
        for k in 0..3 {
            e[k] += i64::from(first) * 2 * edges[k].step_x;
        }
        let mut qx = x_start + 2 * first;
        let x_end = r.x1.min(x_start + 2 * (last + 1));
        while qx < x_end {
            // The four lanes of edge k are e + {0, sx, sy, sx + sy}: their minimum and maximum
            // decide most quads without looking at single lanes.
            let all_in = (e[0] + lowest[0]) | (e[1] + lowest[1]) | (e[2] + lowest[2]) >= 0;
            let mut mask = if all_in {
                0b1111
            } else if e[0] + highest[0] < 0 || e[1] + highest[1] < 0 || e[2] + highest[2] < 0 {
                0
            } else {
                let lane_edges = |k: usize| {
                    let (ex, ey) = (edges[k].step_x, edges[k].step_y);
                    [e[k], e[k] + ex, e[k] + ey, e[k] + ex + ey]
                };
                let (a, b, c) = (lane_edges(0), lane_edges(1), lane_edges(2));
                let mut mask = 0u32;
                for lane in 0..4 {
                    mask |= u32::from((a[lane] | b[lane] | c[lane]) >= 0) << lane;
                }
                mask
            };
            let columns_mask = if qx + 1 < tile.x1 { 0b1111 } else { 0b0101 };
            mask &= rows_mask & columns_mask;
            let origin = e;
            for k in 0..3 {
                e[k] += 2 * edges[k].step_x;
            }
            if mask == 0 {
                qx += 2;
                continue;
            }
            // λ at the quad origin from the exact edge values, then f32 steps to the other lanes.
            let l = std::array::from_fn::<Vec4, 3, _>(|k| {
                let l0 = ((origin[k] + edges[k].bias) as f64 * tri.inv_area) as f32;
                let right = l0 + step_x[k];
                Vec4::new(l0, right, l0 + step_y[k], right + step_y[k])
            });
            let z = (l[0] * depth[0] + l[1] * depth[1]) + l[2] * depth[2];
            let p = [l[0] * inv_w[0], l[1] * inv_w[1], l[2] * inv_w[2]];
            let sum = (p[0] + p[1]) + p[2];
            let perspective = sum.cmpgt(Vec4::ZERO) & sum.is_finite_mask();
            let inv = Vec4::ONE / sum;
            let weights = [
                Vec4::select(perspective, p[0] * inv, l[0]).to_array(),
                Vec4::select(perspective, p[1] * inv, l[1]).to_array(),
                Vec4::select(perspective, p[2] * inv, l[2]).to_array(),
            ];
            let quad_index = (qy - tile.y0) as usize * tile_width + (qx - tile.x0) as usize;
            let compare = match DEPTH {
                LESS => DepthCompare::Less,
                LESS_EQUAL => DepthCompare::LessEqual,
                _ => state.depth_compare,
            };
            // The depth test of all lanes first: lanes are distinct pixels, so testing them
            // before any is written is the same as testing each just before shading it. The
            // four lanes in one compare: a lane past the tile's right or bottom edge (an odd
            // image size) reads lane 0's depth instead, in bounds, and the mask drops it.
            let right = usize::from(columns_mask == 0b1111);
            let below = if rows_mask == 0b1111 { tile_width } else { 0 };
            let stored = &target.depth;
            let stored = Vec4::new(
                stored[quad_index],
                stored[quad_index + right],
                stored[quad_index + below],
                stored[quad_index + below + right],
            );
            let passed = mask
                & match compare {
                    DepthCompare::Always => 0b1111,
                    DepthCompare::Less => z.cmplt(stored).bitmask(),
                    DepthCompare::LessEqual => z.cmple(stored).bitmask(),
                };
            let z = z.to_array();
            if passed == 0 {
                qx += 2;
                continue;
            }
            shaded += u64::from(passed.count_ones());
            let quad_view = Quad {
                x: qx,
                y: qy,
                depth: z,
                front_facing: tri.front_facing,
                corners: varyings,
                weights,
            };
            let slots = QuadSlots {
                origin: quad_index as u32,
                row: tile_width as u32,
                depth: z,
                open: passed,
            };
            if tracks {
                let (column, row) = (qx - tile.x0, qy - tile.y0);
                if held.any(column, row, passed) {
                    shader.finish(deferred, |slot, colour| {
                        written += 1;
                        write_slot::<BLEND, WRITE>(state, target, slot, colour);
                    });
                    held.clear();
                }
                held.mark(column, row, passed);
            }
            shader.shade_quad(deferred, &quad_view, slots, |slot, colour| {
                written += 1;
                write_slot::<BLEND, WRITE>(state, target, slot, colour);
            });
            qx += 2;
        }
    }
    if !tracks {
        shader.finish(deferred, |slot, colour| {
            written += 1;
            write_slot::<BLEND, WRITE>(state, target, slot, colour);
        });
    }
    stats.fragments_shaded += shaded;
    stats.fragments_written += written;
}

/// The quads `first..=last` of a row of `quads` quads that may be covered: quad `n` of the row
/// has edge values `e[k] + n·2·step_x` at its lane 0, and edge `k` rejects it when that plus
/// `highest[k]` (the largest lane offset) is negative. `None` when every quad of the row is
/// rejected. Exact integer arithmetic: the span is the set of quads no edge rejects.
#[inline(always)]
fn quad_span(
    e: &[i64; 3],
    highest: &[i64; 3],
    edges: &[EdgeFunction; 3],
    quads: u32,
) -> Option<(u32, u32)> {
    let (mut first, mut last) = (0i64, i64::from(quads) - 1);
    for k in 0..3 {
        let at_first = e[k] + highest[k];
        let step = 2 * edges[k].step_x;
        if step > 0 {
            if at_first < 0 {
                // The smallest n with at_first + n·step ≥ 0.
                first = first.max((-at_first + step - 1) / step);
            }
        } else if at_first < 0 {
            return None;
        } else if step < 0 {
            // The largest n with at_first + n·step ≥ 0.
            last = last.min(at_first / -step);
        }
    }
    (first <= last).then_some((first as u32, last as u32))
}

/// The depth write and the blend of one shaded lane, with [`rasterize_quads`]'s fixed states.
#[inline(always)]
fn write_slot<const BLEND: u8, const WRITE: u8>(
    state: &DrawState,
    target: &mut TileTarget,
    slot: PixelSlot,
    colour: Vec4,
) {
    let index = slot.index as usize;
    let write_depth = match WRITE {
        NO => false,
        YES => true,
        _ => state.depth_write,
    };
    if write_depth {
        target.depth[index] = slot.depth;
    }
    let dst = &mut target.colour[index];
    let mode = match BLEND {
        ALPHA => BlendMode::Alpha,
        REPLACE => BlendMode::Replace,
        _ => state.blend,
    };
    *dst = blend(mode, colour, *dst);
}

/// The blend equation. `Alpha` is `rgb = src.rgb·a + dst.rgb·(1 − a)` and
/// `alpha = a + dst.a·(1 − a)` with `a` the source alpha (OpenGL's
/// `glBlendFuncSeparate(SRC_ALPHA, ONE_MINUS_SRC_ALPHA, ONE, ONE_MINUS_SRC_ALPHA)`): colour is
/// mixed, coverage accumulates, so fur over an opaque background stays opaque.
#[inline]
pub fn blend(mode: BlendMode, src: Vec4, dst: Vec4) -> Vec4 {
    match mode {
        BlendMode::Replace => src,
        BlendMode::Alpha => {
            // One 4-lane multiply-add: the alpha lane's factor 1 keeps `a` exact, so each lane
            // is the formula's own two products and one sum.
            let a = src.w;
            src * Vec4::new(a, a, a, 1.0) + dst * (1.0 - a)
        }
        BlendMode::Add => src + dst,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_whole_quad_gives_the_slots_of_its_lanes_one_by_one() {
        let quad = |open| QuadSlots {
            origin: 130,
            row: 64,
            depth: [0.25, 0.5, 0.75, 1.0],
            open,
        };
        let mut whole = quad(0b1111);
        let taken = whole.take_whole().expect("all four lanes open");
        let mut one_by_one = quad(0b1111);
        for (lane, slot) in taken.iter().enumerate() {
            let single = one_by_one.take(lane).expect("open");
            assert_eq!((slot.index, slot.depth), (single.index, single.depth));
        }
        assert_eq!(whole.lanes(), 0);
        assert!(whole.take_whole().is_none());
        // A quad with a lane closed gives nothing whole and keeps its lanes.
        let mut partial = quad(0b1011);
        assert!(partial.take_whole().is_none());
        assert_eq!(partial.lanes(), 0b1011);
        // Lanes closed by mask are never taken; the others keep their slots.
        let mut kept = quad(0b1011);
        kept.keep_lanes(!0b0010);
        assert_eq!(kept.lanes(), 0b1001);
        assert!(kept.take(1).is_none());
        assert!(kept.take(2).is_none());
        let slot = kept.take(3).expect("lane 3 kept");
        assert_eq!((slot.index, slot.depth), (130 + 64 + 1, 1.0));
    }

    /// The span is exactly the quads no edge rejects, for random edges of every sign.
    #[test]
    fn quad_span_is_the_quads_no_edge_rejects() {
        let mut state = 0x9e37_79b9_u32;
        let mut next = |range: i64| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            i64::from(state) % (2 * range + 1) - range
        };
        for _ in 0..20_000 {
            let edges: [EdgeFunction; 3] = std::array::from_fn(|_| EdgeFunction {
                step_x: next(40),
                step_y: next(40),
                offset: 0,
                bias: 0,
            });
            let highest = edges.map(|e| e.step_x.max(0) + e.step_y.max(0));
            let e: [i64; 3] = std::array::from_fn(|_| next(3000));
            let quads = (next(20) + 21) as u32;
            let kept: Vec<u32> = (0..quads)
                .filter(|&n| {
                    (0..3).all(|k| e[k] + i64::from(n) * 2 * edges[k].step_x + highest[k] >= 0)
                })
                .collect();
            let want = kept.first().map(|&f| (f, *kept.last().unwrap_or(&f)));
            assert_eq!(
                quad_span(&e, &highest, &edges, quads),
                want,
                "{e:?} {edges:?}"
            );
        }
    }

    #[test]
    fn alpha_blend_matches_the_formula() {
        let src = Vec4::new(1.0, 0.5, 0.0, 0.25);
        let dst = Vec4::new(0.0, 0.5, 1.0, 1.0);
        let out = blend(BlendMode::Alpha, src, dst);
        let expect = [0.25, 0.5, 0.75, 1.0];
        for (o, e) in out.to_array().iter().zip(expect) {
            assert!((o - e).abs() < 1e-7, "{out:?}");
        }
        assert_eq!(blend(BlendMode::Replace, src, dst), src);
    }

    #[test]
    fn alpha_blend_is_the_per_channel_formula_bit_for_bit() {
        let mut x = 0x2545_f491u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32 * 1.5 - 0.25
        };
        for _ in 0..10_000 {
            let src = Vec4::new(next(), next(), next(), next());
            let dst = Vec4::new(next(), next(), next(), next());
            let a = src.w;
            let expect = [
                src.x * a + dst.x * (1.0 - a),
                src.y * a + dst.y * (1.0 - a),
                src.z * a + dst.z * (1.0 - a),
                a + dst.w * (1.0 - a),
            ];
            let got = blend(BlendMode::Alpha, src, dst).to_array();
            assert_eq!(
                got.map(f32::to_bits),
                expect.map(f32::to_bits),
                "{src} over {dst}"
            );
        }
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

    #[test]
    fn a_field_interpolated_alone_is_that_field_of_the_whole_lane() {
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            -1.5,
            1e-40,
            3e38,
            f32::INFINITY,
            f32::NAN,
        ];
        let mut bits = 0x9e37_79b9u32;
        let mut next = |k: usize| {
            bits ^= bits << 13;
            bits ^= bits >> 17;
            bits ^= bits << 5;
            if bits.is_multiple_of(7) {
                specials[k % specials.len()]
            } else {
                (bits as f32 / u32::MAX as f32 - 0.5) * 16.0
            }
        };
        for round in 0..2000 {
            let corners: [[f32; 6]; 3] =
                std::array::from_fn(|c| std::array::from_fn(|i| next(round + c + i)));
            let weights: [[f32; 4]; 3] =
                std::array::from_fn(|c| std::array::from_fn(|l| next(round * 3 + c + l)));
            let quad = Quad::new(
                0,
                0,
                [0.5; 4],
                [&corners[0], &corners[1], &corners[2]],
                weights,
            );
            let whole = quad.varyings();
            for i in 0..6 {
                let alone: [f32; 4] = std::array::from_fn(|lane| quad.field(lane, |v| &v[i]));
                for lane in 0..4 {
                    assert_eq!(
                        alone[lane].to_bits(),
                        whole[lane][i].to_bits(),
                        "component {i}, lane {lane}: {corners:?} {weights:?}"
                    );
                    assert_eq!(quad.lane(lane)[i].to_bits(), whole[lane][i].to_bits());
                }
            }
            // A lane as a fragment is the same lane.
            for (lane, values) in whole.iter().enumerate() {
                let fragment = quad.fragment(lane);
                assert_eq!(
                    fragment.varyings().map(f32::to_bits),
                    values.map(f32::to_bits)
                );
            }
        }
    }
}
