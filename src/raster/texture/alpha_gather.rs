//! The shell shadow's nearest alpha reads of a batch with gathers
//! ([`super::NearestLookup::alpha_lanes`] from a level's alpha plane, where both axes wrap on a
//! power-of-two size): 16 lanes with AVX-512 ([`nearest`]), a multiple of 8 with AVX2
//! ([`nearest_avx2`], 8 a register: a batch of 32 at that level), the coordinates, floors and
//! addressing of the lanes in one register each, and their alpha bytes in one gather a
//! register.
//!
//! Why intrinsics: written as portable loops, LLVM split the 16-lane coordinate steps into two
//! 256-bit halves, widened the row products to 64 bits (`vpmullq`) and read the bytes as 16 scalar
//! loads, each index taken out of a register first and each byte inserted into one after:
//! about a hundred instructions a lookup of 16 lanes, and on thesis-4-2 a lookup happens 2.7
//! times a fragment (at 8 lanes, the same scalar loads and inserts). A gather reads the bytes in
//! one instruction; the alpha plane carries [`ALPHA_PLANE_PADDING`] bytes after its last texel
//! so that the gather's 4-byte reads stay inside it.
//!
//! The same bits as the portable loops: the same IEEE operations in the same order
//! (`c·size − 0`, the clamp to `±COORDINATE_LIMIT`, a non-finite position as 0, the truncation
//! and the floor's correction, `unorm8_exact`'s multiply, multiply, add), and the same integer
//! index (`row·width + column` is below 2³¹ because a level has at most
//! `MAX_TEXTURE_SIZE²` = 2²⁸ texels).

// Only x86-64 has this path; elsewhere it goes unused.
#![cfg_attr(not(target_arch = "x86_64"), allow(dead_code, unused_imports))]

use super::{COORDINATE_LIMIT, UNORM8_CORRECTION, UNORM8_SCALE};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Lanes this path takes: a batch of [`crate::simd::WIDE_LANES`].
pub(super) const LANES: usize = 16;

/// Bytes after the last texel of each alpha plane, so that a 4-byte read at any texel stays
/// inside the plane.
pub(super) const ALPHA_PLANE_PADDING: usize = 3;

/// The alphas (`byte/255`) of the texels nearest to `(u[i]·width, v[i]·height)` on a level of
/// `width × height` texels whose alpha plane is `plane`, both axes wrapped by `mask_u`
/// (`width − 1`) and `mask_v` (`height − 1`).
///
/// # Safety
/// The CPU has AVX-512 F, BW, DQ and VL ([`super::pairs512::available`]); `N` is [`LANES`];
/// `width` and `height` are powers of two with `mask_u = width − 1`, `mask_v = height − 1`;
/// `plane` holds `width × height + ALPHA_PLANE_PADDING` bytes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
pub(super) unsafe fn nearest<const N: usize>(
    u: &[f32; N],
    v: &[f32; N],
    width: u32,
    height: u32,
    [mask_u, mask_v]: [i32; 2],
    plane: &[u8],
) -> [f32; N] {
    assert!(N == LANES);
    // `lane_axis(c, size, 0)`: `⌊x⌋` of `x = texel_coordinate(c·size − 0)`.
    let floor_of = |c: &[f32; N], size: u32| -> __m512i {
        // SAFETY: `N` is 16, one 512-bit register.
        let c = unsafe { _mm512_loadu_ps(c.as_ptr()) };
        let position = _mm512_sub_ps(
            _mm512_mul_ps(c, _mm512_set1_ps(size as f32)),
            _mm512_setzero_ps(),
        );
        let (low, high) = (
            _mm512_set1_ps(-COORDINATE_LIMIT),
            _mm512_set1_ps(COORDINATE_LIMIT),
        );
        // `if position < −L { −L } else { position }`, then `if clamped > L { L } …` (ordered
        // compares: NaN stays).
        let clamped = _mm512_mask_mov_ps(
            position,
            _mm512_cmp_ps_mask::<_CMP_LT_OQ>(position, low),
            low,
        );
        let clamped = _mm512_mask_mov_ps(
            clamped,
            _mm512_cmp_ps_mask::<_CMP_GT_OQ>(clamped, high),
            high,
        );
        // `position.is_finite()`: its bits without the sign below infinity's.
        let magnitude =
            _mm512_and_si512(_mm512_castps_si512(position), _mm512_set1_epi32(i32::MAX));
        let finite = _mm512_cmplt_epi32_mask(magnitude, _mm512_set1_epi32(0x7f80_0000));
        let x = _mm512_maskz_mov_ps(finite, clamped);
        // `|x| ≤ 2³⁰`: the truncation is exact; one down where it rounded up.
        let truncated = _mm512_cvttps_epi32(x);
        let rounded_up = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(_mm512_cvtepi32_ps(truncated), x);
        _mm512_mask_sub_epi32(truncated, rounded_up, truncated, _mm512_set1_epi32(1))
    };
    let column = _mm512_and_si512(floor_of(u, width), _mm512_set1_epi32(mask_u));
    let row = _mm512_and_si512(floor_of(v, height), _mm512_set1_epi32(mask_v));
    let index = _mm512_add_epi32(
        _mm512_mullo_epi32(row, _mm512_set1_epi32(width as i32)),
        column,
    );
    // SAFETY: each index is below `width × height` (a masked row times the width plus a masked
    // column), and the plane has `ALPHA_PLANE_PADDING` bytes after its last texel: every 4-byte
    // read is inside it.
    let words = unsafe { _mm512_i32gather_epi32::<1>(index, plane.as_ptr().cast()) };
    let bytes = _mm512_and_si512(words, _mm512_set1_epi32(0xff));
    // `unorm8_exact`.
    let y = _mm512_mul_ps(_mm512_cvtepi32_ps(bytes), _mm512_set1_ps(UNORM8_SCALE));
    let alphas = _mm512_add_ps(y, _mm512_mul_ps(y, _mm512_set1_ps(UNORM8_CORRECTION)));
    let mut out = [0.0f32; N];
    // SAFETY: `N` is 16: one register fills the array.
    unsafe { _mm512_storeu_ps(out.as_mut_ptr(), alphas) };
    out
}

