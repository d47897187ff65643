//! Textures (raster stage): RGBA8 texels with a mip chain (box-filtered, or weighted by
//! coverage), sampled with GPU rules.
//!
//! The rules a GPU shader must follow to match (all in f32 unless stated):
//! - A texel value is `byte / 255`.
//! - Mip level `k+1` is `max(1, ⌊w/2⌋) × max(1, ⌊h/2⌋)`; its texel (x, y) is the rounded
//!   average `(a + b + c + d + 2) >> 2` (integers) of texels (2x, 2y), (2x+1, 2y), (2x, 2y+1),
//!   (2x+1, 2y+1) of level k, coordinates clamped to level k's size. A texture whose alpha is
//!   coverage ([`MipFilter::Coverage`]: the fur layers) averages its colour channels weighted by
//!   alpha instead: `(Σ αᵢ·cᵢ + ⌊Σαᵢ/2⌋) / Σαᵢ` (integers, alpha in bytes), the plain average
//!   where all four alphas are 0; its alpha channel is the plain average.
//! - Addressing: `Wrap` takes the integer texel index modulo the size (Euclidean), `Clamp`
//!   clamps it to `[0, size − 1]`. Texel-space coordinates (`u·w`, `u·w − 0.5`) that are not
//!   finite are treated as 0, others are clamped to ±2^30.
//! - `Nearest` reads texel `⌊u·w⌋` of level 0. [`Sampler::sample_nearest_level`] reads texel
//!   `⌊u·w_k⌋` of level `k = ⌊clamp(λ) + 0.5⌋`. `Bilinear` reads level 0 at `x = u·w − 0.5`,
//!   `x0 = ⌊x⌋`, `fx = x − x0` (same for y) and returns
//!   `lerp(lerp(t00, t10, fx), lerp(t01, t11, fx), fy)` with `lerp(a, b, t) = a + (b − a)·t`.
//! - `Trilinear` computes the level of detail from the quad's coarse derivatives of (u, v):
//!   `ρ² = max(‖(∂u/∂x·w, ∂v/∂x·h)‖², ‖(∂u/∂y·w, ∂v/∂y·h)‖²)`, `λ = ½·log2(ρ²)` (pelage's
//!   own `log2`, the powers' `crate::shading::numeric::log2_lane`; no square root)
//!   clamped to `[0, levels − 1]` (NaN → 0, +∞ → levels − 1); it samples levels `⌊λ⌋` and
//!   `⌊λ⌋ + 1` bilinearly and returns `lerp(level0, level1, λ − ⌊λ⌋)`.

use super::RasterError;
use crate::simd::SimdLevel;
use glam::{Vec2, Vec4};
use wide::{f32x4, i32x4};

mod alpha_gather;
mod pairs512;

/// One mip level: row-major RGBA8 texels, row 0 at v = 0.
///
/// Invariant: `texels.len() == width × height`, both at least 1. Only [`Texture`] builds
/// levels (its sizes checked), and the fields are private, so the hot reads may rely on it:
/// an index made of an addressed column (`< width`) and an addressed row (`< height`) is in
/// bounds (`MipLevel::texel_at`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MipLevel {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
}

impl MipLevel {
    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The `width × height` texels, row-major.
    pub fn texels(&self) -> &[[u8; 4]] {
        &self.texels
    }

    #[inline]
    fn texel(&self, x: i64, y: i64) -> [u8; 4] {
        self.texels[(y as usize) * self.width as usize + x as usize]
    }

    /// The texel at `index = row·width + column` of an addressed column and row, without a
    /// bounds check.
    ///
    /// Why unchecked: the fur stage reads 8 to 16 texels a lit fragment here, and each check
    /// is a compare and branch on the addressing's result (docs/performance.md, "Texel reads
    /// without bounds checks").
    ///
    /// # Safety
    /// `index < width × height`: it must come from a column in `0..width` and a row in
    /// `0..height` of this level (or of a level of the same size), as [`address`] and
    /// [`LaneAddressing`] give them.
    #[inline(always)]
    unsafe fn texel_at(&self, index: usize) -> [u8; 4] {
        debug_assert!(index < self.texels.len());
        // SAFETY: the caller's index is in `0..width × height`, and the type's invariant makes
        // that the length of `texels`.
        unsafe { *self.texels.get_unchecked(index) }
    }
}

/// Where a bilinear sample reads (texel indices 00, 10, 01, 11 of one level) and its weights.
struct BilinearFootprint {
    texels: [usize; 4],
    fx: f32,
    fy: f32,
}

impl BilinearFootprint {
    /// `top = t00 + (t10 − t00)·fx`, `bottom = t01 + (t11 − t01)·fx`,
    /// `top + (bottom − top)·fy` on the texels' bytes as they are (0–255): the caller scales
    /// the filtered value once ([`unorm8_scale_vec4`]).
    #[inline]
    fn filter(&self, level: &MipLevel) -> Vec4 {
        let [i00, i10, i01, i11] = self.texels;
        let t00 = byte_values(level.texels[i00]);
        let t10 = byte_values(level.texels[i10]);
        let t01 = byte_values(level.texels[i01]);
        let t11 = byte_values(level.texels[i11]);
        let top = t00 + (t10 - t00) * self.fx;
        let bottom = t01 + (t11 - t01) * self.fx;
        top + (bottom - top) * self.fy
    }

    /// [`BilinearFootprint::filter`] of two levels of one size at once (a colour map's and a
    /// tangent map's), the first's channels in lanes 0–3 and the second's in 4–7: the same
    /// operations per channel, written as loops over 8 lanes so that the AVX2 copy of the hot
    /// path ([`crate::simd`]) converts and filters both texels in 256-bit registers.
    ///
    /// # Safety
    /// This footprint's texel indices are of addressed rows and columns of a level the size
    /// of `first` ([`MipLevel::texel_at`]), and `second` is that size too.
    #[inline(always)]
    unsafe fn filter_pair(&self, first: &MipLevel, second: &MipLevel) -> [f32; 8] {
        let texel = |i: usize| -> [f32; 8] {
            // SAFETY: the function's contract.
            let (a, b) = unsafe { (first.texel_at(i), second.texel_at(i)) };
            let mut bytes = [0u8; 8];
            bytes[..4].copy_from_slice(&a);
            bytes[4..].copy_from_slice(&b);
            let mut t = [0.0f32; 8];
            for c in 0..8 {
                t[c] = f32::from(bytes[c]);
            }
            t
        };
        self.filter_8(texel)
    }

    /// The bilinear filter of 8 channels (see [`BilinearFootprint::filter`]) of the texels
    /// `texel(i)` gives for this footprint's indices.
    #[inline(always)]
    fn filter_8(&self, texel: impl Fn(usize) -> [f32; 8]) -> [f32; 8] {
        let [i00, i10, i01, i11] = self.texels;
        let (t00, t10, t01, t11) = (texel(i00), texel(i10), texel(i01), texel(i11));
        let (fx, fy) = (self.fx, self.fy);
        let mut out = [0.0f32; 8];
        for c in 0..8 {
            let top = t00[c] + (t10[c] - t00[c]) * fx;
            let bottom = t01[c] + (t11[c] - t01[c]) * fx;
            out[c] = top + (bottom - top) * fy;
        }
        out
    }
}

impl BilinearFootprint {
    /// [`BilinearFootprint::filter_pair`] from interleaved texels ([`PairedTexels`]): the same
    /// bytes and the same filter operations, so the same bits, with one load a texel.
    ///
    /// # Safety
    /// This footprint's texel indices are of addressed rows and columns of a level of the
    /// size `level` was converted from.
    #[inline(always)]
    unsafe fn filter_converted(&self, level: &[PairTexel]) -> [f32; 8] {
        let texel = |i: usize| {
            // SAFETY: the function's contract; `level` holds one texel per texel of its level.
            let bytes = unsafe { level.get_unchecked(i).0 };
            let mut t = [0.0f32; 8];
            for c in 0..8 {
                t[c] = f32::from(bytes[c]);
            }
            t
        };
        self.filter_8(texel)
    }
}

/// One texel of [`PairedTexels`]: two RGBA8 texels side by side, 8-byte aligned so that one
/// load reads it and no texel straddles two cache lines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(8))]
struct PairTexel([u8; 8]);

/// A filtered byte value `x` (0–255) scaled to 0–1, the one scaling of a texture sample
/// (docs/conventions.md, "Textures"): `y = x·257/2^16`, then `y + y·(2^-16 + 2^-32)`, since
/// `1/255 = (257/2^16)·(1 + 2^-16 + 2^-32 + …)`. For a whole byte `b` (a texel read alone, or
/// four equal texels) it is the correctly rounded `b/255` (test `unorm8_exact_is_the_quotient`);
/// between bytes, two roundings from `x/255`. No division.
#[inline(always)]
fn unorm8_exact(x: f32) -> f32 {
    let y = x * UNORM8_SCALE;
    y + y * UNORM8_CORRECTION
}

/// [`unorm8_exact`] of four channels, the same operations per channel.
#[inline(always)]
fn unorm8_scale_vec4(x: Vec4) -> Vec4 {
    let y = x * UNORM8_SCALE;
    y + y * UNORM8_CORRECTION
}

/// [`unorm8_exact`] of eight channels.
#[inline(always)]
fn unorm8_scale_8(x: [f32; 8]) -> [f32; 8] {
    let mut out = [0.0f32; 8];
    for c in 0..8 {
        out[c] = unorm8_exact(x[c]);
    }
    out
}

/// [`unorm8_exact`] of every lane of every channel, once the lanes' filtered bytes are in their
/// channel arrays: a packed loop over each channel's lanes. (A lane's eight channels scaled
/// before they are stored apart became scalar code, 32 instructions a lane.)
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
fn scale_channels<const N: usize>(channels: &mut PairChannels<N>) {
    for channel in channels.iter_mut() {
        for i in 0..N {
            channel[i] = unorm8_exact(channel[i]);
        }
    }
}

/// The factors of [`unorm8_exact`]: `257/2^16`, then `2^-16 + 2^-32`.
const UNORM8_SCALE: f32 = 257.0 / 65536.0;
const UNORM8_CORRECTION: f32 = 1.0 / 65536.0 + 1.0 / 4_294_967_296.0;

/// Two textures with one mip chain shape (a layer's colour and tangent maps), interleaved
/// once: texel `i` of level `k` holds the first texture's RGBA bytes in 0–3 and the second's in
/// 4–7, so that a texel read of both is one 8-byte load, widened and converted in 8 lanes at
/// once (docs/performance.md, "Texel pairs side by side"). Also each level's alpha bytes of the
/// first texture alone, for the shadow's nearest lookups.
#[derive(Clone, Debug, PartialEq)]
pub struct PairedTexels {
    /// Each level's texel count (its width × height, as in both textures) and its texels.
    levels: Vec<Vec<PairTexel>>,
    /// Each level's alpha bytes of the first texture alone, for the nearest lookups that
    /// read only alpha ([`NearestLookup::with_converted`]): a quarter of its texels' bytes,
    /// then `alpha_gather::ALPHA_PLANE_PADDING` zeros.
    alphas: Vec<Vec<u8>>,
}

