//! The draw-call API (raster stage): a caller supplies vertices, triangles, a vertex closure, a
//! fragment closure and per-draw state; a [`Frame`] collects draws and runs them tile by tile.
//!
//! Setup (vertex stage, clipping, triangle setup, binning) runs when a draw is submitted;
//! rasterization runs at [`Frame::flush`] or [`Frame::finish`]. Invariant: every tile replays the
//! pending draws in submission order, each draw's triangles in index order, on one thread — so
//! flushing early, the thread count and the tile size never change the image.

use super::RasterError;
use super::bin::TileGrid;
use super::clip::{ClipVertex, clip_triangle, inside_clip_volume};
use super::framebuffer::{Framebuffer, TileTarget};
use super::setup::{ScreenVertex, SetupTriangle, setup_screen_triangle, setup_triangle_order};
pub use super::state::{BlendMode, DepthCompare, DrawState};
use super::tile::{
    Fragment, HeldPixels, PerFragment, QuadShader, RasterStats, finish_tile,
    holds_across_triangles, rasterize_triangle,
};
use super::varyings::Varyings;
use crate::simd::{self, Kernel, SimdLevel};
use glam::Vec4;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// A submitted draw with its closures erased, as the tile loop sees it.
trait TileDraw: Send + Sync {
    /// Replays the draw's triangles over one tile, with the hot path compiled for `level`.
    fn rasterize_tile(
        &self,
        tile: usize,
        target: &mut TileTarget,
        stats: &mut RasterStats,
        level: SimdLevel,
    );
    fn triangle_count(&self) -> usize;
}

/// A run of consecutive triangles of a draw, set up and binned by one task.
///
/// A triangle's corners are kept as vertex indices, not copies of their varyings: a copy was
/// 3 × the varyings' size per kept triangle (336 bytes for the fur's), written once and read
/// once per tile, and first touches of that fresh memory (page faults, zeroed pages, copies)
/// took about a tenth of a frame of a 100,000-triangle torus with 30 shells.
struct SetUpChunk<V> {
    triangles: Vec<SetupTriangle>,
    /// Per triangle, its corners in set-up order: an index into the draw's vertices, or
    /// `CLIPPED | k` for `clipped[k]`.
    corners: Vec<[u32; 3]>,
    /// The varyings of the vertices that clipping made (three per clipped triangle; rare).
    clipped: Vec<V>,
    /// Per tile, the indices into `triangles` that touch it, ascending.
    bins: Vec<Vec<u32>>,
}

/// The flag of a corner index naming a vertex made by clipping ([`SetUpChunk::clipped`]).
const CLIPPED: u32 = 1 << 31;

/// Most vertices one draw may have: a corner index must leave `CLIPPED` free.
pub const MAX_DRAW_VERTICES: usize = CLIPPED as usize;

impl<V> SetUpChunk<V> {
    /// The varyings of triangle `t`'s corners, `vertices` being the draw's.
    #[inline(always)]
    fn corners<'c>(&'c self, t: usize, vertices: &'c [ClipVertex<V>]) -> [&'c V; 3] {
        self.corners[t].map(|i| {
            if i & CLIPPED == 0 {
                &vertices[i as usize].varyings
            } else {
                &self.clipped[(i & !CLIPPED) as usize]
            }
        })
    }
}

struct DrawCall<V, S> {
    state: DrawState,
    /// The draw's vertices after the vertex stage, which the corners index.
    vertices: Vec<ClipVertex<V>>,
    /// In triangle order: a tile replays chunk 0's triangles, then chunk 1's, …, which is the
    /// draw's triangle order whatever the chunking.
    chunks: Vec<SetUpChunk<V>>,
    shader: S,
}

impl<V, S> TileDraw for DrawCall<V, S>
where
    V: Varyings,
    S: QuadShader<V>,
{
    fn rasterize_tile(
        &self,
        tile: usize,
        target: &mut TileTarget,
        stats: &mut RasterStats,
        level: SimdLevel,
    ) {
        // The one run-time choice of instruction set: once per tile and draw.
        simd::dispatch(
            level,
            TileReplay {
                draw: self,
                tile,
                target,
                stats,
            },
        );
    }

    fn triangle_count(&self) -> usize {
        self.chunks.iter().map(|c| c.triangles.len()).sum()
    }
}

/// One draw's triangles replayed over one tile: the hot path (quad traversal, depth test,
/// fragment stage, blend), inlined whole into each [`simd`] level's copy.
struct TileReplay<'r, V, S> {
    draw: &'r DrawCall<V, S>,
    tile: usize,
    target: &'r mut TileTarget,
    stats: &'r mut RasterStats,
}

