//! 8-bit RGBA images of baked fur, the f32 → u8 quantisation, the tangent encoding, and the
//! supersampled bake grid with its box downsample (thesis 3.1.3 anti-aliasing; fur bake).
//!
//! Conventions (stable; a GPU backend must match them):
//! - texels are row-major, row 0 first (`v = 0`), `texels[y · width + x]`;
//! - quantisation `unorm8(x) = floor(clamp(x, 0, 1) · 255 + 0.5)`;
//! - a tangent `t` is stored as `unorm8(t · 0.5 + 0.5)` per component, decoded by
//!   [`tangent_from_rgb8`];
//! - alpha is straight (not premultiplied); colours are linear RGB.

use glam::Vec3;

/// An 8-bit RGBA image, row-major from row 0 (`v = 0`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rgba8Image {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width · height` texels, `texels[y · width + x]`.
    pub texels: Vec<[u8; 4]>,
}

impl Rgba8Image {
    /// A `width × height` image filled with `fill`.
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Self {
        Self {
            width,
            height,
            texels: vec![fill; width as usize * height as usize],
        }
    }

    /// The texel at column `x`, row `y`, or `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.texels
            .get(y as usize * self.width as usize + x as usize)
            .copied()
    }

    /// The raw bytes, RGBA per texel, rows in order (row 0 first).
    pub fn as_bytes(&self) -> Vec<u8> {
        self.texels.iter().flatten().copied().collect()
    }
}

/// Quantises `x` to 8 bits: `floor(clamp(x, 0, 1) · 255 + 0.5)`; NaN gives 0.
pub fn unorm8(x: f32) -> u8 {
    if x.is_nan() {
        return 0;
    }
    libm::floorf(x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Encodes a unit tangent as RGB: `unorm8(t · 0.5 + 0.5)` per component.
pub fn tangent_to_rgb8(t: Vec3) -> [u8; 3] {
    let e = t * 0.5 + Vec3::splat(0.5);
    [unorm8(e.x), unorm8(e.y), unorm8(e.z)]
}

/// Decodes an RGB tangent: `c / 255 · 2 − 1` per component, then normalised (`+z` if zero).
pub fn tangent_from_rgb8(rgb: [u8; 3]) -> Vec3 {
    let d = |c: u8| c as f32 / 255.0 * 2.0 - 1.0;
    Vec3::new(d(rgb[0]), d(rgb[1]), d(rgb[2])).normalize_or(Vec3::Z)
}

/// Tangent stored in texels no strand covers when no neighbour can lend one: straight up.
pub const EMPTY_TANGENT: Vec3 = Vec3::Z;
/// Colour stored in texels no strand covers when no neighbour can lend one: black.
pub const EMPTY_COLOUR: Vec3 = Vec3::ZERO;

/// Sentinel "no strand" in a [`SampleGrid`].
pub(crate) const NO_STRAND: u32 = u32::MAX;

/// One subsample of the bake grid: which strand covers it last, its tangent, and (fins) depth.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sample {
    pub strand: u32,
    pub tangent: Vec3,
    pub depth: f32,
}

/// The supersampled bake grid, row-major like the images.
pub(crate) struct SampleGrid {
    pub width: usize,
    pub height: usize,
    pub samples: Vec<Sample>,
}

impl SampleGrid {
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            samples: vec![
                Sample {
                    strand: NO_STRAND,
                    tangent: EMPTY_TANGENT,
                    depth: f32::INFINITY,
                };
                width * height
            ],
        }
    }
}

/// Box-downsamples a grid by `factor` into colour and tangent images.
///
/// Per output texel: the colour and the tangent are averages over the covered subsamples only
/// (the tangent renormalised), and `alpha = covered fraction · weight(row)`. Texels with no
/// covered subsample are then *dilated*: they take the average colour and tangent of their
/// covered 8-neighbours (wrapping in x, and in y when `wrap_y`), else [`EMPTY_COLOUR`] and
/// [`EMPTY_TANGENT`]; their alpha stays 0. This keeps bilinear filtering at strand edges from
/// bleeding black or a wrong tangent.
pub(crate) fn downsample(
    grid: &SampleGrid,
    factor: usize,
    colours: &[Vec3],
    weight: impl Fn(usize) -> f32,
    wrap_y: bool,
) -> (Rgba8Image, Rgba8Image) {
    let w = grid.width / factor;
    let h = grid.height / factor;
    let n = (factor * factor) as f32;
    // Straight colour, tangent, alpha per texel; alpha 0 means nothing covered.
    let mut col = vec![Vec3::ZERO; w * h];
    let mut tan = vec![Vec3::ZERO; w * h];
    let mut alpha = vec![0.0f32; w * h];
    let mut is_covered = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut c_sum = Vec3::ZERO;
            let mut t_sum = Vec3::ZERO;
            let mut covered = 0usize;
            for sy in 0..factor {
                let row = (y * factor + sy) * grid.width;
                for sx in 0..factor {
                    let s = &grid.samples[row + x * factor + sx];
                    if let Some(c) = colours.get(s.strand as usize) {
                        c_sum += *c;
                        t_sum += s.tangent;
                        covered += 1;
                    }
                }
            }
            if covered > 0 {
                let i = y * w + x;
                col[i] = c_sum / covered as f32;
                tan[i] = t_sum.normalize_or(EMPTY_TANGENT);
                alpha[i] = covered as f32 / n * weight(y);
                is_covered[i] = true;
            }
        }
    }
    let covered = |i: usize| is_covered[i];
    let mut colour_img = Rgba8Image::new(w as u32, h as u32, [0; 4]);
    let mut tangent_img = Rgba8Image::new(w as u32, h as u32, [0; 4]);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (c, t) = if covered(i) {
                (col[i], tan[i])
            } else {
                let mut c_sum = Vec3::ZERO;
                let mut t_sum = Vec3::ZERO;
                let mut k = 0usize;
                for dy in [-1i64, 0, 1] {
                    let ny = y as i64 + dy;
                    let ny = if wrap_y {
                        ny.rem_euclid(h as i64)
                    } else if ny < 0 || ny >= h as i64 {
                        continue;
                    } else {
                        ny
                    };
                    for dx in [-1i64, 0, 1] {
                        let nx = (x as i64 + dx).rem_euclid(w as i64);
                        let j = ny as usize * w + nx as usize;
                        if covered(j) {
                            c_sum += col[j];
                            t_sum += tan[j];
                            k += 1;
                        }
                    }
                }
                if k > 0 {
                    (c_sum / k as f32, t_sum.normalize_or(EMPTY_TANGENT))
                } else {
                    (EMPTY_COLOUR, EMPTY_TANGENT)
                }
            };
            let a = unorm8(alpha[i]);
            colour_img.texels[i] = [unorm8(c.x), unorm8(c.y), unorm8(c.z), a];
            let [r, g, b] = tangent_to_rgb8(t);
            tangent_img.texels[i] = [r, g, b, a];
        }
    }
    (colour_img, tangent_img)
}