impl PairedTexels {
    /// `first` and `second` side by side; `None` when their mip chains differ in shape.
    pub fn new(first: &Texture, second: &Texture) -> Option<Self> {
        let same_shape = first.levels.len() == second.levels.len()
            && first
                .levels
                .iter()
                .zip(&second.levels)
                .all(|(a, b)| (a.width, a.height) == (b.width, b.height));
        if !same_shape {
            return None;
        }
        let levels = first
            .levels
            .iter()
            .zip(&second.levels)
            .map(|(a, b)| {
                a.texels
                    .iter()
                    .zip(&b.texels)
                    .map(|(x, y)| PairTexel([x[0], x[1], x[2], x[3], y[0], y[1], y[2], y[3]]))
                    .collect()
            })
            .collect();
        // Padded for the 4-byte reads of `alpha_gather`'s gather.
        let alphas = first
            .levels
            .iter()
            .map(|l| {
                l.texels
                    .iter()
                    .map(|t| t[3])
                    .chain([0; alpha_gather::ALPHA_PLANE_PADDING])
                    .collect()
            })
            .collect();
        Some(PairedTexels { levels, alphas })
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.alphas.iter().map(Vec::len).sum::<usize>()
            + self
                .levels
                .iter()
                .map(|l| l.len() * size_of::<PairTexel>())
                .sum::<usize>()
    }
}

/// An RGBA8 texture with its full mip chain.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Texture {
    levels: Vec<MipLevel>,
}

/// Largest texture side accepted.
pub const MAX_TEXTURE_SIZE: u32 = 16384;

impl Texture {
    /// The mip level `k` below `lod`, the next `k1` (`k` itself at the end of the chain) and
    /// the fraction from `k` towards it, `lod` clamped to the chain (NaN → 0). `lod ≥ 0` after
    /// the clamp, so truncation is the floor.
    #[inline]
    pub fn trilinear_indices(&self, lod: f32) -> (usize, usize, f32) {
        let max = (self.levels.len() - 1) as f32;
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, max)
        };
        // Through `u32`: the same value (`lod` is in [0, max]) with one conversion instruction,
        // where a float-to-`usize` cast needs a fix-up for values past 2⁶³.
        let k = lod as u32 as usize;
        (k, (k + 1).min(self.levels.len() - 1), lod - k as f32)
    }

    /// The lower mip level and the nearest one of a squared footprint `ρ²`
    /// ([`footprint_squared`]): `trilinear_indices(λ).0` and `nearest_level_index(λ)` of
    /// `λ = level_of_detail_of_footprint(ρ²)`, the same indices, without the logarithm where
    /// `ρ²` is a normal number further than 2^12 mantissa steps from a
    /// power of two (the rest takes the logarithm).
    ///
    /// Why that is exact: such a `ρ² = 2^e·(1 + f)` has `½·log2 ρ²` in
    /// `[e/2 + 1.7·10⁻⁴, (e + 1)/2 − 1.7·10⁻⁴]`, and pelage's `log2` is
    /// `k + r(m)` with the reduced mantissa's `r(m)` within `2·10⁻⁶` of `log2 m` for every `m`
    /// (test `log2_of_every_reduced_mantissa_is_close`), rounded once when `k` is added
    /// (`|k + r| < 129`: an error below `2^-17`). So `λ` lies strictly inside
    /// `(e/2, (e + 1)/2)`, more than its rounding of `λ + ½` away from either end: `⌊λ⌋ =
    /// ⌊e/2⌋` and `⌊λ + ½⌋ = ⌊(e + 1)/2⌋`, each clamped to the chain as the clamp of `λ` does.
    /// The lower level decides which batch a quad's lanes join; their `λ` itself is computed
    /// in the batch, sixteen lanes at a time.
    #[inline(always)]
    pub fn levels_of_footprint(&self, squared: f32) -> (usize, usize) {
        let bits = squared.to_bits();
        let biased = bits >> 23;
        let mantissa = bits & 0x7f_ffff;
        let far_from_powers =
            mantissa.wrapping_sub(FOOTPRINT_EXACT_WINDOW) <= 0x7f_ffff - 2 * FOOTPRINT_EXACT_WINDOW;
        // Positive normal numbers: the biased exponent in 1..=254 with the sign bit clear.
        if far_from_powers && (1..=254).contains(&biased) {
            let e = biased as i32 - 127;
            let max = (self.levels.len() - 1) as i32;
            let lower = (e >> 1).clamp(0, max) as usize;
            let nearest = ((e + 1) >> 1).clamp(0, max) as usize;
            return (lower, nearest);
        }
        let lod = level_of_detail_of_footprint(squared);
        (self.trilinear_indices(lod).0, self.nearest_level_index(lod))
    }

    /// Builds a texture and its mip chain with [`MipFilter::Box`]. Fails when the size is
    /// zero, too large, or does not match the number of texels.
    pub fn from_rgba8(width: u32, height: u32, texels: Vec<[u8; 4]>) -> Result<Self, RasterError> {
        Self::with_mip_filter(width, height, texels, MipFilter::Box)
    }

    /// [`Texture::from_rgba8`] with the mip levels built by `filter`.
    pub fn with_mip_filter(
        width: u32,
        height: u32,
        texels: Vec<[u8; 4]>,
        filter: MipFilter,
    ) -> Result<Self, RasterError> {
        let expected = width as usize * height as usize;
        if width == 0
            || height == 0
            || width > MAX_TEXTURE_SIZE
            || height > MAX_TEXTURE_SIZE
            || texels.len() != expected
        {
            return Err(RasterError::TextureSize {
                width,
                height,
                expected,
                actual: texels.len(),
            });
        }
        let mut levels = vec![MipLevel {
            width,
            height,
            texels,
        }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(downsample(last, filter));
        }
        Ok(Texture { levels })
    }

    /// The mip level `round(lod)` (clamped to the chain, NaN → 0) that
    /// [`Sampler::sample_nearest_level`] reads.
    #[inline]
    pub fn nearest_level(&self, lod: f32) -> &MipLevel {
        &self.levels[self.nearest_level_index(lod)]
    }

    /// The index of [`Texture::nearest_level`].
    #[inline]
    pub fn nearest_level_index(&self, lod: f32) -> usize {
        let max = (self.levels.len() - 1) as f32;
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, max)
        };
        // lod is in [0, max]: adding 0.5 and truncating rounds half up (through `u32`, as in
        // `trilinear_indices`).
        (lod + 0.5) as u32 as usize
    }

    /// Number of mip levels (1 for a 1×1 texture).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Mip level `k`, if it exists.
    pub fn level(&self, k: usize) -> Option<&MipLevel> {
        self.levels.get(k)
    }

    /// The mip chain, level 0 first.
    pub fn levels(&self) -> &[MipLevel] {
        &self.levels
    }

    /// Width of level 0.
    pub fn width(&self) -> u32 {
        self.levels[0].width
    }

    /// Height of level 0.
    pub fn height(&self) -> u32 {
        self.levels[0].height
    }
}

/// How a texture's mip levels average the texels they merge (the module docs give the rules).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MipFilter {
    /// Every channel the plain average of the four texels.
    #[default]
    Box,
    /// Alpha is coverage: the colour channels averaged weighted by alpha, so that transparent
    /// texels (whose colour nothing shows) do not pull the colour of the covered ones towards
    /// theirs. The fur layers: their transparent texels hold a neighbour's colour or the empty
    /// colour (black) and tangent, and a plain average darkened a sparse layer's colour level by
    /// level (of a fur of 30 shells, layer 25 kept half its colour four levels down, the top
    /// layer a tenth), so fur seen from afar or at a grazing angle was darker than near fur.
    Coverage,
}

/// One texel of the next level from four (`q`), as `filter` says.
fn merge_texels(q: &[[u8; 4]; 4], filter: MipFilter) -> [u8; 4] {
    let average = |c: usize| {
        let sum: u32 = q.iter().map(|t| u32::from(t[c])).sum();
        ((sum + 2) >> 2) as u8
    };
    let weight: u32 = q.iter().map(|t| u32::from(t[3])).sum();
    match filter {
        MipFilter::Coverage if weight > 0 => std::array::from_fn(|c| {
            if c == 3 {
                return average(3);
            }
            let sum: u32 = q.iter().map(|t| u32::from(t[c]) * u32::from(t[3])).sum();
            // At most 255: a weighted mean of bytes.
            ((sum + weight / 2) / weight) as u8
        }),
        _ => std::array::from_fn(average),
    }
}

fn downsample(src: &MipLevel, filter: MipFilter) -> MipLevel {
    let width = (src.width / 2).max(1);
    let height = (src.height / 2).max(1);
    let (mx, my) = (i64::from(src.width) - 1, i64::from(src.height) - 1);
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for y in 0..i64::from(height) {
        for x in 0..i64::from(width) {
            let (x0, y0) = ((2 * x).min(mx), (2 * y).min(my));
            let (x1, y1) = ((2 * x + 1).min(mx), (2 * y + 1).min(my));
            let q = [
                src.texel(x0, y0),
                src.texel(x1, y0),
                src.texel(x0, y1),
                src.texel(x1, y1),
            ];
            texels.push(merge_texels(&q, filter));
        }
    }
    MipLevel {
        width,
        height,
        texels,
    }
}

/// What happens outside [0, 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AddressMode {
    /// Repeat the texture (the fur tile is seamless).
    #[default]
    Wrap,
    /// Repeat the edge texel.
    Clamp,
}

/// How texels are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// The texel containing the point, level 0.
    Nearest,
    /// Four texels of level 0, bilinearly weighted.
    Bilinear,
    /// Bilinear in the two mip levels around the level of detail, linearly mixed.
    #[default]
    Trilinear,
}

/// Sampling state: addressing per axis and filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Sampler {
    /// Addressing along u.
    pub address_u: AddressMode,
    /// Addressing along v.
    pub address_v: AddressMode,
    /// Filter.
    pub filter: Filter,
}

/// `byte / 255` for every byte, for reading one channel: a load instead of a division.
static UNORM8: [f32; 256] = {
    let mut table = [0.0f32; 256];
    let mut i = 0;
    while i < 256 {
        table[i] = i as f32 / 255.0;
        i += 1;
    }
    table
};

/// The four bytes of a texel as floats (0–255), for the bilinear filter.
#[inline]
fn byte_values(t: [u8; 4]) -> Vec4 {
    Vec4::new(
        f32::from(t[0]),
        f32::from(t[1]),
        f32::from(t[2]),
        f32::from(t[3]),
    )
}