impl<V, S> Kernel for TileReplay<'_, V, S>
where
    V: Varyings,
    S: QuadShader<V>,
{
    type Output = ();

    #[inline(always)]
    fn run<const BATCH: usize>(self) {
        let TileReplay {
            draw,
            tile,
            target,
            stats,
        } = self;
        let mut deferred = S::Deferred::<BATCH>::default();
        let holds = holds_across_triangles::<V, S, BATCH>(draw.state.depth_write);
        let mut held = HeldPixels::new(target.rect, holds);
        for chunk in &draw.chunks {
            for &t in &chunk.bins[tile] {
                let t = t as usize;
                stats.triangles += 1;
                rasterize_triangle(
                    &chunk.triangles[t],
                    chunk.corners(t, &draw.vertices),
                    &draw.state,
                    &draw.shader,
                    &mut deferred,
                    &mut held,
                    target,
                    stats,
                );
            }
        }
        finish_tile(&draw.state, &draw.shader, &mut deferred, target, stats);
    }
}

/// Pending set-up triangles plus the pending draws' vertices (which their corners index) above
/// which a draw flushes the frame, bounding memory. Flushing never changes the image.
const AUTO_FLUSH_ENTRIES: usize = 1 << 20;

/// A draw's triangles are set up and binned in up to this many parallel tasks, of at least
/// [`MIN_SETUP_CHUNK`] triangles each...
const SETUP_TASKS: usize = 8;
const MIN_SETUP_CHUNK: usize = 1024;
/// ...and fewer with many tiles: each task keeps a list per tile, so tasks × tiles stays under
/// this, or one task when the tiles alone exceed it (small tiles on a large image).
const TASK_TILE_LISTS: usize = 1 << 16;

/// One frame being drawn into a framebuffer.
pub struct Frame<'fb, 'a> {
    framebuffer: &'fb mut Framebuffer,
    pending: Vec<Box<dyn TileDraw + 'a>>,
    /// Set-up triangles and vertices of the pending draws.
    pending_entries: usize,
    stats: RasterStats,
    simd: SimdLevel,
    /// Once set, tiles not yet rasterized are skipped (see [`Frame::set_cancel`]).
    cancel: Option<&'a AtomicBool>,
}

impl<'fb, 'a> Frame<'fb, 'a> {
    /// Starts a frame; the framebuffer keeps its contents (clear it first if needed). It runs at
    /// [`SimdLevel::active`].
    pub fn new(framebuffer: &'fb mut Framebuffer) -> Self {
        Frame {
            framebuffer,
            pending: Vec::new(),
            pending_entries: 0,
            stats: RasterStats::default(),
            simd: SimdLevel::active(),
            cancel: None,
        }
    }

    /// Lets another thread stop this frame early: once `cancel` is set, every tile-draw not
    /// yet begun is skipped, so the framebuffer is left unfinished (the caller must discard
    /// it, see [`Frame::cancelled`]). While it stays clear, nothing changes: the flag is read,
    /// never written, and the image is the same bytes.
    pub fn set_cancel(&mut self, cancel: &'a AtomicBool) {
        self.cancel = Some(cancel);
    }

    /// Whether the flag of [`Frame::set_cancel`] was set: the framebuffer is then unfinished.
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Runs the rasterization of this frame at `level`, capped by what the CPU has
    /// ([`SimdLevel::capped`]). Every level gives the same image; this chooses the speed.
    pub fn set_simd_level(&mut self, level: SimdLevel) {
        self.simd = level.capped();
    }

    /// The level this frame rasterizes at.
    pub fn simd_level(&self) -> SimdLevel {
        self.simd
    }

    /// The framebuffer's tile layout.
    pub fn grid(&self) -> TileGrid {
        *self.framebuffer.grid()
    }

    /// Submits a draw: runs `vertex` on every vertex (in parallel), clips and sets up every
    /// triangle and bins it. `fragment` returns the colour of a pixel, or `None` to discard it.
    /// Fails, drawing nothing, when an index is out of range.
    pub fn draw<I, V, VS, FS>(
        &mut self,
        vertices: &[I],
        triangles: &[[u32; 3]],
        state: DrawState,
        vertex: VS,
        fragment: FS,
    ) -> Result<(), RasterError>
    where
        I: Sync,
        V: Varyings + 'a,
        VS: Fn(&I) -> ClipVertex<V> + Sync,
        FS: Fn(&Fragment<V>) -> Option<Vec4> + Send + Sync + 'a,
    {
        self.draw_quads(vertices, triangles, state, vertex, PerFragment(fragment))
    }