/// The density bands of a layer: per output texel and band `j` in 0..4, the covered fraction of
/// its subsamples whose strand's band (`bands[strand]`) is at most `j`, times `weight`,
/// quantised like alpha. Band 3 counts every covered subsample, so it equals the colour
/// image's alpha.
pub(crate) fn density_bands(
    grid: &SampleGrid,
    factor: usize,
    bands: &[u32],
    weight: f32,
) -> Rgba8Image {
    let w = grid.width / factor;
    let h = grid.height / factor;
    let n = (factor * factor) as f32;
    let mut image = Rgba8Image::new(w as u32, h as u32, [0; 4]);
    for y in 0..h {
        for x in 0..w {
            let mut counts = [0u32; 4];
            for sy in 0..factor {
                let row = (y * factor + sy) * grid.width;
                for sx in 0..factor {
                    let s = &grid.samples[row + x * factor + sx];
                    if let Some(&band) = bands.get(s.strand as usize) {
                        counts[band.min(3) as usize] += 1;
                    }
                }
            }
            let mut texel = [0u8; 4];
            let mut cumulative = 0;
            for (j, count) in counts.iter().enumerate() {
                cumulative += count;
                // The same expression as the colour alpha, so band 3 equals it bit for bit.
                texel[j] = unorm8(cumulative as f32 / n * weight);
            }
            image.texels[y * w + x] = texel;
        }
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unorm8_rounds_half_up_and_clamps() {
        assert_eq!(unorm8(0.0), 0);
        assert_eq!(unorm8(1.0), 255);
        assert_eq!(unorm8(-3.0), 0);
        assert_eq!(unorm8(7.0), 255);
        assert_eq!(unorm8(f32::NAN), 0);
        assert_eq!(unorm8(0.5), 128); // 127.5 + 0.5 = 128
        assert_eq!(unorm8(1.49 / 255.0), 1);
        assert_eq!(unorm8(1.51 / 255.0), 2);
    }

    #[test]
    fn tangent_round_trip() {
        let ts = [
            Vec3::Z,
            Vec3::X,
            -Vec3::Y,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ];
        for t in ts {
            let back = tangent_from_rgb8(tangent_to_rgb8(t));
            assert!((back - t).length() < 0.01, "{t} -> {back}");
        }
        assert_eq!(tangent_to_rgb8(Vec3::Z), [128, 128, 255]);
    }

    #[test]
    fn downsample_coverage_and_dilation() {
        // 4×4 grid, factor 2 → 2×2; cover 3 of the 4 subsamples of texel (0, 0) only.
        let mut g = SampleGrid::new(4, 4);
        for (x, y) in [(0, 0), (1, 0), (0, 1)] {
            g.samples[y * 4 + x].strand = 0;
            g.samples[y * 4 + x].tangent = Vec3::X;
        }
        let colours = [Vec3::new(1.0, 0.5, 0.0)];
        let (c, t) = downsample(&g, 2, &colours, |_| 1.0, true);
        assert_eq!(c.get(0, 0), Some([255, 128, 0, unorm8(0.75)]));
        assert_eq!(t.get(0, 0), Some([255, 128, 128, unorm8(0.75)]));
        // Neighbours dilate colour and tangent but stay transparent.
        assert_eq!(c.get(1, 1), Some([255, 128, 0, 0]));
        assert_eq!(t.get(1, 0), Some([255, 128, 128, 0]));
        // Density bands: strand 0 in band 2 covers 3 of 4 subsamples.
        let bands = density_bands(&g, 2, &[2], 1.0);
        assert_eq!(bands.get(0, 0), Some([0, 0, unorm8(0.75), unorm8(0.75)]));
        assert_eq!(bands.get(1, 1), Some([0, 0, 0, 0]));
        // Nothing at all: the documented constants.
        let empty = SampleGrid::new(2, 2);
        let (c, t) = downsample(&empty, 1, &colours, |_| 1.0, true);
        assert!(c.texels.iter().all(|&p| p == [0, 0, 0, 0]));
        assert!(t.texels.iter().all(|&p| p == [128, 128, 255, 0]));
    }
}
