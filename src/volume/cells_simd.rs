//! The unorm8 cells copy's blocks of sixteen cells packed with SSE2
//! (`cells.rs` packs the rest cell by cell): stored plainly for a whole
//! copy, or streamed past the cache for a series step's scattered blocks.

/// Sixteen unorm8 cells at a time, by byte, pair and quad interleaves
/// (SSE2, which every x86-64 CPU has): one cell at a time, nbody:256's
/// 17 million cells packed in 18 to 26 ms on lavapipe's two cores, so
/// in 8 to 16 (a plain fill of those 136 MB takes 8).
#[cfg(target_arch = "x86_64")]
pub(crate) fn pack_u8_blocks(out: &mut [u8], rows: [&[u8]; 4]) -> usize {
    pack_u8_blocks_as::<false>(out, rows)
}

/// As `pack_u8_blocks`, with non-temporal stores: for blocks scattered
/// over the cells copy (a series step's changed cells, `cells_delta.rs`),
/// whose lines are not in cache and would otherwise be read in before
/// they are overwritten (nbody:256's changed blocks: 15-20 ms to 10-12
/// on an EPYC host). Slower for a whole copy, which the CPU streams anyway.
///
/// # Safety
/// The calling thread must run `_mm_sfence` after it and before `out` is
/// read or written again by any thread, this one included: until then
/// the streamed stores are not ordered with other accesses.
#[cfg(target_arch = "x86_64")]
pub(crate) unsafe fn stream_u8_blocks(out: &mut [u8], rows: [&[u8]; 4]) -> usize {
    pack_u8_blocks_as::<true>(out, rows)
}

/// Packs nothing (no SIMD here): `cells_delta.rs` packs cell by cell.
///
/// # Safety
/// None: nothing is streamed.
#[cfg(not(target_arch = "x86_64"))]
pub(crate) unsafe fn stream_u8_blocks(_: &mut [u8], _: [&[u8]; 4]) -> usize {
    0
}

#[cfg(target_arch = "x86_64")]
fn pack_u8_blocks_as<const STREAM: bool>(out: &mut [u8], rows: [&[u8]; 4]) -> usize {
    use std::arch::x86_64::{
        __m128i, _mm_cvtsi128_si64, _mm_loadu_si128, _mm_storeu_si128, _mm_stream_si64, _mm_unpackhi_epi16,
        _mm_unpackhi_epi32, _mm_unpackhi_epi64, _mm_unpackhi_epi8, _mm_unpacklo_epi16, _mm_unpacklo_epi32,
        _mm_unpacklo_epi8,
    };
    // Cell m reads voxels m and m + 1 of each row: a block of 16 reads 17.
    let blocks = (rows[0].len().saturating_sub(1) / 16).min(out.len() / 128);
    for b in 0..blocks {
        let m = 16 * b;
        let o = &mut out[128 * b..][..128];
        // SAFETY: every load reads 16 bytes of a slice of 16 (checked by
        // the slicing), every store writes 16 bytes within `o`'s 128 (a
        // streamed one as two 8-byte words: movnti takes any alignment,
        // and the fence is `stream_u8_blocks`'s caller's); loadu and
        // storeu take any alignment, and SSE2 is part of x86-64.
        unsafe {
            let load = |r: &[u8], at: usize| _mm_loadu_si128(r[at..at + 16].as_ptr() as *const __m128i);
            // Per row, the (m, m + 1) byte pairs of cells 0-7 and 8-15.
            let pairs = rows.map(|r| {
                let (a, b) = (load(r, m), load(r, m + 1));
                (_mm_unpacklo_epi8(a, b), _mm_unpackhi_epi8(a, b))
            });
            // Rows 0 and 1, rows 2 and 3: a quad per cell, four cells a vector.
            let quads = |p: (__m128i, __m128i), q: (__m128i, __m128i)| {
                [
                    _mm_unpacklo_epi16(p.0, q.0),
                    _mm_unpackhi_epi16(p.0, q.0),
                    _mm_unpacklo_epi16(p.1, q.1),
                    _mm_unpackhi_epi16(p.1, q.1),
                ]
            };
            let (lo, hi) = (quads(pairs[0], pairs[1]), quads(pairs[2], pairs[3]));
            for k in 0..4 {
                // Two cells a vector: their low quads, then their high ones.
                let at = o[32 * k..].as_mut_ptr() as *mut __m128i;
                let pair = [_mm_unpacklo_epi32(lo[k], hi[k]), _mm_unpackhi_epi32(lo[k], hi[k])];
                if STREAM {
                    // 16-byte streaming stores need alignment rows of
                    // cells do not keep (8 bytes a cell).
                    let words = at as *mut i64;
                    for (i, v) in pair.into_iter().enumerate() {
                        _mm_stream_si64(words.add(2 * i), _mm_cvtsi128_si64(v));
                        _mm_stream_si64(words.add(2 * i + 1), _mm_cvtsi128_si64(_mm_unpackhi_epi64(v, v)));
                    }
                } else {
                    _mm_storeu_si128(at, pair[0]);
                    _mm_storeu_si128(at.add(1), pair[1]);
                }
            }
        }
    }
    16 * blocks
}

#[cfg(not(target_arch = "x86_64"))]
pub(crate) fn pack_u8_blocks(_: &mut [u8], _: [&[u8]; 4]) -> usize {
    0
}