    /// [`Frame::draw`] with a fragment stage that shades a quad at a time.
    pub fn draw_quads<I, V, VS, S>(
        &mut self,
        vertices: &[I],
        triangles: &[[u32; 3]],
        state: DrawState,
        vertex: VS,
        shader: S,
    ) -> Result<(), RasterError>
    where
        I: Sync,
        V: Varyings + 'a,
        VS: Fn(&I) -> ClipVertex<V> + Sync,
        S: QuadShader<V> + 'a,
    {
        if let Some((triangle, &index)) = triangles.iter().enumerate().find_map(|(t, tri)| {
            tri.iter()
                .find(|&&i| i as usize >= vertices.len())
                .map(|i| (t, i))
        }) {
            return Err(RasterError::IndexOutOfRange {
                triangle,
                index,
                vertex_count: vertices.len(),
            });
        }
        if vertices.len() > MAX_DRAW_VERTICES {
            return Err(RasterError::TooManyVertices {
                count: vertices.len(),
                limit: MAX_DRAW_VERTICES,
            });
        }
        let shaded: Vec<ClipVertex<V>> =
            vertices.par_iter().with_min_len(256).map(&vertex).collect();
        let grid = self.grid();
        let (width, height) = (grid.width, grid.height);
        // Each vertex snapped once, and whether it is inside the clip volume: a triangle of
        // three inside is set up from these alone, without copying its vertices.
        let screen: Vec<(ScreenVertex, bool)> = shaded
            .par_iter()
            .with_min_len(256)
            .map(|v| {
                (
                    ScreenVertex::new(v.position, width, height),
                    inside_clip_volume(v.position),
                )
            })
            .collect();
        let tasks = SETUP_TASKS.min(TASK_TILE_LISTS / grid.tile_count()).max(1);
        let chunk_len = triangles.len().div_ceil(tasks).max(MIN_SETUP_CHUNK);
        let chunks: Vec<SetUpChunk<V>> = triangles
            .par_chunks(chunk_len)
            .map(|chunk| {
                // Room for every triangle of the chunk while it is set up (one draw's worth at
                // a time, which the memory estimate of `crate::limits` counts), trimmed below
                // to what is kept: most of a dense mesh's triangles are culled, clipped away or
                // cover no sample, and room kept for every submitted triangle of every pending
                // draw was address space far above the estimate (an abort under `ulimit -v`).
                let mut set_up = SetUpChunk {
                    triangles: Vec::with_capacity(chunk.len()),
                    corners: Vec::with_capacity(chunk.len()),
                    clipped: Vec::new(),
                    bins: vec![Vec::new(); grid.tile_count()],
                };
                let keep = |set_up: &mut SetUpChunk<V>, tri: SetupTriangle, corners| {
                    grid.bin(&mut set_up.bins, set_up.triangles.len() as u32, &tri.bounds);
                    set_up.triangles.push(tri);
                    set_up.corners.push(corners);
                };
                for &indices in chunk {
                    let on_screen = indices.map(|i| screen[i as usize]);
                    if on_screen.iter().all(|&(_, inside)| inside) {
                        let corners = on_screen.map(|(vertex, _)| vertex);
                        if let Some((tri, order)) =
                            setup_screen_triangle(&corners, width, height, state.cull)
                        {
                            keep(&mut set_up, tri, order.map(|k| indices[k]));
                        }
                        continue;
                    }
                    let clip = indices.map(|i| shaded[i as usize]);
                    clip_triangle(clip, |clipped| {
                        if let Some((tri, order)) =
                            setup_triangle_order(&clipped, width, height, state.cull)
                        {
                            let first = set_up.clipped.len();
                            set_up.clipped.extend(order.map(|k| clipped[k].varyings));
                            let corners = [0, 1, 2].map(|k| CLIPPED | (first + k) as u32);
                            keep(&mut set_up, tri, corners);
                        }
                    });
                }
                set_up.triangles.shrink_to_fit();
                set_up.corners.shrink_to_fit();
                set_up.clipped.shrink_to_fit();
                for bin in &mut set_up.bins {
                    bin.shrink_to_fit();
                }
                set_up
            })
            .collect();
        let count: usize = chunks.iter().map(|c| c.triangles.len()).sum();
        let shaded_len = shaded.len();
        self.pending_entries += count + shaded_len;
        self.pending.push(Box::new(DrawCall {
            state,
            vertices: shaded,
            chunks,
            shader,
        }));
        if self.pending_entries >= AUTO_FLUSH_ENTRIES {
            self.flush();
        }
        Ok(())
    }

    /// Rasterizes every pending draw, tiles in parallel.
    pub fn flush(&mut self) {
        if self.pending.is_empty() {
            return;
        }
        let draws = &self.pending;
        let level = self.simd;
        let cancel = self.cancel;
        let per_tile: Vec<RasterStats> = self
            .framebuffer
            .tiles_mut()
            .par_iter_mut()
            .enumerate()
            .map(|(i, target)| {
                let mut stats = RasterStats::default();
                for draw in draws {
                    if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                        break;
                    }
                    draw.rasterize_tile(i, target, &mut stats, level);
                }
                stats
            })
            .collect();
        for s in per_tile {
            self.stats += s;
        }
        self.pending.clear();
        self.pending_entries = 0;
    }

    /// Triangles submitted and set up but not yet rasterized.
    pub fn pending_triangles(&self) -> usize {
        self.pending.iter().map(|d| d.triangle_count()).sum()
    }

    /// Rasterizes what is pending and returns the frame's counters.
    pub fn finish(mut self) -> RasterStats {
        self.flush();
        self.stats
    }
}