/// `byte / 255` per channel: one packed conversion and one packed division, the same IEEE
/// quotient as the scalar `f32::from(byte) / 255.0` (a table of the 256 quotients needed four
/// lookups and inserts per texel).
#[inline]
fn to_vec4(t: [u8; 4]) -> Vec4 {
    byte_values(t) / 255.0
}

#[inline]
pub(crate) fn address(i: i64, size: u32, mode: AddressMode) -> i64 {
    let size = i64::from(size);
    match mode {
        // Most coordinates are already inside: skip the division.
        AddressMode::Wrap if (0..size).contains(&i) => i,
        // For a power of two the two's-complement mask is the Euclidean remainder.
        AddressMode::Wrap if size & (size - 1) == 0 => i & (size - 1),
        AddressMode::Wrap => i.rem_euclid(size),
        AddressMode::Clamp => i.clamp(0, size - 1),
    }
}

/// Texel coordinates are kept within ±2^30 (far beyond any texture), which makes the floor
/// below exact.
const COORDINATE_LIMIT: f32 = (1u32 << 30) as f32;

/// A texel-space coordinate: non-finite values become 0, others are clamped to ±2^30.
#[inline]
fn texel_coordinate(x: f32) -> f32 {
    if x.is_finite() {
        x.clamp(-COORDINATE_LIMIT, COORDINATE_LIMIT)
    } else {
        0.0
    }
}

/// [`texel_coordinate`] of four lanes.
#[inline(always)]
fn texel_coordinate_x4(x: f32x4) -> f32x4 {
    let limit = f32x4::splat(COORDINATE_LIMIT);
    let clamped = x.simd_lt(-limit).select(-limit, x);
    let clamped = clamped.simd_gt(limit).select(limit, clamped);
    x.is_finite().select(clamped, f32x4::ZERO)
}

/// [`floor_small`] of four lanes: truncated (exact within ±2^30), then one down where that
/// rounded up.
#[inline(always)]
fn floor_x4(x: f32x4) -> i32x4 {
    let truncated = x.fast_trunc_int();
    let rounded_up: i32x4 = wide::bytemuck::cast(truncated.round_float().simd_gt(x));
    truncated + rounded_up
}

/// `⌊x⌋` for `|x| ≤ 2^30`, equal to `f32::floor` there. (`f32::floor` is a library call on
/// x86-64 without SSE4.1; truncation plus a correction is not.)
#[inline]
fn floor_small(x: f32) -> i64 {
    let t = x as i64;
    if (t as f32) > x { t - 1 } else { t }
}

/// The level of detail λ for a texture of `width`×`height` from the coarse derivatives of the
/// texture coordinates, `½·log2 ρ²` with pelage's own `log2` (see the module's notes),
/// unclamped except for NaN (→ 0) and infinities (→ `f32::MAX`); a zero footprint gives −∞,
/// which sampling clamps to level 0.
#[inline]
pub fn level_of_detail(ddx: Vec2, ddy: Vec2, width: u32, height: u32) -> f32 {
    level_of_detail_of_footprint(footprint_squared(ddx, ddy, width, height))
}

/// The squared footprint `ρ² = max(|ddx·size|², |ddy·size|²)` of [`level_of_detail`], NaN
/// where either derivative's is NaN.
#[inline]
pub fn footprint_squared(ddx: Vec2, ddy: Vec2, width: u32, height: u32) -> f32 {
    let size = Vec2::new(width as f32, height as f32);
    let (squared_x, squared_y) = ((ddx * size).length_squared(), (ddy * size).length_squared());
    if squared_x.is_nan() || squared_y.is_nan() {
        return f32::NAN;
    }
    squared_x.max(squared_y)
}

/// The level of detail of a squared footprint ([`footprint_squared`]): `½·log2 ρ²` (`log2 ρ =
/// ½·log2 ρ²` and `max(√a, √b) = √max(a, b)`: no square root at all), NaN → 0, +∞ →
/// `f32::MAX`, 0 → −∞. The branches are selects, so that a loop of it over lanes vectorises
/// (the fur stage's batches compute their lanes' levels of detail so).
#[inline(always)]
pub fn level_of_detail_of_footprint(squared: f32) -> f32 {
    let lod = 0.5 * crate::shading::numeric::log2_lane(squared);
    let lod = if squared == 0.0 {
        f32::NEG_INFINITY
    } else {
        lod
    };
    let lod = if squared == f32::INFINITY {
        f32::MAX
    } else {
        lod
    };
    if squared.is_nan() { 0.0 } else { lod }
}

/// Squared footprints within this many steps of the mantissa from a power of two take
/// [`Texture::levels_of_footprint`]'s exact path: `2^12` steps keep `ρ²` a factor of at least
/// `1 + 2^-12` from either power of two around it, which keeps `½·log2 ρ²` at least
/// `1.7·10⁻⁴` from the nearest multiple of ½.
const FOOTPRINT_EXACT_WINDOW: u32 = 1 << 12;

impl Sampler {
    /// Samples with the filter's rules; `ddx`, `ddy` are the screen derivatives of `uv`
    /// (only `Trilinear` uses them).
    #[inline]
    pub fn sample(&self, texture: &Texture, uv: Vec2, ddx: Vec2, ddy: Vec2) -> Vec4 {
        match self.filter {
            Filter::Nearest => self.nearest(&texture.levels[0], uv),
            Filter::Bilinear => self.bilinear(&texture.levels[0], uv),
            Filter::Trilinear => {
                let lod = level_of_detail(ddx, ddy, texture.width(), texture.height());
                self.sample_level(texture, uv, lod)
            }
        }
    }

    /// Trilinear sample at an explicit level of detail (clamped to the chain).
    #[inline]
    pub fn sample_level(&self, texture: &Texture, uv: Vec2, lod: f32) -> Vec4 {
        self.trilinear_levels(texture, lod).sample(uv)
    }

    /// What a trilinear sample of `texture` at level of detail `lod` reads besides the
    /// coordinate: the two levels, the fraction between them and their addressing. Lanes that
    /// share `lod` (a quad's) choose them once; [`TrilinearLevels::sample`] then gives the same
    /// values as [`Sampler::sample_level`].
    #[inline]
    pub fn trilinear_levels<'a>(&self, texture: &'a Texture, lod: f32) -> TrilinearLevels<'a> {
        self.levels_at(texture, texture.trilinear_indices(lod))
    }

    /// [`Sampler::trilinear_levels`] from `Texture::trilinear_indices`.
    #[inline]
    fn levels_at<'a>(
        &self,
        texture: &'a Texture,
        (k, k1, frac): (usize, usize, f32),
    ) -> TrilinearLevels<'a> {
        let levels = [&texture.levels[k], &texture.levels[k1]];
        TrilinearLevels {
            levels,
            blend: (frac != 0.0 && k1 != k).then_some(frac),
            addressing: self.footprint_addressing(levels),
        }
    }

    /// Two textures of the same size sampled at the same point and level of detail: the same
    /// values as two [`Sampler::sample_level`] calls, with the addressing done once (a shader
    /// reading a colour map and a tangent map at one coordinate).
    #[inline]
    pub fn sample_level_pair(
        &self,
        first: &Texture,
        second: &Texture,
        uv: Vec2,
        lod: f32,
    ) -> (Vec4, Vec4) {
        match self.trilinear_pair(first, second, lod) {
            Some(pair) => pair.sample(uv),
            None => (
                self.sample_level(first, uv, lod),
                self.sample_level(second, uv, lod),
            ),
        }
    }

    /// [`Sampler::trilinear_levels`] of two textures with the same mip chain shape (`None`
    /// otherwise): [`TrilinearPair::sample`] gives the values of [`Sampler::sample_level_pair`].
    #[inline]
    pub fn trilinear_pair<'a>(
        &self,
        first: &'a Texture,
        second: &'a Texture,
        lod: f32,
    ) -> Option<TrilinearPair<'a>> {
        self.trilinear_pair_at(first, second, first.trilinear_indices(lod))
    }

    /// [`Sampler::trilinear_pair`] at levels `k` and `k1` with fraction `frac`, as
    /// [`Texture::trilinear_indices`] gives them. A pair for [`TrilinearPair::sample_lanes`]
    /// alone, whose lanes bring their own fractions, may take `frac` 0: its levels and
    /// addressing do not depend on it.
    #[inline]
    pub fn trilinear_pair_at<'a>(
        &self,
        first: &'a Texture,
        second: &'a Texture,
        indices @ (k, k1, _): (usize, usize, f32),
    ) -> Option<TrilinearPair<'a>> {
        if first.levels.len() != second.levels.len()
            || first.width() != second.width()
            || first.height() != second.height()
            || k1 >= first.levels.len()
            || k > k1
        {
            return None;
        }
        Some(TrilinearPair {
            first: self.levels_at(first, indices),
            second: [&second.levels[k], &second.levels[k1]],
            indices: [k, k1],
            converted: None,
        })
    }

    /// The nearest texel of mip level `round(lod)` (clamped to the chain, NaN → 0): one texel
    /// read, for lookups that only ask whether a point is covered.
    #[inline]
    pub fn sample_nearest_level(&self, texture: &Texture, uv: Vec2, lod: f32) -> Vec4 {
        self.nearest(texture.nearest_level(lod), uv)
    }

    /// The nearest texel of `level` (from [`Texture::nearest_level`]): the same read as
    /// [`Sampler::sample_nearest_level`] with the level chosen once, for a run of lookups at
    /// one level of detail.
    #[inline]
    pub fn sample_nearest_in(&self, level: &MipLevel, uv: Vec2) -> Vec4 {
        self.nearest(level, uv)
    }

    /// The alpha of [`Sampler::sample_nearest_in`]: the same value, converting one byte.
    #[inline]
    pub fn alpha_nearest_in(&self, level: &MipLevel, uv: Vec2) -> f32 {
        UNORM8[usize::from(self.nearest_texel(level, uv)[3])]
    }

    /// What [`Sampler::alpha_nearest_in`] reads of `level` besides the coordinate, for lookups
    /// several at a time ([`NearestLookup::alpha_lanes`]); lanes that share a level choose it
    /// once.
    #[inline]
    pub fn nearest_lookup<'a>(&self, level: &'a MipLevel) -> NearestLookup<'a> {
        NearestLookup {
            level,
            converted: None,
            u: LaneAddressing::new([level.width; 4], [self.address_u; 4]),
            v: LaneAddressing::new([level.height; 4], [self.address_v; 4]),
        }
    }

    /// The sizes and modes of the four lanes of [`TrilinearLevels::footprints`]: x and y of
    /// the lower level, x and y of the upper.
    #[inline]
    fn footprint_addressing(&self, [a, b]: [&MipLevel; 2]) -> LaneAddressing {
        LaneAddressing::new(
            [a.width, a.height, b.width, b.height],
            [
                self.address_u,
                self.address_v,
                self.address_u,
                self.address_v,
            ],
        )
    }

    #[inline]
    fn nearest(&self, level: &MipLevel, uv: Vec2) -> Vec4 {
        to_vec4(self.nearest_texel(level, uv))
    }

    #[inline]
    fn nearest_texel(&self, level: &MipLevel, uv: Vec2) -> [u8; 4] {
        let x = floor_small(texel_coordinate(uv.x * level.width as f32));
        let y = floor_small(texel_coordinate(uv.y * level.height as f32));
        level.texel(
            address(x, level.width, self.address_u),
            address(y, level.height, self.address_v),
        )
    }

    #[inline]
    fn bilinear(&self, level: &MipLevel, uv: Vec2) -> Vec4 {
        let levels = [level, level];
        TrilinearLevels {
            levels,
            blend: None,
            addressing: self.footprint_addressing(levels),
        }
        .sample(uv)
    }
}

