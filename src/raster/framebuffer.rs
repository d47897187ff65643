//! The framebuffer (raster stage): f32 RGBA colour and f32 depth, stored tile by tile so that each
//! tile can be handed whole to one thread.
//!
//! Invariant: every pixel belongs to exactly one tile; tiles never share memory. The storage
//! layout depends on the tile size, the pixel values never do.
//!
//! Quantisation to 8 bits (the rounding a GPU comparison must match): each channel is clamped
//! to [0, 1], multiplied by 255, 0.5 added and the result truncated: `⌊255·clamp(c) + 0.5⌋`.
//! NaN becomes 0. No colour-space conversion is applied: values are written to the PNG as they
//! are (the thesis's OpenGL 2.1 framebuffer had no sRGB encoding either).

use super::RasterError;
use super::bin::TileGrid;
use super::setup::PixelRect;
use glam::Vec4;
use rayon::prelude::*;

/// The pixels of one tile.
#[derive(Clone, Debug)]
pub struct TileTarget {
    /// Which pixels this tile holds.
    pub rect: PixelRect,
    /// Row-major colour, `rect` width × height.
    pub colour: Vec<Vec4>,
    /// Row-major depth, `rect` width × height.
    pub depth: Vec<f32>,
}

impl TileTarget {
    /// Index of pixel (x, y) (image coordinates) inside this tile's arrays.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        ((y - self.rect.y0) * (self.rect.x1 - self.rect.x0) + (x - self.rect.x0)) as usize
    }
}

/// A tiled f32 RGBA + depth render target.
#[derive(Clone, Debug)]
pub struct Framebuffer {
    grid: TileGrid,
    tiles: Vec<TileTarget>,
}

/// Most pixels a framebuffer may hold (about 1.3 GiB of colour and depth).
pub const MAX_PIXELS: u64 = 1 << 26;

/// Checks an image size against the limits before anything is allocated; errors name the
/// parameter.
pub fn check_size(width: u32, height: u32) -> Result<(), RasterError> {
    use super::setup::MAX_DIMENSION;
    for (name, value) in [("width", width), ("height", height)] {
        if value == 0 || value > MAX_DIMENSION {
            return Err(RasterError::ImageSize {
                parameter: name,
                value: u64::from(value),
                limit: u64::from(MAX_DIMENSION),
            });
        }
    }
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_PIXELS {
        return Err(RasterError::ImageSize {
            parameter: "width×height",
            value: pixels,
            limit: MAX_PIXELS,
        });
    }
    Ok(())
}

impl Framebuffer {
    /// A framebuffer cleared to `colour` and depth 1.0. Fails, before allocating, on a zero or
    /// oversized image or a bad tile size.
    pub fn new(width: u32, height: u32, tile_size: u32, colour: Vec4) -> Result<Self, RasterError> {
        check_size(width, height)?;
        let grid = TileGrid::new(width, height, tile_size)?;
        // In parallel: a frame's 21 MB of colour and depth, filled one tile at a time, took
        // 4–5 ms at 1366×768 on one core, every frame.
        let tiles = (0..grid.tile_count())
            .into_par_iter()
            .map(|i| {
                let rect = grid.tile_rect(i);
                let n = ((rect.x1 - rect.x0) * (rect.y1 - rect.y0)) as usize;
                TileTarget {
                    rect,
                    colour: vec![colour; n],
                    depth: vec![1.0; n],
                }
            })
            .collect();
        Ok(Framebuffer { grid, tiles })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.grid.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.grid.height
    }

    /// The tile layout.
    pub fn grid(&self) -> &TileGrid {
        &self.grid
    }

    /// Sets every pixel to `colour` and every depth to `depth` (the tiles in parallel, as
    /// [`Framebuffer::new`] fills them).
    pub fn clear(&mut self, colour: Vec4, depth: f32) {
        self.tiles.par_iter_mut().for_each(|tile| {
            tile.colour.fill(colour);
            tile.depth.fill(depth);
        });
    }

    pub(crate) fn tiles_mut(&mut self) -> &mut [TileTarget] {
        &mut self.tiles
    }

    fn tile_of(&self, x: u32, y: u32) -> &TileTarget {
        &self.tiles[self.grid.tile_index_of(x, y)]
    }

    /// Colour of pixel (x, y); `None` outside the image.
    pub fn colour(&self, x: u32, y: u32) -> Option<Vec4> {
        (x < self.width() && y < self.height()).then(|| {
            let t = self.tile_of(x, y);
            t.colour[t.index(x, y)]
        })
    }

    /// Depth of pixel (x, y); `None` outside the image.
    pub fn depth(&self, x: u32, y: u32) -> Option<f32> {
        (x < self.width() && y < self.height()).then(|| {
            let t = self.tile_of(x, y);
            t.depth[t.index(x, y)]
        })
    }

    /// The image as row-major f32 RGBA, row 0 at the top.
    pub fn to_rgba_f32(&self) -> Vec<Vec4> {
        let (w, h) = (self.width() as usize, self.height() as usize);
        let mut out = vec![Vec4::ZERO; w * h];
        self.rows_into(&mut out, 1, |dst, src| dst.copy_from_slice(src));
        out
    }

