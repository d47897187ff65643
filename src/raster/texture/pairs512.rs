//! The texture pair of a 16-lane batch with AVX-512 ([`super::TrilinearPair::sample_lanes`] from
//! interleaved texels at [`crate::simd::SimdLevel::Avx512`]): two lanes' texels converted and
//! filtered in one 512-bit register, then the 16 lanes' results transposed into channel arrays
//! in registers.
//!
//! Why intrinsics: written as portable loops over two lanes' 16 channels, LLVM vectorised the
//! loop over the lane pairs instead (two lanes of one channel in a 128-bit register, each byte
//! taken out of the texel with a shift), and the transpose into channel arrays is 128 scalar
//! stores in the portable code. Here each lane pair costs a few 512-bit operations a corner,
//! and the transpose 24 two-register permutes (`vpermt2ps`) for the whole batch. Measured on
//! thesis-4-2 (docs/performance.md, "The AVX-512 level"): 16-lane batches without this path
//! took the same CPU as the AVX2 level's 8; with it, 14–15 % less.
//!
//! The same bits as [`super::BilinearFootprint::filter_converted`] and the per-lane blend of
//! `sample_lanes`: per channel, the same IEEE operations in the same order (the filter's
//! subtract, multiply, add on the bytes; the blend where a lane's fraction is not 0;
//! `unorm8_exact`'s multiply, multiply, add once at the end), with no fused multiply-add
//! (each intrinsic is one correctly rounded operation, and Rust never contracts them).

// Only x86-64 has this path; elsewhere `available` is false and the rest goes unused.
#![cfg_attr(not(target_arch = "x86_64"), allow(dead_code, unused_imports))]

use super::{FootprintLanes, PairChannels, PairTexel, UNORM8_CORRECTION, UNORM8_SCALE};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Lanes this path takes: a batch of [`crate::simd::WIDE_LANES`].
pub(super) const LANES: usize = 16;