/// Lanes of one AVX2 register in [`nearest_avx2`], which takes one or two of them (the AVX2
/// level's batches hold two).
pub(super) const AVX2_LANES: usize = 8;

/// Whether this CPU has AVX2 (cached), which [`nearest_avx2`] runs.
#[inline]
pub(super) fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::sync::OnceLock;
        static AVAILABLE: OnceLock<bool> = OnceLock::new();
        *AVAILABLE.get_or_init(|| is_x86_feature_detected!("avx2"))
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// [`nearest`] of a batch of the AVX2 level with AVX2: a multiple of 8 lanes (the level's
/// batches hold 32, its narrower stages 16 or 8), each 8 in 256-bit registers with one 8-lane
/// gather; the same steps and the same bits.
///
/// # Safety
/// The CPU has AVX2 ([`avx2_available`]); `N` is a multiple of [`AVX2_LANES`]; the rest as
/// [`nearest`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn nearest_avx2<const N: usize>(
    u: &[f32; N],
    v: &[f32; N],
    width: u32,
    height: u32,
    [mask_u, mask_v]: [i32; 2],
    plane: &[u8],
) -> [f32; N] {
    assert!(N.is_multiple_of(AVX2_LANES));
    let floor_of = |c: &[f32], size: u32| -> __m256i {
        assert!(c.len() == AVX2_LANES);
        // SAFETY: 8 floats, one 256-bit register.
        let c = unsafe { _mm256_loadu_ps(c.as_ptr()) };
        let position = _mm256_sub_ps(
            _mm256_mul_ps(c, _mm256_set1_ps(size as f32)),
            _mm256_setzero_ps(),
        );
        let (low, high) = (
            _mm256_set1_ps(-COORDINATE_LIMIT),
            _mm256_set1_ps(COORDINATE_LIMIT),
        );
        let clamped = _mm256_blendv_ps(position, low, _mm256_cmp_ps::<_CMP_LT_OQ>(position, low));
        let clamped = _mm256_blendv_ps(clamped, high, _mm256_cmp_ps::<_CMP_GT_OQ>(clamped, high));
        let magnitude =
            _mm256_and_si256(_mm256_castps_si256(position), _mm256_set1_epi32(i32::MAX));
        let finite = _mm256_cmpgt_epi32(_mm256_set1_epi32(0x7f80_0000), magnitude);
        let x = _mm256_and_ps(clamped, _mm256_castsi256_ps(finite));
        let truncated = _mm256_cvttps_epi32(x);
        // All ones (−1) where the truncation rounded up.
        let rounded_up = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(
            _mm256_cvtepi32_ps(truncated),
            x,
        ));
        _mm256_add_epi32(truncated, rounded_up)
    };
    let mut out = [0.0f32; N];
    // Eight lanes a register.
    for ((u, v), out) in u
        .chunks_exact(AVX2_LANES)
        .zip(v.chunks_exact(AVX2_LANES))
        .zip(out.chunks_exact_mut(AVX2_LANES))
    {
        let column = _mm256_and_si256(floor_of(u, width), _mm256_set1_epi32(mask_u));
        let row = _mm256_and_si256(floor_of(v, height), _mm256_set1_epi32(mask_v));
        let index = _mm256_add_epi32(
            _mm256_mullo_epi32(row, _mm256_set1_epi32(width as i32)),
            column,
        );
        // SAFETY: as in `nearest`: every 4-byte read is inside the padded plane.
        let words = unsafe { _mm256_i32gather_epi32::<1>(plane.as_ptr().cast(), index) };
        let bytes = _mm256_and_si256(words, _mm256_set1_epi32(0xff));
        let y = _mm256_mul_ps(_mm256_cvtepi32_ps(bytes), _mm256_set1_ps(UNORM8_SCALE));
        let alphas = _mm256_add_ps(y, _mm256_mul_ps(y, _mm256_set1_ps(UNORM8_CORRECTION)));
        // SAFETY: `out` is a chunk of 8 floats: one register fills it.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), alphas) };
    }
    out
}
