//! Binning (raster stage): the screen is cut into square tiles and every triangle is listed in each
//! tile its bounding box touches, in submission order.
//!
//! Invariant: a tile's list holds triangle indices in increasing order, so rasterizing a tile
//! replays the draw exactly as submitted. The default tile is 64×64 pixels (llvmpipe's
//! `TILE_ORDER 6`); any even size from 2 to 1024 gives the same image.

use super::RasterError;
use super::setup::PixelRect;

/// Default tile side in pixels.
pub const DEFAULT_TILE_SIZE: u32 = 64;
/// Largest tile side accepted.
pub const MAX_TILE_SIZE: u32 = 1024;

/// How the screen is divided into tiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileGrid {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Tile side in pixels (even, so 2×2 quads never straddle tiles).
    pub tile_size: u32,
    /// Tiles per row.
    pub tiles_x: u32,
    /// Tiles per column.
    pub tiles_y: u32,
}

impl TileGrid {
    /// A grid over a `width`×`height` image. The tile size must be even, 2..=1024.
    pub fn new(width: u32, height: u32, tile_size: u32) -> Result<Self, RasterError> {
        if !(2..=MAX_TILE_SIZE).contains(&tile_size) || !tile_size.is_multiple_of(2) {
            return Err(RasterError::TileSize(tile_size));
        }
        Ok(TileGrid {
            width,
            height,
            tile_size,
            tiles_x: width.div_ceil(tile_size),
            tiles_y: height.div_ceil(tile_size),
        })
    }

    /// Number of tiles.
    pub fn tile_count(&self) -> usize {
        (self.tiles_x * self.tiles_y) as usize
    }

    /// The pixels of tile `index` (row-major tile order), clamped to the image.
    pub fn tile_rect(&self, index: usize) -> PixelRect {
        let tx = index as u32 % self.tiles_x;
        let ty = index as u32 / self.tiles_x;
        PixelRect {
            x0: tx * self.tile_size,
            y0: ty * self.tile_size,
            x1: ((tx + 1) * self.tile_size).min(self.width),
            y1: ((ty + 1) * self.tile_size).min(self.height),
        }
    }

    /// The tile holding pixel (x, y).
    pub fn tile_index_of(&self, x: u32, y: u32) -> usize {
        ((y / self.tile_size) * self.tiles_x + x / self.tile_size) as usize
    }

    /// Appends `triangle` to the list of every tile that `bounds` touches.
    pub fn bin(&self, bins: &mut [Vec<u32>], triangle: u32, bounds: &PixelRect) {
        let tx0 = bounds.x0 / self.tile_size;
        let ty0 = bounds.y0 / self.tile_size;
        let tx1 = (bounds.x1 - 1) / self.tile_size;
        let ty1 = (bounds.y1 - 1) / self.tile_size;
        for ty in ty0..=ty1 {
            for tx in tx0..=tx1 {
                bins[(ty * self.tiles_x + tx) as usize].push(triangle);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once() {
        let grid = TileGrid::new(37, 21, 8).expect("grid");
        let mut hits = vec![0u32; 37 * 21];
        for i in 0..grid.tile_count() {
            let r = grid.tile_rect(i);
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    hits[(y * 37 + x) as usize] += 1;
                    assert_eq!(grid.tile_index_of(x, y), i);
                }
            }
        }
        assert!(hits.iter().all(|&h| h == 1));
    }

    #[test]
    fn odd_or_absurd_tile_sizes_are_refused() {
        for t in [0, 1, 3, 2048] {
            assert!(TileGrid::new(10, 10, t).is_err(), "{t}");
        }
    }

    #[test]
    fn binning_keeps_submission_order() {
        let grid = TileGrid::new(32, 32, 16).expect("grid");
        let mut bins = vec![Vec::new(); grid.tile_count()];
        let all = PixelRect {
            x0: 0,
            y0: 0,
            x1: 32,
            y1: 32,
        };
        let corner = PixelRect {
            x0: 20,
            y0: 20,
            x1: 21,
            y1: 21,
        };
        grid.bin(&mut bins, 0, &all);
        grid.bin(&mut bins, 1, &corner);
        grid.bin(&mut bins, 2, &all);
        assert_eq!(bins[3], vec![0, 1, 2]);
        assert_eq!(bins[0], vec![0, 2]);
    }
}