/// Whether this CPU has what [`sample`] runs (AVX-512 F, BW, DQ, VL; cached).
#[inline]
pub(super) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::sync::OnceLock;
        static AVAILABLE: OnceLock<bool> = OnceLock::new();
        *AVAILABLE.get_or_init(|| {
            is_x86_feature_detected!("avx512f")
                && is_x86_feature_detected!("avx512bw")
                && is_x86_feature_detected!("avx512dq")
                && is_x86_feature_detected!("avx512vl")
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// The permutes of the transpose ([`transpose`]): `INDEX[s][t]` is table `t` of stage `s`, for
/// `vpermt2ps` (`out[j] = if idx[j] & 16 != 0 { b[idx[j] & 15] } else { a[idx[j] & 15] }`).
///
/// The layouts, lane `l` and channel `c` of position `j` of register `r`:
/// - rows (the filter's results): `l = 2r + j/8`, `c = j % 8`;
/// - stage 1, from rows `2g` and `2g + 1` (`r = 2g + h`): `l = 4g + j%4`, `c = 4h + j/4`;
/// - stage 2, from stage-1 registers `4g + h` and `4g + 2 + h` (`r = 4g + q`, `h = q/2`):
///   `l = 8g + j%8`, `c = 2q + j/8`;
/// - stage 3, from stage-2 registers `q` and `4 + q` (`r = c`, `q = c/2`): `l = j`.
const INDEX: [[[i32; 16]; 4]; 3] = transpose_indices();

const fn transpose_indices() -> [[[i32; 16]; 4]; 3] {
    let mut t = [[[0i32; 16]; 4]; 3];
    let mut j = 0;
    while j < 16 {
        // Stage 1: table h (channels 4h..4h+4 of four lanes).
        let mut h = 0;
        while h < 2 {
            let (lane, c) = (j % 4, 4 * h + j / 4);
            t[0][h][j] = ((lane % 2) * 8 + c + if lane >= 2 { 16 } else { 0 }) as i32;
            h += 1;
        }
        // Stage 2: table q (channels 2q, 2q + 1 of eight lanes).
        let mut q = 0;
        while q < 4 {
            let (lane, c) = (j % 8, 2 * q + j / 8);
            let local = c - 4 * (q / 2);
            t[1][q][j] = ((lane % 4) + 4 * local + if lane >= 4 { 16 } else { 0 }) as i32;
            q += 1;
        }
        // Stage 3: table c % 2 (one channel of sixteen lanes).
        let mut odd = 0;
        while odd < 2 {
            t[2][odd][j] = ((j % 8) + 8 * odd + if j >= 8 { 16 } else { 0 }) as i32;
            odd += 1;
        }
        j += 1;
    }
    t
}

/// The transpose of eight rows (lanes `2r` and `2r + 1`, eight channels each) into eight
/// channels of sixteen lanes, through `permute(a, table, b)` (`vpermt2ps`'s rule): the wiring of
/// [`INDEX`]'s stages, shared by the AVX-512 code and its test.
#[inline(always)]
fn transpose<V: Copy>(rows: [V; 8], mut permute: impl FnMut(V, &[i32; 16], V) -> V) -> [V; 8] {
    let one: [V; 8] = std::array::from_fn(|r| {
        let (g, h) = (r / 2, r % 2);
        permute(rows[2 * g], &INDEX[0][h], rows[2 * g + 1])
    });
    let two: [V; 8] = std::array::from_fn(|r| {
        let (g, q) = (r / 4, r % 4);
        let h = q / 2;
        permute(one[4 * g + h], &INDEX[1][q], one[4 * g + 2 + h])
    });
    std::array::from_fn(|c| {
        let q = c / 2;
        permute(two[q], &INDEX[2][c % 2], two[4 + q])
    })
}

/// `TrilinearPair::sample_lanes` of a 16-lane batch from interleaved levels `lower` and
/// `upper`: the footprints `low` (lower level) and `high` (upper level; read only where a
/// lane's `frac` is not 0), each lane's blend fraction `frac`.
///
/// # Safety
/// The CPU has AVX-512 F, BW, DQ and VL ([`available`]); `N` is [`LANES`]; every texel index
/// of `low` is within `lower` and, for lanes whose fraction is not 0 and the other lane of
/// their pair, every index of `high` within `upper` (as `footprint_lanes` addresses them).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
pub(super) unsafe fn sample<const N: usize>(
    low: &FootprintLanes<N>,
    high: &FootprintLanes<N>,
    frac: &[f32; N],
    lower: &[PairTexel],
    upper: &[PairTexel],
) -> PairChannels<N> {
    assert!(N == LANES);
    // The four texel indices of every lane (rows plus columns, as `FootprintLanes::lane`).
    let indices = |f: &FootprintLanes<N>| -> [[i32; LANES]; 4] {
        let mut out = [[0i32; LANES]; 4];
        for (k, (row, column)) in [
            (&f.rows.0, &f.x.0),
            (&f.rows.0, &f.x.1),
            (&f.rows.1, &f.x.0),
            (&f.rows.1, &f.x.1),
        ]
        .into_iter()
        .enumerate()
        {
            // SAFETY: `N` is 16, so each array is one 512-bit register wide.
            unsafe {
                let sum = _mm512_add_epi32(
                    _mm512_loadu_si512(row.as_ptr().cast()),
                    _mm512_loadu_si512(column.as_ptr().cast()),
                );
                _mm512_storeu_si512(out[k].as_mut_ptr().cast(), sum);
            }
        }
        out
    };
    let (scale, correction) = (
        _mm512_set1_ps(UNORM8_SCALE),
        _mm512_set1_ps(UNORM8_CORRECTION),
    );
    // Texel `index[a]` of lane a in channels 0–7 and `index[b]` of lane b in 8–15, as bytes.
    let texels = |level: &[PairTexel], a: usize, b: usize| -> __m512 {
        // SAFETY: the function's contract puts both indices within `level`; a `PairTexel` is
        // 8 bytes, read unaligned.
        unsafe {
            let first = _mm_loadl_epi64(level.as_ptr().add(a).cast());
            let both = _mm_castpd_si128(_mm_loadh_pd(
                _mm_castsi128_pd(first),
                level.as_ptr().add(b).cast(),
            ));
            _mm512_cvtepi32_ps(_mm512_cvtepu8_epi32(both))
        }
    };
    // Lane a's value in channels 0–7, lane b's in 8–15.
    let pair = |a: f32, b: f32| _mm512_mask_blend_ps(0xff00, _mm512_set1_ps(a), _mm512_set1_ps(b));
    // `BilinearFootprint::filter_converted` of lanes 2p and 2p + 1.
    let filter = |level: &[PairTexel], index: &[[i32; LANES]; 4], f: &FootprintLanes<N>, p| {
        let (a, b) = (2 * p, 2 * p + 1);
        let t: [__m512; 4] =
            std::array::from_fn(|k| texels(level, index[k][a] as usize, index[k][b] as usize));
        let (fx, fy) = (pair(f.fx[a], f.fx[b]), pair(f.fy[a], f.fy[b]));
        let top = _mm512_add_ps(t[0], _mm512_mul_ps(_mm512_sub_ps(t[1], t[0]), fx));
        let bottom = _mm512_add_ps(t[2], _mm512_mul_ps(_mm512_sub_ps(t[3], t[2]), fx));
        _mm512_add_ps(top, _mm512_mul_ps(_mm512_sub_ps(bottom, top), fy))
    };
    let low_index = indices(low);
    let mut high_index = None;
    let rows: [__m512; 8] = std::array::from_fn(|p| {
        let mut both = filter(lower, &low_index, low, p);
        let (a, b) = (2 * p, 2 * p + 1);
        if frac[a] != 0.0 || frac[b] != 0.0 {
            let index = high_index.get_or_insert_with(|| indices(high));
            let upper = filter(upper, index, high, p);
            let f = pair(frac[a], frac[b]);
            let blended = _mm512_add_ps(both, _mm512_mul_ps(_mm512_sub_ps(upper, both), f));
            // `!=` as Rust's: true for NaN, false for −0.
            let blends = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(f, _mm512_setzero_ps());
            both = _mm512_mask_mov_ps(both, blends, blended);
        }
        both
    });
    let channels = transpose(rows, |a, table, b| {
        // SAFETY: a 16-element table, read unaligned.
        let index = unsafe { _mm512_loadu_si512(table.as_ptr().cast()) };
        _mm512_permutex2var_ps(a, index, b)
    });
    let mut out = [[0.0f32; N]; 8];
    for (c, channel) in channels.into_iter().enumerate() {
        // `unorm8_exact` of the filtered bytes: the one scaling, after the blend.
        let y = _mm512_mul_ps(channel, scale);
        let scaled = _mm512_add_ps(y, _mm512_mul_ps(y, correction));
        // SAFETY: `N` is 16: one register fills the channel's array.
        unsafe { _mm512_storeu_ps(out[c].as_mut_ptr(), scaled) };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `vpermt2ps`'s rule on plain arrays.
    fn permute(a: [f32; 16], table: &[i32; 16], b: [f32; 16]) -> [f32; 16] {
        std::array::from_fn(|j| {
            let i = table[j] as usize;
            if i & 16 != 0 { b[i & 15] } else { a[i & 15] }
        })
    }

    #[test]
    fn the_transpose_gives_channel_arrays() {
        // Row r holds lane 2r's channels, then lane 2r + 1's; value = 100·lane + channel.
        let rows: [[f32; 16]; 8] = std::array::from_fn(|r| {
            std::array::from_fn(|j| (100 * (2 * r + j / 8) + j % 8) as f32)
        });
        let channels = transpose(rows, permute);
        for (c, channel) in channels.iter().enumerate() {
            for (lane, &value) in channel.iter().enumerate() {
                assert_eq!(value, (100 * lane + c) as f32, "channel {c} lane {lane}");
            }
        }
        for stage in INDEX {
            for table in stage {
                assert!(table.iter().all(|&i| (0..32).contains(&i)));
            }
        }
    }
}