    /// The image quantised to 8-bit RGBA, row-major, row 0 at the top.
    pub fn to_rgba8(&self) -> Vec<u8> {
        let (w, h) = (self.width() as usize, self.height() as usize);
        let mut out = vec![0u8; w * h * 4];
        self.rows_into(&mut out, 4, |dst, src| {
            for (d, c) in dst.chunks_exact_mut(4).zip(src) {
                d.copy_from_slice(&c.to_array().map(quantise_unorm8));
            }
        });
        out
    }

    /// Fills `out`, `per_pixel` elements a pixel, row-major, row 0 at the top, from each
    /// tile's part of each row: `convert(dst, src)` with `src` a tile's pixels on one row and
    /// `dst` their place in `out`. Rows in parallel (each element is written once, from its
    /// pixel alone): on one core this took 11 ms a 1366×768 frame.
    fn rows_into<T: Send>(
        &self,
        out: &mut [T],
        per_pixel: usize,
        convert: impl Fn(&mut [T], &[Vec4]) + Sync,
    ) {
        let g = &self.grid;
        let row_len = g.width as usize * per_pixel;
        out.par_chunks_mut(row_len)
            .enumerate()
            .for_each(|(y, row)| {
                let y = y as u32;
                let first = g.tile_index_of(0, y);
                for tile in &self.tiles[first..first + g.tiles_x as usize] {
                    let r = tile.rect;
                    let tw = (r.x1 - r.x0) as usize;
                    let start = (y - r.y0) as usize * tw;
                    let dst = &mut row[r.x0 as usize * per_pixel..r.x1 as usize * per_pixel];
                    convert(dst, &tile.colour[start..start + tw]);
                }
            });
    }
}

/// `⌊255·clamp(c, 0, 1) + 0.5⌋`, NaN → 0: the framebuffer's rounding rule.
#[inline]
pub fn quantise_unorm8(c: f32) -> u8 {
    // NaN stays NaN through the clamp and the float-to-integer cast saturates it to 0: no
    // branch, so that a row of pixels converts in vector registers.
    (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_rounds_half_up_and_clamps() {
        assert_eq!(quantise_unorm8(0.0), 0);
        assert_eq!(quantise_unorm8(1.0), 255);
        assert_eq!(quantise_unorm8(-3.0), 0);
        assert_eq!(quantise_unorm8(7.0), 255);
        assert_eq!(quantise_unorm8(f32::NAN), 0);
        assert_eq!(quantise_unorm8(0.5), 128);
        assert_eq!(quantise_unorm8(1.0 / 255.0), 1);
        for v in 0..=255u8 {
            assert_eq!(quantise_unorm8(f32::from(v) / 255.0), v);
        }
    }

    #[test]
    fn zero_and_huge_sizes_are_refused_before_allocation() {
        assert!(Framebuffer::new(0, 10, 16, Vec4::ZERO).is_err());
        assert!(Framebuffer::new(10, 0, 16, Vec4::ZERO).is_err());
        let err = Framebuffer::new(100_000, 10, 16, Vec4::ZERO).unwrap_err();
        assert!(err.to_string().contains("width"), "{err}");
        assert!(Framebuffer::new(16384, 16384, 64, Vec4::ZERO).is_err());
        assert!(Framebuffer::new(10, 10, 7, Vec4::ZERO).is_err());
    }

    #[test]
    fn readback_is_independent_of_tile_size() {
        for tile in [2, 4, 16, 64] {
            let mut fb = Framebuffer::new(13, 7, tile, Vec4::ZERO).expect("size");
            for t in fb.tiles_mut() {
                let r = t.rect;
                for y in r.y0..r.y1 {
                    for x in r.x0..r.x1 {
                        let i = t.index(x, y);
                        t.colour[i] = Vec4::new(x as f32, y as f32, 0.0, 1.0);
                    }
                }
            }
            let img = fb.to_rgba_f32();
            assert_eq!(img[3 * 13 + 5], Vec4::new(5.0, 3.0, 0.0, 1.0));
            assert_eq!(fb.colour(12, 6), Some(Vec4::new(12.0, 6.0, 0.0, 1.0)));
            assert_eq!(fb.colour(13, 6), None);
            // Every pixel in its place, as floats and as bytes (k/255 rounds back to k).
            for t in fb.tiles_mut() {
                for c in &mut t.colour {
                    *c /= 255.0;
                }
            }
            let (floats, bytes) = (fb.to_rgba_f32(), fb.to_rgba8());
            for y in 0..7u8 {
                for x in 0..13u8 {
                    let i = usize::from(y) * 13 + usize::from(x);
                    let expected = Vec4::new(f32::from(x), f32::from(y), 0.0, 1.0) / 255.0;
                    assert_eq!(floats[i], expected, "tile {tile}, ({x}, {y})");
                    assert_eq!(
                        bytes[4 * i..4 * i + 4],
                        [x, y, 0, 1],
                        "tile {tile}, ({x}, {y})"
                    );
                }
            }
        }
    }
}