/// Four lanes of texel indices to address, each with its own size and mode, fixed for a run
/// of lookups.
#[derive(Clone, Copy, Debug)]
struct LaneAddressing {
    size: [u32; 4],
    size_f32: f32x4,
    modes: [AddressMode; 4],
    /// `size − 1` when every lane wraps on a power-of-two size: addressing is then a mask (the
    /// Euclidean remainder of a two's-complement index).
    wrap_mask: Option<i32x4>,
}

impl LaneAddressing {
    #[inline(always)]
    fn new(size: [u32; 4], modes: [AddressMode; 4]) -> Self {
        let masks = modes.iter().all(|&m| m == AddressMode::Wrap)
            && size.iter().all(|n| n.is_power_of_two());
        LaneAddressing {
            size,
            size_f32: f32x4::new(size.map(|n| n as f32)),
            modes,
            wrap_mask: masks.then(|| i32x4::new(size.map(|n| n as i32 - 1))),
        }
    }

    /// [`address`] of each lane.
    #[inline(always)]
    fn address(&self, index: i32x4) -> i32x4 {
        match self.wrap_mask {
            Some(mask) => index & mask,
            None => {
                let index = index.to_array();
                i32x4::new(std::array::from_fn(|lane| {
                    address(i64::from(index[lane]), self.size[lane], self.modes[lane]) as i32
                }))
            }
        }
    }
}

/// The levels, blend fraction and addressing of a trilinear sample at one level of detail,
/// from [`Sampler::trilinear_levels`].
#[derive(Clone, Copy, Debug)]
pub struct TrilinearLevels<'a> {
    /// Levels `⌊λ⌋` and `⌊λ⌋ + 1` (the same level twice at the end of the chain).
    levels: [&'a MipLevel; 2],
    /// `λ − ⌊λ⌋`; `None` when only the lower level is read (a zero fraction, or the last
    /// level).
    blend: Option<f32>,
    addressing: LaneAddressing,
}

impl TrilinearLevels<'_> {
    /// The trilinear sample at `uv`: [`Sampler::sample_level`]'s value.
    #[inline]
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let [fa, fb] = self.footprints(uv);
        let a = fa.filter(self.levels[0]);
        unorm8_scale_vec4(match self.blend {
            None => a,
            Some(frac) => {
                let b = fb.filter(self.levels[1]);
                a + (b - a) * frac
            }
        })
    }

    /// The four texels and the weights of a bilinear sample of each level: the x and y of
    /// both levels go through the coordinate clamp, the floor and the addressing together, as
    /// four packed lanes.
    #[inline(always)]
    fn footprints(&self, uv: Vec2) -> [BilinearFootprint; 2] {
        let addressing = &self.addressing;
        let position =
            f32x4::new([uv.x, uv.y, uv.x, uv.y]) * addressing.size_f32 - f32x4::splat(0.5);
        let position = texel_coordinate_x4(position);
        let floor = floor_x4(position);
        let fraction = (position - floor.round_float()).to_array();
        let low = addressing.address(floor).to_array();
        let high = addressing.address(floor + i32x4::ONE).to_array();
        std::array::from_fn(|level| {
            let (x, y) = (2 * level, 2 * level + 1);
            let row = addressing.size[x] as usize;
            let (xa, xb) = (low[x] as usize, high[x] as usize);
            let (ya, yb) = (low[y] as usize, high[y] as usize);
            BilinearFootprint {
                texels: [ya * row + xa, ya * row + xb, yb * row + xa, yb * row + xb],
                fx: fraction[x],
                fy: fraction[y],
            }
        })
    }
}

/// Trilinear samples of two textures with one mip chain shape (a colour map and a tangent
/// map) at one level of detail, from [`Sampler::trilinear_pair`]: the addressing is done once
/// for both.
#[derive(Clone, Copy, Debug)]
pub struct TrilinearPair<'a> {
    first: TrilinearLevels<'a>,
    /// The second texture's levels, the same indices as the first's.
    second: [&'a MipLevel; 2],
    /// The indices of the two levels.
    indices: [usize; 2],
    /// Both textures' levels interleaved ([`TrilinearPair::with_converted`]), read instead of
    /// the two maps' bytes by [`TrilinearPair::sample_lanes`].
    converted: Option<[&'a [PairTexel]; 2]>,
}

impl<'a> TrilinearPair<'a> {
    /// This pair reading `converted`, the same two textures interleaved beforehand, in
    /// [`TrilinearPair::sample_lanes`] (the same values). Unchanged when `converted` has
    /// another shape than this pair's textures (so it cannot be of them).
    pub fn with_converted(mut self, converted: &'a PairedTexels) -> Self {
        let level = |k: usize, l: &MipLevel| {
            converted
                .levels
                .get(k)
                .filter(|texels| texels.len() == l.texels.len())
        };
        let [k, k1] = self.indices;
        let [lower, upper] = self.first.levels;
        if let (Some(a), Some(b)) = (level(k, lower), level(k1, upper)) {
            self.converted = Some([a.as_slice(), b.as_slice()]);
        }
        self
    }
}

impl TrilinearPair<'_> {
    /// Both samples at `uv`: [`Sampler::sample_level_pair`]'s values.
    #[inline(always)]
    pub fn sample(&self, uv: Vec2) -> (Vec4, Vec4) {
        let [fa, fb] = self.first.footprints(uv);
        let [lower, upper] = self.first.levels;
        // SAFETY: `footprints` addresses each level's rows and columns along its own size, and
        // the second texture's levels are the first's sizes (`Sampler::trilinear_pair`).
        let mut both = unsafe { fa.filter_pair(lower, self.second[0]) };
        if let Some(frac) = self.first.blend {
            // SAFETY: as for the lower level.
            let b = unsafe { fb.filter_pair(upper, self.second[1]) };
            for c in 0..8 {
                both[c] = both[c] + (b[c] - both[c]) * frac;
            }
        }
        let both = unorm8_scale_8(both);
        (Vec4::from_slice(&both[..4]), Vec4::from_slice(&both[4..]))
    }
}

/// The eight channels of [`TrilinearPair::sample_lanes`] for `N` lanes, one array a channel:
/// the first texture's RGBA in 0–3, the second's in 4–7.
pub type PairChannels<const N: usize> = [[f32; N]; 8];

impl TrilinearPair<'_> {
    /// [`TrilinearPair::sample`] of `N` lanes (a multiple of 4), the result in
    /// structure-of-arrays form: lane `i` samples `(u[i], v[i])` at this pair's mip levels with
    /// its own blend fraction `frac[i]` (the `λ − ⌊λ⌋` of its quad; 0 reads the lower level
    /// alone), and gets, channel by channel, the bits [`TrilinearPair::sample`] gives at that
    /// fraction. The footprints (the coordinate clamp, the floor, the weights, the addressing)
    /// are plain loops over the lanes, which LLVM packs as wide as the level's copy of the hot
    /// path allows; each lane's texels are then converted and filtered as today's single
    /// sample does, both textures' eight channels at once. `level` caps the instructions the
    /// reads may use: the AVX-512 path (`pairs512`, 16 lanes) runs only at
    /// [`SimdLevel::Avx512`] on a CPU that has it; the bits are the same either way.
    #[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
    #[inline(always)]
    pub fn sample_lanes<const N: usize>(
        &self,
        u: &[f32; N],
        v: &[f32; N],
        frac: &[f32; N],
        level: SimdLevel,
    ) -> PairChannels<N> {
        let [lower, upper] = self.first.levels;
        let mut any_blend = 0u32;
        for i in 0..N {
            any_blend |= u32::from(frac[i] != 0.0);
        }
        let low = self.footprint_lanes(0, u, v);
        let high = if any_blend != 0 {
            self.footprint_lanes(1, u, v)
        } else {
            low
        };
        let mut out = [[0.0f32; N]; 8];
        // The two ways of reading texels as two written-out loops, not one loop over a
        // closure or a match: a closure is not `#[inline(always)]`, and LLVM left one out of
        // line, compiled for the baseline (+39 % instructions a frame); a match inside the
        // loop cost as much.
        if let Some([converted_lower, converted_upper]) = self.converted {
            #[cfg(target_arch = "x86_64")]
            if level >= SimdLevel::Avx512 && N == pairs512::LANES && pairs512::available() {
                // SAFETY: AVX-512 F, BW, DQ and VL were detected just above, `N` is 16, and
                // the footprints address their levels as below (`high` is the upper level's
                // for every lane whenever a lane blends).
                return unsafe {
                    pairs512::sample(&low, &high, frac, converted_lower, converted_upper)
                };
            }
            for i in 0..N {
                // SAFETY: `footprint_lanes` addresses each level's rows and columns along its
                // own size, and `with_converted` took converted levels of those texel counts.
                let mut both = unsafe { low.lane(i).filter_converted(converted_lower) };
                if frac[i] != 0.0 {
                    // SAFETY: as for the lower level.
                    let b = unsafe { high.lane(i).filter_converted(converted_upper) };
                    for c in 0..8 {
                        both[c] = both[c] + (b[c] - both[c]) * frac[i];
                    }
                }
                for c in 0..8 {
                    out[c][i] = both[c];
                }
            }
            scale_channels(&mut out);
            return out;
        }
        for i in 0..N {
            // SAFETY: `footprint_lanes` addresses each level's rows and columns along its own
            // size, and the second texture's levels are the first's sizes
            // (`Sampler::trilinear_pair`).
            let mut both = unsafe { low.lane(i).filter_pair(lower, self.second[0]) };
            if frac[i] != 0.0 {
                // SAFETY: as for the lower level.
                let b = unsafe { high.lane(i).filter_pair(upper, self.second[1]) };
                for c in 0..8 {
                    both[c] = both[c] + (b[c] - both[c]) * frac[i];
                }
            }
            for c in 0..8 {
                out[c][i] = both[c];
            }
        }
        scale_channels(&mut out);
        out
    }

    /// The bilinear footprints of `N` lanes on level `level` of the pair (0 the lower, 1 the
    /// upper): [`TrilinearLevels::footprints`], lane by lane the same operations.
    #[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
    #[inline(always)]
    fn footprint_lanes<const N: usize>(
        &self,
        level: usize,
        u: &[f32; N],
        v: &[f32; N],
    ) -> FootprintLanes<N> {
        let addressing = &self.first.addressing;
        let (ax, ay) = (2 * level, 2 * level + 1);
        let size = addressing.size_f32.to_array();
        let (x, fx) = lane_footprint_axis(u, size[ax]);
        let (y, fy) = lane_footprint_axis(v, size[ay]);
        let (x0, x1) = addressing.address_lanes(ax, &x);
        let (y0, y1) = addressing.address_lanes(ay, &y);
        let row = addressing.size[ax] as i32;
        let mut rows = ([0i32; N], [0i32; N]);
        for i in 0..N {
            // Within the level: the products are below its texel count.
            rows.0[i] = y0[i] * row;
            rows.1[i] = y1[i] * row;
        }
        FootprintLanes {
            x: (x0, x1),
            rows,
            fx,
            fy,
        }
    }
}

/// The bilinear footprints of `N` lanes on one level, one array per component: the columns
/// and row offsets of the texels below and above each sample point, and the weights.
#[derive(Clone, Copy)]
struct FootprintLanes<const N: usize> {
    x: ([i32; N], [i32; N]),
    rows: ([i32; N], [i32; N]),
    fx: [f32; N],
    fy: [f32; N],
}

impl<const N: usize> FootprintLanes<N> {
    /// Lane `i`'s footprint.
    #[inline(always)]
    fn lane(&self, i: usize) -> BilinearFootprint {
        let (xa, xb) = (self.x.0[i] as usize, self.x.1[i] as usize);
        let (ya, yb) = (self.rows.0[i] as usize, self.rows.1[i] as usize);
        BilinearFootprint {
            texels: [ya + xa, ya + xb, yb + xa, yb + xb],
            fx: self.fx[i],
            fy: self.fy[i],
        }
    }
}

/// One axis of the bilinear footprints of `N` lanes (a multiple of 4) on a level `size`
/// texels wide: the texel index below the sample point (`⌊x⌋` of
/// `x = texel_coordinate(c·size − 0.5)`, before addressing) and the weight `x − ⌊x⌋` of the
/// one above.
#[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
#[inline(always)]
fn lane_footprint_axis<const N: usize>(c: &[f32; N], size: f32) -> ([i32; N], [f32; N]) {
    lane_axis(c, size, 0.5)
}

/// `⌊x⌋` and `x − ⌊x⌋` of `x = texel_coordinate(c·size − shift)` for `N` lanes (a multiple of
/// 4), the steps of `texel_coordinate_x4` and `floor_x4` lane by lane.
#[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
#[inline(always)]
fn lane_axis<const N: usize>(c: &[f32; N], size: f32, shift: f32) -> ([i32; N], [f32; N]) {
    let mut x = [0.0f32; N];
    for i in 0..N {
        // `texel_coordinate_x4`, one lane.
        let position = c[i] * size - shift;
        let clamped = if position < -COORDINATE_LIMIT {
            -COORDINATE_LIMIT
        } else {
            position
        };
        let clamped = if clamped > COORDINATE_LIMIT {
            COORDINATE_LIMIT
        } else {
            clamped
        };
        x[i] = if position.is_finite() { clamped } else { 0.0 };
    }
    // The truncation four lanes at a time with `wide`'s packed conversion (|x| ≤ 2^30: exact,
    // never out of range); Rust's saturating `as` keeps the loop scalar.
    let mut truncated = [0i32; N];
    for first in (0..N).step_by(4) {
        let four = f32x4::new([x[first], x[first + 1], x[first + 2], x[first + 3]]);
        let t = four.fast_trunc_int().to_array();
        truncated[first..first + 4].copy_from_slice(&t);
    }
    let mut index = [0i32; N];
    let mut weight = [0.0f32; N];
    for i in 0..N {
        // `floor_x4`: one down where the truncation rounded up.
        let floor = truncated[i] - i32::from(truncated[i] as f32 > x[i]);
        index[i] = floor;
        weight[i] = x[i] - floor as f32;
    }
    (index, weight)
}

impl LaneAddressing {
    /// [`address`] of the indices `index[i]` and `index[i] + 1` of `N` lanes along the axis
    /// of footprint lane `axis`.
    #[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
    #[inline(always)]
    fn address_lanes<const N: usize>(&self, axis: usize, index: &[i32; N]) -> ([i32; N], [i32; N]) {
        let (mut low, mut high) = ([0i32; N], [0i32; N]);
        match self.wrap_mask {
            Some(mask) => {
                let mask = mask.to_array()[axis];
                for i in 0..N {
                    low[i] = index[i] & mask;
                    high[i] = (index[i] + 1) & mask;
                }
            }
            None => {
                let (size, mode) = (self.size[axis], self.modes[axis]);
                for i in 0..N {
                    let at = i64::from(index[i]);
                    low[i] = address(at, size, mode) as i32;
                    high[i] = address(at + 1, size, mode) as i32;
                }
            }
        }
        (low, high)
    }
}

/// Nearest reads of one mip level several at a time, from [`Sampler::nearest_lookup`].
#[derive(Clone, Copy, Debug)]
pub struct NearestLookup<'a> {
    level: &'a MipLevel,
    /// The level's alpha plane ([`NearestLookup::with_converted`]), read instead of its
    /// 4-byte texels.
    converted: Option<&'a [u8]>,
    u: LaneAddressing,
    v: LaneAddressing,
}

impl<'a> NearestLookup<'a> {
    /// These lookups reading the alpha plane of level `k` of `converted`, whose first texture
    /// must be the one this level is level `k` of: the same values from 1 byte a texel instead
    /// of 4, a quarter of the cache lines. Unchanged when that plane's texel count is not this
    /// level's (so reads stay in bounds whatever `k`; a wrong `k` of the same size would read
    /// another level's alphas, which the caller rules out by taking `k` from
    /// [`Texture::nearest_level_index`]).
    pub fn with_converted(mut self, converted: &'a PairedTexels, k: usize) -> Self {
        if let Some(texels) = converted.alphas.get(k).filter(|texels| {
            texels.len() == self.level.texels.len() + alpha_gather::ALPHA_PLANE_PADDING
        }) {
            self.converted = Some(texels.as_slice());
        }
        self
    }
}

impl NearestLookup<'_> {
    /// [`Sampler::alpha_nearest_in`] at `N` points `(u[i], v[i])` (`N` a multiple of 4), the
    /// same values: the coordinate clamp, the floor and the addressing as plain loops over
    /// the lanes, or, from the alpha plane of a level that wraps on power-of-two sizes, as one
    /// gather of 16 lanes (AVX-512) or one a register of 8 (AVX2, `N` a multiple of 8) where
    /// `level` allows it and the CPU has it (`alpha_gather`); the bits are the same either way.
    #[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
    #[inline(always)]
    pub fn alpha_lanes<const N: usize>(
        &self,
        u: [f32; N],
        v: [f32; N],
        level: SimdLevel,
    ) -> [f32; N] {
        // The gathers where the level and the CPU allow them: the alpha plane of a level whose
        // axes both wrap on power-of-two sizes.
        #[cfg(target_arch = "x86_64")]
        if let Some(plane) = self.converted
            && let (Some(mask_u), Some(mask_v)) = (self.u.wrap_mask, self.v.wrap_mask)
        {
            let masks = [mask_u.to_array()[0], mask_v.to_array()[0]];
            let (width, height) = (self.level.width, self.level.height);
            // SAFETY (both calls): the CPU's features were detected just before each, `N` is
            // the lanes each takes, both axes wrap on the level's power-of-two sizes
            // (`wrap_mask` is `size − 1`), and `with_converted` took a padded plane of this
            // level's texel count.
            if level >= SimdLevel::Avx512 && N == alpha_gather::LANES && pairs512::available() {
                return unsafe { alpha_gather::nearest(&u, &v, width, height, masks, plane) };
            }
            if level >= SimdLevel::Avx2
                && N.is_multiple_of(alpha_gather::AVX2_LANES)
                && alpha_gather::avx2_available()
            {
                return unsafe { alpha_gather::nearest_avx2(&u, &v, width, height, masks, plane) };
            }
        }
        // `c·size − 0` is `c·size`, bit for bit: the nearest texel has no half-texel shift.
        let (x, _) = lane_axis(&u, self.u.size[0] as f32, 0.0);
        let (y, _) = lane_axis(&v, self.v.size[0] as f32, 0.0);
        let (x, _) = self.u.address_lanes(0, &x);
        let (y, _) = self.v.address_lanes(0, &y);
        let row = self.level.width as usize;
        // The alpha bytes first, then `byte/255` of all lanes as packed arithmetic
        // ([`unorm8_exact`], the same quotients as the table `UNORM8`): a table read per lane
        // became a gather in the AVX-512 copy.
        let mut bytes = [0u8; N];
        // Two written-out loops, as in `TrilinearPair::sample_lanes`.
        if let Some(converted) = self.converted {
            for i in 0..N {
                let index = y[i] as usize * row + x[i] as usize;
                // SAFETY: as below; `with_converted` took a converted level of this level's
                // texel count.
                bytes[i] = unsafe { *converted.get_unchecked(index) };
            }
        } else {
            for i in 0..N {
                // SAFETY: `x[i]` and `y[i]` are addressed along this level's width and height
                // (`address_lanes` of addressing made from its size), so the index is in
                // bounds.
                bytes[i] = unsafe { self.level.texel_at(y[i] as usize * row + x[i] as usize) }[3];
            }
        }
        let mut out = [0.0; N];
        for i in 0..N {
            out[i] = unorm8_exact(f32::from(bytes[i]));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(size: u32) -> Texture {
        let texels = (0..size * size)
            .map(|i| {
                if (i % size + i / size).is_multiple_of(2) {
                    [255, 255, 255, 255]
                } else {
                    [0, 0, 0, 255]
                }
            })
            .collect();
        Texture::from_rgba8(size, size, texels).expect("texture")
    }

    #[test]
    fn mip_chain_halves_down_to_one_texel() {
        let t = checker(8);
        assert_eq!(t.level_count(), 4);
        let last = t.level(3).expect("level 3");
        assert_eq!((last.width, last.height), (1, 1));
        // A checkerboard averages to (255·2 + 2) >> 2 = 128.
        assert_eq!(t.level(1).expect("level 1").texels[0], [128, 128, 128, 255]);
        let odd = Texture::from_rgba8(5, 3, vec![[10, 20, 30, 40]; 15]).expect("odd");
        assert_eq!(odd.level_count(), 3);
        assert_eq!(odd.level(1).map(|l| (l.width, l.height)), Some((2, 1)));
    }

    #[test]
    fn coverage_mips_weight_colour_by_alpha() {
        // One covered texel among three transparent black ones: the box filter quarters its
        // colour, the coverage filter keeps it; alpha is the plain average either way.
        let texels = vec![
            [200, 100, 40, 255],
            [0, 0, 0, 0],
            [0, 0, 0, 0],
            [0, 0, 0, 0],
        ];
        let boxed = Texture::from_rgba8(2, 2, texels.clone()).expect("box");
        let covered =
            Texture::with_mip_filter(2, 2, texels, MipFilter::Coverage).expect("coverage");
        assert_eq!(boxed.level(1).expect("level 1").texels[0], [50, 25, 10, 64]);
        assert_eq!(
            covered.level(1).expect("level 1").texels[0],
            [200, 100, 40, 64]
        );
        // All four transparent: the plain average of their (dilated) colours.
        let clear = vec![[8, 16, 32, 0], [8, 16, 32, 0], [16, 16, 0, 0], [0, 0, 0, 0]];
        let t = Texture::with_mip_filter(2, 2, clear, MipFilter::Coverage).expect("clear");
        assert_eq!(t.level(1).expect("level 1").texels[0], [8, 12, 16, 0]);
    }

    #[test]
    fn coverage_mips_match_an_f64_weighted_mean() {
        // Against the weighted mean in f64, rounded half up: Σαc / Σα is never an exact half
        // when Σα is odd, and `⌊Σα/2⌋` adds exactly a half when it is even.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut byte = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 56) as u8
        };
        for _ in 0..2000 {
            let q: [[u8; 4]; 4] = std::array::from_fn(|_| std::array::from_fn(|_| byte()));
            let merged = merge_texels(&q, MipFilter::Coverage);
            let weight: f64 = q.iter().map(|t| f64::from(t[3])).sum();
            for c in 0..3 {
                let expected = if weight > 0.0 {
                    let sum: f64 = q.iter().map(|t| f64::from(t[c]) * f64::from(t[3])).sum();
                    (sum / weight + 0.5).floor()
                } else {
                    (q.iter().map(|t| f64::from(t[c])).sum::<f64>() / 4.0 + 0.5).floor()
                };
                assert_eq!(f64::from(merged[c]), expected, "{q:?} channel {c}");
            }
            let alpha: f64 = q.iter().map(|t| f64::from(t[3])).sum::<f64>() / 4.0;
            assert_eq!(f64::from(merged[3]), (alpha + 0.5).floor(), "{q:?} alpha");
            let boxed = merge_texels(&q, MipFilter::Box);
            for c in 0..4 {
                let mean = q.iter().map(|t| f64::from(t[c])).sum::<f64>() / 4.0;
                assert_eq!(f64::from(boxed[c]), (mean + 0.5).floor(), "{q:?} box {c}");
            }
        }
    }

    #[test]
    fn bad_sizes_are_refused() {
        assert!(Texture::from_rgba8(0, 4, vec![]).is_err());
        assert!(Texture::from_rgba8(2, 2, vec![[0; 4]; 3]).is_err());
    }

    #[test]
    fn wrap_and_clamp_addressing() {
        let texels = vec![[0, 0, 0, 0], [255, 0, 0, 0], [0, 255, 0, 0], [0, 0, 255, 0]];
        let t = Texture::from_rgba8(4, 1, texels).expect("texture");
        let wrap = Sampler {
            filter: Filter::Nearest,
            ..Sampler::default()
        };
        let clamp = Sampler {
            filter: Filter::Nearest,
            address_u: AddressMode::Clamp,
            address_v: AddressMode::Clamp,
        };
        let at = |s: &Sampler, u: f32| s.sample(&t, Vec2::new(u, 0.5), Vec2::ZERO, Vec2::ZERO);
        assert_eq!(at(&wrap, 1.3), at(&wrap, 0.3));
        assert_eq!(at(&wrap, -0.1), Vec4::new(0.0, 0.0, 1.0, 0.0));
        assert_eq!(at(&clamp, -0.1), Vec4::ZERO);
        assert_eq!(at(&clamp, 7.0), Vec4::new(0.0, 0.0, 1.0, 0.0));
        assert_eq!(at(&wrap, f32::NAN), Vec4::ZERO);
        assert_eq!(at(&wrap, 1e30), at(&wrap, (1u32 << 30) as f32 / 4.0));
    }

    #[test]
    fn nearest_level_picks_the_rounded_level() {
        let t = checker(8);
        let s = Sampler::default();
        let uv = Vec2::new(0.1, 0.1);
        assert_eq!(s.sample_nearest_level(&t, uv, 0.4).x, 1.0);
        // Level 1 of a one-texel checkerboard is uniform grey (128/255).
        assert_eq!(s.sample_nearest_level(&t, uv, 0.5).x, 128.0 / 255.0);
        assert_eq!(
            s.sample_nearest_level(&t, uv, 99.0),
            s.sample_nearest_level(&t, uv, 3.0)
        );
        assert_eq!(s.sample_nearest_level(&t, uv, f32::NAN).x, 1.0);
    }

    #[test]
    fn nearest_lookups_of_8_16_and_32_lanes_are_single_lookups() {
        // Lanes from the alpha plane of a wrapped level take `alpha_gather`: 16 with AVX-512
        // (`nearest`), 8, 16 or 32 with AVX2 (`nearest_avx2`, a register of 8 at a time); the
        // clamped sampler and the 4-byte texels take the portable loops.
        nearest_lanes_are_single_lookups::<8>();
        nearest_lanes_are_single_lookups::<16>();
        nearest_lanes_are_single_lookups::<32>();
    }

    fn nearest_lanes_are_single_lookups<const N: usize>() {
        let texels: Vec<[u8; 4]> = (0..64 * 32u32)
            .map(|i| [0, 0, 0, (i * 37 + i / 64) as u8])
            .collect();
        let t = Texture::from_rgba8(64, 32, texels).expect("texture");
        let converted = PairedTexels::new(&t, &t).expect("same shape");
        let specials = [f32::NAN, f32::INFINITY, -1e30, -0.0, 1.0, 0.999_999_9];
        for sampler in [
            Sampler::default(),
            Sampler {
                address_u: AddressMode::Clamp,
                ..Sampler::default()
            },
        ] {
            for k_level in 0..t.level_count() {
                let level = t.level(k_level).expect("level");
                let lookup = sampler.nearest_lookup(level);
                let from_alphas = lookup.with_converted(&converted, k_level);
                assert!(from_alphas.converted.is_some(), "the alpha plane is taken");
                // Another level's plane has another texel count: refused.
                let wrong = sampler
                    .nearest_lookup(level)
                    .with_converted(&converted, (k_level + 1) % t.level_count());
                assert!(wrong.converted.is_none());
                for k in 0..500u32 {
                    let point = |i: u32| {
                        let j = k * N as u32 + i;
                        let u = if j.is_multiple_of(13) {
                            specials[(j / 13) as usize % specials.len()]
                        } else {
                            (j as f32 * 0.618_034).fract() * 6.0 - 3.0
                        };
                        (u, (j as f32 * 0.414_213_5).fract() * 4.0 - 2.0)
                    };
                    let (u, v): (Vec<f32>, Vec<f32>) = (0..N as u32).map(point).unzip();
                    let (u, v): ([f32; N], [f32; N]) =
                        (u.try_into().expect("N"), v.try_into().expect("N"));
                    let got = lookup.alpha_lanes(u, v, SimdLevel::detected());
                    // The alpha plane's reads at every level (the gathers where the level and
                    // the CPU allow them, the portable loops below).
                    for simd in SimdLevel::available() {
                        let alphas = from_alphas.alpha_lanes(u, v, simd);
                        assert_eq!(
                            alphas.map(f32::to_bits),
                            got.map(f32::to_bits),
                            "alpha plane at {simd}"
                        );
                    }
                    for i in 0..N {
                        let want = sampler.alpha_nearest_in(level, Vec2::new(u[i], v[i]));
                        assert_eq!(got[i].to_bits(), want.to_bits(), "({}, {})", u[i], v[i]);
                    }
                }
            }
        }
    }

    #[test]
    fn floor_small_matches_floor() {
        for x in [
            -3.5f32,
            -3.0,
            -0.25,
            -0.0,
            0.0,
            0.25,
            2.999_999_8,
            3.0,
            8_388_607.5,
            -8_388_607.5,
            1.0e9,
            -1.0e9,
        ] {
            assert_eq!(floor_small(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn wrapping_masks_powers_of_two_like_rem_euclid() {
        for size in [1u32, 2, 4, 16, 128, 3, 12, 100] {
            for i in (-1000i64..1000).chain([i64::MIN / 2, -(1 << 40), 1 << 40]) {
                assert_eq!(
                    address(i, size, AddressMode::Wrap),
                    i.rem_euclid(i64::from(size)),
                    "{i} mod {size}"
                );
            }
        }
    }

    #[test]
    fn paired_samples_equal_single_samples() {
        let a = checker(16);
        let texels: Vec<[u8; 4]> = (0..256u32)
            .map(|i| [(i * 7) as u8, (i * 13) as u8, (i * 29) as u8, (i * 3) as u8])
            .collect();
        let b = Texture::from_rgba8(16, 16, texels).expect("texture");
        let s = Sampler::default();
        for k in 0..500 {
            let uv = Vec2::new(k as f32 * 0.0137 - 2.0, k as f32 * 0.0291 - 5.0);
            let lod = k as f32 * 0.011 - 0.5;
            let (pa, pb) = s.sample_level_pair(&a, &b, uv, lod);
            // Bit for bit: the pair filters both textures' channels as one 8-lane batch.
            let bits = |v: Vec4| v.to_array().map(f32::to_bits);
            assert_eq!(bits(pa), bits(s.sample_level(&a, uv, lod)));
            assert_eq!(bits(pb), bits(s.sample_level(&b, uv, lod)));
            assert_eq!(bits(pa), bits(plain_trilinear(&s, &a, uv, lod)));
            assert_eq!(bits(pb), bits(plain_trilinear(&s, &b, uv, lod)));
        }
        let small = checker(4);
        let (pa, pb) = s.sample_level_pair(&a, &small, Vec2::splat(0.3), 0.7);
        assert_eq!(pa, s.sample_level(&a, Vec2::splat(0.3), 0.7));
        assert_eq!(pb, s.sample_level(&small, Vec2::splat(0.3), 0.7));
    }

    /// `sample_lanes` on 16, 8 and 4 lanes (16 from interleaved texels: `pairs512` where the
    /// CPU has AVX-512), each lane with its own coordinate (awkward ones among them) and blend
    /// fraction (zero among them), gives each lane the bits of the pair taken at its own level
    /// of detail; over wrapped and clamped, square and odd-shaped textures.
    #[test]
    fn pair_lanes_are_single_pair_samples() {
        let pattern = |w: u32, h: u32, seed: u32| hashed_texture(w, h, 7, seed);
        let samplers = [
            Sampler::default(),
            Sampler {
                address_u: AddressMode::Clamp,
                address_v: AddressMode::Wrap,
                ..Sampler::default()
            },
        ];
        let mut seed = 0x2545_f491u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let bits = |v: Vec4| v.to_array().map(f32::to_bits);
        for (w, h) in [(16, 16), (12, 5), (32, 8)] {
            let (a, b) = (pattern(w, h, 0), pattern(w, h, 3));
            let converted = PairedTexels::new(&a, &b).expect("same shape");
            for s in &samplers {
                for k in 0..a.level_count() {
                    let bytes = s.trilinear_pair(&a, &b, k as f32).expect("same shape");
                    let pair = bytes.with_converted(&converted);
                    assert!(pair.converted.is_some(), "the converted levels are taken");
                    for round in 0..200u32 {
                        let lods: [f32; 16] = std::array::from_fn(|_| {
                            let r = next();
                            if r % 5 == 0 {
                                k as f32
                            } else {
                                k as f32 + (r >> 8) as f32 / (1u32 << 24) as f32
                            }
                        });
                        let uvs: [Vec2; 16] = std::array::from_fn(|i| {
                            if (round + i as u32).is_multiple_of(3) {
                                awkward_coordinates(next())
                            } else {
                                Vec2::new(
                                    (next() >> 8) as f32 / 1e6 - 4.0,
                                    (next() >> 8) as f32 / 3e6 - 2.0,
                                )
                            }
                        });
                        let frac = lods.map(|lod| {
                            let (lk, _, frac) = a.trilinear_indices(lod);
                            assert_eq!(lk, k);
                            frac
                        });
                        let (u, v) = (uvs.map(|uv| uv.x), uvs.map(|uv| uv.y));
                        let best = SimdLevel::detected();
                        let lanes = pair.sample_lanes(&u, &v, &frac, best);
                        // Every level's reads (the AVX-512 path where the CPU has it, the
                        // portable loops below it) give the same bits.
                        for level in SimdLevel::available() {
                            let at = pair.sample_lanes(&u, &v, &frac, level);
                            assert_eq!(
                                at.map(|c| c.map(f32::to_bits)),
                                lanes.map(|c| c.map(f32::to_bits)),
                                "{level} against {best}"
                            );
                        }
                        let from_bytes = bytes.sample_lanes(&u, &v, &frac, best);
                        assert_eq!(
                            lanes.map(|c| c.map(f32::to_bits)),
                            from_bytes.map(|c| c.map(f32::to_bits)),
                            "converted texels against bytes"
                        );
                        let first = |x: &[f32; 16]| -> [f32; 8] { std::array::from_fn(|i| x[i]) };
                        let eight = pair.sample_lanes(&first(&u), &first(&v), &first(&frac), best);
                        assert_eq!(
                            eight.map(|c| c.map(f32::to_bits)),
                            lanes.map(|c| first(&c).map(f32::to_bits)),
                            "8 lanes against the first 8 of 16"
                        );
                        let quad = pair.sample_lanes(
                            &[u[0], u[1], u[2], u[3]],
                            &[v[0], v[1], v[2], v[3]],
                            &[frac[0], frac[1], frac[2], frac[3]],
                            best,
                        );
                        for i in 0..16 {
                            let single = s.trilinear_pair(&a, &b, lods[i]).expect("same shape");
                            let (ca, cb) = single.sample(uvs[i]);
                            let got = |c: &[[f32; 16]; 8], t: usize| {
                                Vec4::new(
                                    c[4 * t][i],
                                    c[4 * t + 1][i],
                                    c[4 * t + 2][i],
                                    c[4 * t + 3][i],
                                )
                            };
                            assert_eq!(bits(got(&lanes, 0)), bits(ca), "lane {i} at {:?}", uvs[i]);
                            assert_eq!(bits(got(&lanes, 1)), bits(cb), "lane {i} at {:?}", uvs[i]);
                            if i < 4 {
                                let first: [f32; 4] = std::array::from_fn(|c| quad[c][i]);
                                assert_eq!(first.map(f32::to_bits), bits(ca));
                            }
                        }
                    }
                }
            }
        }
    }

    /// Interleaved texels hold both maps' bytes and the first's alphas, and a pair takes only
    /// interleaved levels of its own texel counts (an unsafe read relies on that).
    #[test]
    fn interleaved_texels_are_the_maps_bytes_and_must_fit() {
        let (a, b) = (hashed_texture(12, 5, 7, 1), hashed_texture(12, 5, 7, 2));
        let converted = PairedTexels::new(&a, &b).expect("same shape");
        for (k, level) in converted.levels.iter().enumerate() {
            let (la, lb) = (a.level(k).expect("level"), b.level(k).expect("level"));
            assert_eq!(level.len(), la.texels.len());
            for (i, t) in level.iter().enumerate() {
                let want: [u8; 8] = std::array::from_fn(|c| {
                    if c < 4 {
                        la.texels[i][c]
                    } else {
                        lb.texels[i][c - 4]
                    }
                });
                assert_eq!(t.0, want);
                assert_eq!(converted.alphas[k][i], la.texels[i][3]);
            }
            let padding = &converted.alphas[k][level.len()..];
            assert_eq!(padding, [0; alpha_gather::ALPHA_PLANE_PADDING]);
        }
        assert_eq!(
            converted.bytes(),
            9 * (60 + 12 + 3 + 1) + 4 * alpha_gather::ALPHA_PLANE_PADDING
        );
        assert!(PairedTexels::new(&a, &hashed_texture(12, 6, 7, 2)).is_none());
        let s = Sampler::default();
        let other = PairedTexels::new(&hashed_texture(16, 16, 7, 1), &hashed_texture(16, 16, 7, 2))
            .expect("same shape");
        for lod in [0.0, 1.5, 3.0] {
            let pair = s.trilinear_pair(&a, &b, lod).expect("same shape");
            assert!(pair.with_converted(&other).converted.is_none(), "{lod}");
            assert!(pair.with_converted(&converted).converted.is_some(), "{lod}");
        }
    }

    /// The division-free `byte/255` is the correctly rounded quotient for every byte (f64
    /// holds `b/255` to 53 bits, so its rounding to f32 is the f32 quotient's, except at a tie,
    /// which a quotient of a byte by 255 never is).
    #[test]
    fn unorm8_exact_is_the_quotient() {
        for b in 0..=255u8 {
            let want = f32::from(b) / 255.0;
            assert_eq!(unorm8_exact(f32::from(b)).to_bits(), want.to_bits(), "{b}");
            assert_eq!(
                want.to_bits(),
                ((f64::from(b) / 255.0) as f32).to_bits(),
                "{b}"
            );
            assert_eq!(UNORM8[usize::from(b)].to_bits(), want.to_bits(), "{b}");
        }
    }

    /// A trilinear sample written out plainly from the module's rules, scalar in each step: the
    /// reference for [`TrilinearLevels`] and [`TrilinearPair`], which choose the levels once.
    fn plain_trilinear(s: &Sampler, texture: &Texture, uv: Vec2, lod: f32) -> Vec4 {
        let last = texture.level_count() - 1;
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, last as f32)
        };
        let k = lod.floor() as usize;
        let k1 = (k + 1).min(last);
        let frac = lod - k as f32;
        // The texels' bytes filtered as they are, the result scaled once.
        let bilinear = |level: &MipLevel| {
            let (texels, fx, fy) = scalar_footprint(s, level, uv);
            let t = texels.map(|i| Vec4::from_array(level.texels[i].map(f32::from)));
            let top = t[0] + (t[1] - t[0]) * fx;
            let bottom = t[2] + (t[3] - t[2]) * fx;
            top + (bottom - top) * fy
        };
        let scale = |x: Vec4| {
            let y = x * (257.0 / 65536.0);
            y + y * (1.0 / 65536.0 + 1.0 / 4_294_967_296.0)
        };
        let a = bilinear(&texture.levels[k]);
        if frac == 0.0 || k1 == k {
            return scale(a);
        }
        let b = bilinear(&texture.levels[k1]);
        scale(a + (b - a) * frac)
    }

    /// A `w`×`h` texture of hashed texels: channel `c` of texel `i` is the byte of
    /// `i·2654435761` shifted right by `shift·c + seed`.
    fn hashed_texture(w: u32, h: u32, shift: u32, seed: u32) -> Texture {
        let texels = (0..w * h)
            .map(|i| {
                std::array::from_fn(|c| {
                    (i.wrapping_mul(2_654_435_761) >> (shift * c as u32 + seed)) as u8
                })
            })
            .collect();
        Texture::from_rgba8(w, h, texels).expect("texture")
    }

    #[test]
    fn levels_chosen_once_give_the_plain_trilinear_sample() {
        let pattern = |w: u32, h: u32, seed: u32| hashed_texture(w, h, 8, seed);
        let shapes = [(16, 16), (12, 5), (1, 8), (1, 1)];
        let modes = [AddressMode::Wrap, AddressMode::Clamp];
        let lods = [
            f32::NAN,
            -1.0,
            0.0,
            0.25,
            1.0,
            1.5,
            2.999,
            3.0,
            4.0,
            100.0,
            f32::INFINITY,
        ];
        for &(w, h) in &shapes {
            let (first, second) = (pattern(w, h, 0), pattern(w, h, 3));
            for (address_u, address_v) in modes.iter().flat_map(|&u| modes.map(|v| (u, v))) {
                let s = Sampler {
                    address_u,
                    address_v,
                    filter: Filter::Trilinear,
                };
                for (j, &lod) in lods.iter().enumerate() {
                    let levels = s.trilinear_levels(&first, lod);
                    let pair = s.trilinear_pair(&first, &second, lod).expect("same shape");
                    for k in 0..300u32 {
                        let uv = awkward_coordinates(k * 11 + j as u32);
                        let bits = |v: Vec4| v.to_array().map(f32::to_bits);
                        let expected = bits(plain_trilinear(&s, &first, uv, lod));
                        assert_eq!(bits(levels.sample(uv)), expected, "{w}×{h} {uv} {lod}");
                        assert_eq!(bits(s.sample_level(&first, uv, lod)), expected);
                        let (a, b) = pair.sample(uv);
                        assert_eq!(bits(a), expected, "{w}×{h} {uv} {lod}");
                        assert_eq!(bits(b), bits(plain_trilinear(&s, &second, uv, lod)));
                    }
                }
            }
        }
        let s = Sampler::default();
        assert!(
            s.trilinear_pair(&pattern(16, 16, 0), &pattern(16, 8, 0), 0.5)
                .is_none()
        );
    }

    /// The footprint as first written, one axis at a time in i64: the reference the packed
    /// [`TrilinearLevels::footprints`] must equal.
    fn scalar_footprint(s: &Sampler, level: &MipLevel, uv: Vec2) -> ([usize; 4], f32, f32) {
        let x = texel_coordinate(uv.x * level.width as f32 - 0.5);
        let y = texel_coordinate(uv.y * level.height as f32 - 0.5);
        let (xi, yi) = (floor_small(x), floor_small(y));
        let xa = address(xi, level.width, s.address_u) as usize;
        let xb = address(xi.saturating_add(1), level.width, s.address_u) as usize;
        let ya = address(yi, level.height, s.address_v) as usize;
        let yb = address(yi.saturating_add(1), level.height, s.address_v) as usize;
        let w = level.width as usize;
        (
            [ya * w + xa, ya * w + xb, yb * w + xa, yb * w + xb],
            x - xi as f32,
            y - yi as f32,
        )
    }

    /// Coordinates from far outside the texture to texel edges, with NaN and infinities.
    fn awkward_coordinates(k: u32) -> Vec2 {
        let special = [
            0.0,
            -0.0,
            1.0,
            0.5 / 16.0,
            -1e-9,
            1e9,
            -1e9,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            3.0e38,
        ];
        let wave = |k: u32, scale: f32| ((k as f32 * 0.618_034).fract() - 0.5) * scale;
        let pick = |k: u32, scale: f32| {
            if k.is_multiple_of(7) {
                special[(k / 7) as usize % special.len()]
            } else {
                wave(k, scale)
            }
        };
        Vec2::new(pick(k, 9.0), pick(k.wrapping_mul(31) + 3, 5.0))
    }

    #[test]
    fn packed_addressing_equals_the_scalar_rules() {
        let textures = [
            checker(16),
            Texture::from_rgba8(12, 5, (0..60u8).map(|i| [i, i, i, i * 4]).collect())
                .expect("texture"),
        ];
        let modes = [AddressMode::Wrap, AddressMode::Clamp];
        for texture in &textures {
            for (address_u, address_v) in modes.iter().flat_map(|&u| modes.map(|v| (u, v))) {
                let s = Sampler {
                    address_u,
                    address_v,
                    filter: Filter::Trilinear,
                };
                for k in 0..4000u32 {
                    let uv = awkward_coordinates(k);
                    let a = &texture.levels[k as usize % texture.levels.len()];
                    let b = &texture.levels[(k as usize + 1) % texture.levels.len()];
                    let levels = TrilinearLevels {
                        levels: [a, b],
                        blend: None,
                        addressing: s.footprint_addressing([a, b]),
                    };
                    let packed = levels.footprints(uv);
                    for (footprint, level) in packed.iter().zip([a, b]) {
                        let (texels, fx, fy) = scalar_footprint(&s, level, uv);
                        assert_eq!(footprint.texels, texels, "{uv} {address_u:?} {address_v:?}");
                        assert_eq!(footprint.fx.to_bits(), fx.to_bits(), "{uv}");
                        assert_eq!(footprint.fy.to_bits(), fy.to_bits(), "{uv}");
                    }
                    let points: [Vec2; 4] =
                        std::array::from_fn(|i| awkward_coordinates(k * 4 + i as u32));
                    let alphas = s.nearest_lookup(a).alpha_lanes(
                        points.map(|p| p.x),
                        points.map(|p| p.y),
                        SimdLevel::detected(),
                    );
                    for (alpha, point) in alphas.iter().zip(points) {
                        assert_eq!(alpha.to_bits(), s.alpha_nearest_in(a, point).to_bits());
                    }
                }
            }
        }
    }

    #[test]
    fn bilinear_matches_f64_weights() {
        let texels: Vec<[u8; 4]> = (0..16u8).map(|i| [i * 16, 255 - i * 16, i, 200]).collect();
        let t = Texture::from_rgba8(4, 4, texels.clone()).expect("texture");
        let s = Sampler {
            filter: Filter::Bilinear,
            ..Sampler::default()
        };
        for &(u, v) in &[(0.3f32, 0.6f32), (0.125, 0.125), (0.9, 0.05), (0.51, 0.49)] {
            let got = s.sample(&t, Vec2::new(u, v), Vec2::ZERO, Vec2::ZERO);
            let x = f64::from(u) * 4.0 - 0.5;
            let y = f64::from(v) * 4.0 - 0.5;
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let tex = |xi: f64, yi: f64, c: usize| {
                let xi = (xi as i64).rem_euclid(4) as usize;
                let yi = (yi as i64).rem_euclid(4) as usize;
                f64::from(texels[yi * 4 + xi][c]) / 255.0
            };
            for c in 0..4 {
                let e = (1.0 - fy) * ((1.0 - fx) * tex(x0, y0, c) + fx * tex(x0 + 1.0, y0, c))
                    + fy * ((1.0 - fx) * tex(x0, y0 + 1.0, c) + fx * tex(x0 + 1.0, y0 + 1.0, c));
                assert!(
                    (f64::from(got[c]) - e).abs() < 1e-6,
                    "uv ({u},{v}) c{c}: {} vs {e}",
                    got[c]
                );
            }
        }
    }

    #[test]
    fn alpha_nearest_is_the_alpha_of_the_nearest_texel() {
        let texels = (0..64u32 * 32)
            .map(|i| [(i % 251) as u8, (i % 7) as u8, 0, (i * 37 % 256) as u8])
            .collect();
        let t = Texture::from_rgba8(64, 32, texels).expect("texture");
        for (k, level) in [0usize, 1, 3].into_iter().enumerate() {
            let level = t.level(level).expect("level");
            let sampler = Sampler {
                address_u: [AddressMode::Wrap, AddressMode::Clamp][k % 2],
                address_v: AddressMode::Wrap,
                filter: Filter::Nearest,
            };
            for i in 0..2000 {
                let u = (i as f32 * 0.618_034).fract() * 3.0 - 1.0;
                let v = (i as f32 * 0.414_213_5).fract() * 2.0 - 0.5;
                let uv = match i % 50 {
                    0 => Vec2::new(f32::NAN, v),
                    1 => Vec2::new(u, f32::INFINITY),
                    _ => Vec2::new(u, v),
                };
                assert_eq!(
                    sampler.alpha_nearest_in(level, uv).to_bits(),
                    sampler.sample_nearest_in(level, uv).w.to_bits(),
                    "{uv}"
                );
            }
        }
    }

    /// `λ = ½·log2 ρ²` against f64: within 3 ulp of `λ` plus `2^-22` (the f32 rounding of
    /// `ρ²`, about 1.5 ulp of it, moves `log2 ρ²` by up to `2^-23.6`), over random derivatives
    /// from 2^-31 to 2^9 and texture sides from 1 to 2048; NaN gives 0, an infinite footprint
    /// `f32::MAX`, a zero one `−∞`.
    #[test]
    fn level_of_detail_against_f64() {
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            f32::from_bits(0x3000_0000 + state % 0x1400_0000)
                * if state & 1 == 0 { 1.0 } else { -1.0 }
        };
        for k in 0..200_000u32 {
            let (ddx, ddy) = (Vec2::new(next(), next()), Vec2::new(next(), next()));
            let (w, h) = (1 << (k % 12), 1 << (k / 7 % 12));
            let squared = |d: Vec2| {
                let (x, y) = (f64::from(d.x) * f64::from(w), f64::from(d.y) * f64::from(h));
                x * x + y * y
            };
            let exact = 0.5 * squared(ddx).max(squared(ddy)).log2();
            let got = f64::from(level_of_detail(ddx, ddy, w, h));
            let ulp = 2f64.powi(exact.abs().log2().floor() as i32 - 23);
            assert!(
                (got - exact).abs() <= 3.0 * ulp + 2f64.powi(-22),
                "{ddx} {ddy} {w}×{h}: {got} vs {exact}"
            );
        }
        let one = Vec2::new(1.0, 0.0);
        assert_eq!(level_of_detail(Vec2::NAN, one, 4, 4), 0.0);
        assert_eq!(level_of_detail(one, Vec2::new(0.0, f32::NAN), 4, 4), 0.0);
        assert_eq!(level_of_detail(Vec2::INFINITY, one, 4, 4), f32::MAX);
        assert_eq!(level_of_detail(Vec2::new(3e38, 0.0), one, 4, 4), f32::MAX);
        assert_eq!(
            level_of_detail(Vec2::ZERO, -Vec2::ZERO, 4, 4),
            f32::NEG_INFINITY
        );
        // Powers of two are exact: `log2 1 = 0` and the exponent is added exactly.
        assert_eq!(level_of_detail(one, Vec2::ZERO, 8, 8), 3.0);
        assert_eq!(
            level_of_detail(Vec2::new(0.0, 1.0 / 64.0), one / 1024.0, 16, 16),
            -2.0
        );
    }

    /// [`Texture::levels_of_footprint`] against the logarithm's levels, on chains of 1, 3, 8
    /// and 15 levels: every footprint within `FOOTPRINT_EXACT_WINDOW + 64` mantissa steps of
    /// each power of two (both paths and their border), zeros, subnormals, infinities, NaN,
    /// and 400,000 random bit patterns.
    #[test]
    fn levels_of_footprint_are_those_of_the_level_of_detail() {
        let textures = [(1, 1), (4, 4), (128, 96), (16384, 1)].map(|(w, h)| {
            Texture::from_rgba8(w, h, vec![[0; 4]; (w * h) as usize]).expect("texture")
        });
        let mut footprints = vec![0.0, -0.0, f32::NAN, f32::INFINITY, f32::MAX, 1e-40, 1e-45];
        let reach = FOOTPRINT_EXACT_WINDOW + 64;
        for e in 1..=254u32 {
            let power = e << 23;
            footprints.extend((power - reach.min(power)..power + reach).map(f32::from_bits));
        }
        let mut state = 0x9e37_79b9_u32;
        footprints.extend((0..400_000).map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            f32::from_bits(state >> 1)
        }));
        for texture in &textures {
            for &squared in &footprints {
                let lod = level_of_detail_of_footprint(squared);
                assert_eq!(
                    texture.levels_of_footprint(squared),
                    (
                        texture.trilinear_indices(lod).0,
                        texture.nearest_level_index(lod)
                    ),
                    "ρ² = {squared:e} ({:#x}), λ = {lod}, {} levels",
                    squared.to_bits(),
                    texture.level_count()
                );
            }
        }
    }

    #[test]
    fn level_of_detail_follows_the_footprint() {
        let one_texel = Vec2::new(1.0 / 256.0, 0.0);
        assert_eq!(level_of_detail(one_texel, Vec2::ZERO, 256, 256), 0.0);
        assert_eq!(level_of_detail(one_texel * 4.0, Vec2::ZERO, 256, 256), 2.0);
        assert_eq!(
            level_of_detail(Vec2::ZERO, Vec2::new(0.0, 8.0 / 256.0), 256, 256),
            3.0
        );
        assert_eq!(level_of_detail(Vec2::NAN, Vec2::ZERO, 256, 256), 0.0);
        let t = checker(16);
        let s = Sampler::default();
        // Far away (a footprint of many texels) the checkerboard blurs to grey.
        let far = s.sample(
            &t,
            Vec2::new(0.37, 0.61),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        );
        assert!((far.x - 128.0 / 255.0).abs() < 1e-6, "{far:?}");
        let inf = s.sample(&t, Vec2::new(0.37, 0.61), Vec2::INFINITY, Vec2::ZERO);
        assert_eq!(inf, far);
    }
}
