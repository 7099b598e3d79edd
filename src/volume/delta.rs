//! What changed between two time steps on one grid, found on the host by
//! comparing their texels: per row of voxels along x, a bit per segment of
//! [`SEGMENT`] voxels whose texels differ. A new step then rewrites only
//! the cells copy around changed segments (`cells::repack_changed`) and
//! recomputes only the value ranges of bricks whose apron holds one
//! (`bricks_changed`); everything else stays as the step before left it,
//! equal bit for bit to what a full upload makes. In a simulation's series
//! most of the volume repeats from step to step (nbody:256: 3 % of voxels,
//! 14 % of 4^3 bricks change a step).

use rayon::iter::Either;
use rayon::prelude::*;
use std::ops::RangeInclusive;

/// Voxels per segment along x: a brick of 4 (the distance maps' finest
/// cell) is one segment, so its apron reaches one segment either side.
pub const SEGMENT: u32 = 4;

/// The changed segments of each row of voxels between two steps.
#[derive(Clone, Debug, PartialEq)]
pub struct StepDelta {
    dims: [u32; 3],
    /// u64 words of segment bits per row.
    words: usize,
    /// Row (y + H * z)'s bits at `words * row`: bit s of word w is segment
    /// 64 * w + s (voxels SEGMENT * that up to SEGMENT more).
    bits: Vec<u64>,
    /// For 1-byte texels, the same bits for a segment's first voxel and
    /// for its last (a short last segment: any voxel of it): a brick's
    /// apron reads one voxel of the segments either side, so only those
    /// ends' changes reach it (`bricks_changed`). None: any voxel.
    ends: Option<[Vec<u64>; 2]>,
    changed: u64,
}

impl StepDelta {
    /// The segments whose texels differ between `a` and `b`, each every
    /// texel of a volume of `dims` (x fastest, texels of one size), or
    /// None where their sizes differ (`StepDelta::between` compares two
    /// volumes).
    pub fn of_texels(dims: [u32; 3], a: &[u8], b: &[u8]) -> Option<StepDelta> {
        let row_bytes = row_bytes(dims, a.len(), b.len())?;
        let rows = a.par_chunks(row_bytes).zip(b.par_chunks(row_bytes));
        Some(Self::of_rows(dims, row_bytes, rows, |_, _| {}))
    }

    /// As `of_texels(dims, before, after)`, turning `before` into `after`
    /// on the way (each row that differs copied while it is in cache): a
    /// copy of the step before's texels (a CPU device's staging mirror)
    /// brought up to date in the pass that compares them, where
    /// `copy_changed` would read the changed segments again.
    pub fn of_texels_updating(dims: [u32; 3], before: &mut [u8], after: &[u8]) -> Option<StepDelta> {
        let row_bytes = row_bytes(dims, before.len(), after.len())?;
        let rows = before.par_chunks_mut(row_bytes).zip(after.par_chunks(row_bytes));
        Some(Self::of_rows(dims, row_bytes, rows, |a: &mut [u8], b| {
            a.copy_from_slice(b)
        }))
    }

    /// The delta of rows (a, b) of `row_bytes` (every row of a volume of
    /// `dims`, in order), `changed` called on each pair that differs.
    fn of_rows<'a, A: std::ops::Deref<Target = [u8]> + Send>(
        dims: [u32; 3],
        row_bytes: usize,
        rows: impl IndexedParallelIterator<Item = (A, &'a [u8])>,
        changed: impl Fn(A, &[u8]) + Sync + Send,
    ) -> StepDelta {
        let [w, h, d] = dims.map(|n| n as usize);
        let seg_bytes = row_bytes / w * SEGMENT as usize;
        let words = w.div_ceil(SEGMENT as usize).div_ceil(64);
        let mut bits = vec![0u64; h * d * words];
        let mut ends = (seg_bytes == 4).then(|| [vec![0u64; h * d * words], vec![0u64; h * d * words]]);
        let row_ends = match &mut ends {
            // 1-byte texels: with the segments' ends.
            Some([first, last]) => Either::Left(first.par_chunks_mut(words).zip(last.par_chunks_mut(words)).map(Some)),
            None => Either::Right((0..h * d).into_par_iter().map(|_| None)),
        };
        bits.par_chunks_mut(words)
            .zip(row_ends)
            .zip(rows)
            .for_each(|((out, ends), (ra, rb))| {
                if *ra == *rb {
                    return;
                }
                match (ends, seg_bytes) {
                    (Some((first, last)), _) => mark_segments_u8(&ra, rb, [out, first, last]),
                    // Fixed-size compares (a slice compare of a length known
                    // only at run time is a call per segment: 4x slower).
                    (None, 8) => mark_segments::<8>(&ra, rb, out),
                    (None, 16) => mark_segments::<16>(&ra, rb, out),
                    (None, _) => {
                        for (s, (sa, sb)) in ra.chunks(seg_bytes).zip(rb.chunks(seg_bytes)).enumerate() {
                            if sa != sb {
                                out[s / 64] |= 1 << (s % 64);
                            }
                        }
                    }
                }
                changed(ra, rb);
            });
        let changed = bits.iter().map(|w| w.count_ones() as u64).sum();
        StepDelta {
            dims,
            words,
            bits,
            ends,
            changed,
        }
    }

    /// The volume's dims.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// Whether any voxel changed.
    pub fn any(&self) -> bool {
        self.changed > 0
    }

    /// The share of segments that changed, in [0, 1].
    pub fn fraction(&self) -> f64 {
        let [w, h, d] = self.dims.map(|n| n as u64);
        let total = w.div_ceil(SEGMENT as u64) * h * d;
        self.changed as f64 / total.max(1) as f64
    }

    /// Row (y, z)'s segment bits (`words` u64s).
    pub fn row(&self, y: u32, z: u32) -> &[u64] {
        let r = y as usize + self.dims[1] as usize * z as usize;
        &self.bits[r * self.words..][..self.words]
    }

    /// The OR of the segment bits of rows `ys` x `zs` into `acc` (cleared
    /// first, `row(0, 0).len()` words): the segments any of them changed.
    pub fn rows_or(&self, ys: RangeInclusive<u32>, zs: RangeInclusive<u32>, acc: &mut [u64]) {
        self.or_rows(&self.bits, ys, zs, acc);
    }

    /// `rows_or` of the rows of `set` (`bits` or one of `ends`).
    fn or_rows(&self, set: &[u64], ys: RangeInclusive<u32>, zs: RangeInclusive<u32>, acc: &mut [u64]) {
        acc.fill(0);
        for z in zs {
            for y in ys.clone() {
                let r = y as usize + self.dims[1] as usize * z as usize;
                for (a, r) in acc.iter_mut().zip(&set[r * self.words..][..self.words]) {
                    *a |= r;
                }
            }
        }
    }

    /// Whether a voxel of x in [x0, x1] changed in row bits `row`.
    pub fn row_any(row: &[u64], x0: u32, x1: u32) -> bool {
        let (s0, s1) = ((x0 / SEGMENT) as usize, (x1 / SEGMENT) as usize);
        // The bits below `n` of a word.
        let low = |n: usize| if n >= 64 { !0 } else { (1u64 << n) - 1 };
        let (w0, w1) = (s0 / 64, s1 / 64);
        if w0 == w1 {
            return row[w0] >> (s0 % 64) & low(s1 - s0 + 1) != 0;
        }
        row[w0] >> (s0 % 64) != 0 || row[w0 + 1..w1].iter().any(|&w| w != 0) || row[w1] & low(s1 % 64 + 1) != 0
    }

    /// Copies the changed segments' texels from `src` into `dst`, each
    /// every texel of a volume of these dims (x fastest, texels of one
    /// size, as `of_texels` compared them), leaving the rest of `dst` as it
    /// is: `dst` held the step before, and holds `src`'s step after.
    /// False, copying nothing, where their sizes do not fit these dims.
    pub fn copy_changed(&self, src: &[u8], dst: &mut [u8]) -> bool {
        let [w, h, d] = self.dims.map(|n| n as usize);
        let rows = h * d;
        if src.len() != dst.len() || !src.len().is_multiple_of(rows * w) {
            return false;
        }
        let row_bytes = src.len() / rows;
        let seg = row_bytes / w * SEGMENT as usize;
        dst.par_chunks_mut(row_bytes)
            .zip(src.par_chunks(row_bytes))
            .zip(self.bits.par_chunks(self.words))
            .for_each(|((out, row), bits)| {
                for (wi, &word) in bits.iter().enumerate() {
                    let mut left = word;
                    while left != 0 {
                        let at = (64 * wi + left.trailing_zeros() as usize) * seg;
                        left &= left - 1;
                        let end = (at + seg).min(row_bytes);
                        out[at..end].copy_from_slice(&row[at..end]);
                    }
                }
            });
        true
    }

    /// Boxes (low corner, extent) that cover every changed voxel: the
    /// bricks of edge `brick` that hold one, each run of them along x one
    /// box, clipped to the volume; what an upload of the change copies.
    pub fn boxes(&self, brick: u32) -> Vec<([u32; 3], [u32; 3])> {
        let counts = self.dims.map(|n| n.div_ceil(brick));
        let span = |b: u32, n: u32| (b * brick, (b * brick + brick).min(n) - b * brick);
        let rows: Vec<Vec<([u32; 3], [u32; 3])>> = (0..counts[2])
            .into_par_iter()
            .map(|bz| {
                let mut found = Vec::new();
                let (z0, nz) = span(bz, self.dims[2]);
                let mut acc = vec![0u64; self.words];
                for by in 0..counts[1] {
                    let (y0, ny) = span(by, self.dims[1]);
                    self.rows_or(y0..=y0 + ny - 1, z0..=z0 + nz - 1, &mut acc);
                    let mut run: Option<u32> = None;
                    for bx in 0..=counts[0] {
                        let changed = bx < counts[0] && {
                            let (x0, nx) = span(bx, self.dims[0]);
                            Self::row_any(&acc, x0, x0 + nx - 1)
                        };
                        match (changed, run) {
                            (true, None) => run = Some(bx),
                            (false, Some(first)) => {
                                let x0 = first * brick;
                                let x1 = (bx * brick).min(self.dims[0]);
                                found.push(([x0, y0, z0], [x1 - x0, ny, nz]));
                                run = None;
                            }
                            _ => {}
                        }
                    }
                }
                found
            })
            .collect();
        rows.into_iter().flatten().collect()
    }

    /// The bricks of edge `brick` (x fastest, as `brick_counts` counts
    /// them) whose box widened by a one-voxel apron, clamped to the volume,
    /// holds a changed voxel: the bricks whose ranges differ from the step
    /// before's, or a few more (a segment changes as a whole, except at the
    /// ends an apron reads where `ends` are known: nbody:256's steps list
    /// 21 % of the 4^3 bricks so, 26 % by whole segments).
    pub fn bricks_changed(&self, brick: u32) -> Vec<u32> {
        let [w, h, d] = self.dims;
        let counts = self.dims.map(|n| n.div_ceil(brick));
        let span = |b: u32, n: u32| ((b * brick).saturating_sub(1), (b * brick + brick).min(n - 1));
        // A brick's own segments, and the apron's voxel either side as the
        // last of the segment before and the first of the one after.
        let ends = self.ends.as_ref().filter(|_| brick.is_multiple_of(SEGMENT));
        let bit = |row: &[u64], s: u32| row[s as usize / 64] >> (s % 64) & 1 != 0;
        // Per (brick y, z) of rows: the OR of the rows its apron'd box reads.
        let out: Vec<Vec<u32>> = (0..counts[2])
            .into_par_iter()
            .map(|bz| {
                let mut found = Vec::new();
                let (z0, z1) = span(bz, d);
                let mut acc = vec![0u64; self.words];
                let mut acc_ends = [vec![0u64; self.words], vec![0u64; self.words]];
                for by in 0..counts[1] {
                    let (y0, y1) = span(by, h);
                    self.rows_or(y0..=y1, z0..=z1, &mut acc);
                    if acc.iter().all(|&a| a == 0) {
                        continue;
                    }
                    if let Some(ends) = ends {
                        for (set, acc) in ends.iter().zip(&mut acc_ends) {
                            self.or_rows(set, y0..=y1, z0..=z1, acc);
                        }
                    }
                    for bx in 0..counts[0] {
                        let (x0, x1) = span(bx, w);
                        let changed = match ends {
                            None => Self::row_any(&acc, x0, x1),
                            Some(_) => {
                                let (own0, own1) = (bx * brick, (bx * brick + brick - 1).min(w - 1));
                                Self::row_any(&acc, own0, own1)
                                    || (own0 > 0 && bit(&acc_ends[1], own0 / SEGMENT - 1))
                                    || (own1 + 1 < w && bit(&acc_ends[0], (own1 + 1) / SEGMENT))
                            }
                        };
                        if changed {
                            found.push(bx + counts[0] * (by + counts[1] * bz));
                        }
                    }
                }
                found
            })
            .collect();
        out.into_iter().flatten().collect()
    }
}

/// Bytes per row of voxels of two volumes of `dims` of `a` and `b` bytes
/// (texels of one size), or None where they differ or do not fit.
fn row_bytes(dims: [u32; 3], a: usize, b: usize) -> Option<usize> {
    let [w, h, d] = dims.map(|n| n as usize);
    let rows = h * d;
    (a == b && rows > 0 && w > 0 && a.is_multiple_of(rows * w)).then(|| a / rows)
}

/// Marks the segments of 4 bytes (1-byte texels; the last may be shorter)
/// where rows `a` and `b` differ in `sets[0]`, and where their first and
/// their last byte differ in `sets[1]` and `sets[2]` (a short last
/// segment: where it differs at all). Sixteen bytes at a time (SSE2, which
/// every x86-64 CPU has: a byte compare and its 16-bit mask); nbody:256's
/// compare took 4 to 5 ms segment by segment, below what the memory moves.
fn mark_segments_u8(a: &[u8], b: &[u8], sets: [&mut [u64]; 3]) {
    let n = a.len().min(b.len());
    let blocks = n / 16;
    // Bits 0, 4, 8 and 12 of a 16-bit mask as bits 0 to 3.
    let compress = |y: u32| (y | y >> 3 | y >> 6 | y >> 9) & 0b1111;
    let [out, first, last] = sets;
    for i in 0..blocks.div_ceil(16) {
        let mut word = [0u64; 3];
        for j in 0..(blocks - 16 * i).min(16) {
            let differ = differing_bytes(a, b, 16 * (16 * i + j));
            let any = (differ | differ >> 1 | differ >> 2 | differ >> 3) & 0x1111;
            let got = [any, differ & 0x1111, differ >> 3 & 0x1111];
            for (w, g) in word.iter_mut().zip(got) {
                *w |= (compress(g) as u64) << (4 * j);
            }
        }
        for (set, w) in [&mut *out, &mut *first, &mut *last].into_iter().zip(word) {
            set[i] |= w;
        }
    }
    // The bytes past the last 16, one by one.
    for s in (16 * blocks / 4)..n.div_ceil(4) {
        let (lo, hi) = (4 * s, (4 * s + 4).min(n));
        let differs = |i: usize| a[i] != b[i];
        let short = hi - lo < 4;
        for (set, on) in [
            (&mut *out, (lo..hi).any(differs)),
            (&mut *first, differs(lo) || (short && (lo..hi).any(differs))),
            (&mut *last, differs(hi - 1) || (short && (lo..hi).any(differs))),
        ] {
            set[s / 64] |= (on as u64) << (s % 64);
        }
    }
}

/// The bytes where `a` and `b` differ among the 16 from `at`, as bits.
#[cfg(target_arch = "x86_64")]
fn differing_bytes(a: &[u8], b: &[u8], at: usize) -> u32 {
    use std::arch::x86_64::{__m128i, _mm_cmpeq_epi8, _mm_loadu_si128, _mm_movemask_epi8};
    // SAFETY: both loads read 16 bytes of a slice of 16 (checked by the
    // slicing); loadu takes any alignment, and SSE2 is part of x86-64.
    let equal = unsafe {
        let load = |r: &[u8]| _mm_loadu_si128(r[at..at + 16].as_ptr() as *const __m128i);
        _mm_movemask_epi8(_mm_cmpeq_epi8(load(a), load(b)))
    };
    !(equal as u32) & 0xffff
}

#[cfg(not(target_arch = "x86_64"))]
fn differing_bytes(a: &[u8], b: &[u8], at: usize) -> u32 {
    (0..16).fold(0, |m, k| m | ((a[at + k] != b[at + k]) as u32) << k)
}

/// Sets the bits of the segments of `N` bytes (the last one may be
/// shorter) where rows `a` and `b` differ.
fn mark_segments<const N: usize>(a: &[u8], b: &[u8], out: &mut [u64]) {
    let (ca, cb) = (a.chunks_exact(N), b.chunks_exact(N));
    let (ta, tb, tail) = (ca.remainder(), cb.remainder(), a.len() / N);
    for (s, (x, y)) in ca.zip(cb).enumerate() {
        // Arrays of N bytes: one compare of a word of N bytes.
        let differs = <&[u8; N]>::try_from(x).ok() != <&[u8; N]>::try_from(y).ok();
        out[s / 64] |= (differs as u64) << (s % 64);
    }
    if ta != tb {
        out[tail / 64] |= 1 << (tail % 64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Volume, VoxelData};

    fn volume(dims: [u32; 3], data: Vec<u8>) -> Volume {
        let mut v = Volume::load("menger:9", &Default::default()).unwrap();
        v.dims = dims;
        v.data = VoxelData::U8(data);
        v
    }

    #[test]
    fn changed_segments_and_the_bricks_whose_apron_reads_them() {
        let dims = [20, 6, 5];
        let n = 20 * 6 * 5;
        let before = volume(dims, vec![0; n]);
        let mut data = vec![0; n];
        // Voxel (9, 2, 3): segment 2 of row (2, 3).
        data[9 + 20 * (2 + 6 * 3)] = 7;
        let after = volume(dims, data);
        let delta = StepDelta::between(&before, &after).unwrap();
        assert!(delta.any());
        assert_eq!(delta.row(2, 3), &[0b100]);
        assert!(delta.row(2, 2).iter().all(|&w| w == 0));
        assert!((delta.fraction() - 1.0 / (5.0 * 30.0)).abs() < 1e-12);
        // Bricks of 4 with the apron: voxel 9, inside segment 2 (x 8 to
        // 11) but neither of its ends, lies in x brick 2's box (7 to 12)
        // alone (a whole changed segment would reach bricks 1, 3 too); y 2
        // in y brick 0's (0 to 4) only; z 3 in z bricks 0 (0 to 4) and 1
        // (3 to 4).
        let mut got = delta.bricks_changed(4);
        got.sort_unstable();
        let counts = [5, 2, 2];
        let at = |x: u32, y: u32, z: u32| x + counts[0] * (y + counts[1] * z);
        let mut want = vec![at(2, 0, 0), at(2, 0, 1)];
        want.sort_unstable();
        assert_eq!(got, want);
        // A segment's last voxel (11) reaches the brick after (apron 11 to
        // 16), its first (12) the brick before (apron 7 to 12).
        for x in [11, 12] {
            let mut data = vec![0; n];
            data[x + 20 * (2 + 6 * 3)] = 7;
            let delta = StepDelta::between(&before, &volume(dims, data)).unwrap();
            let mut got = delta.bricks_changed(4);
            got.sort_unstable();
            assert_eq!(
                got,
                vec![at(2, 0, 0), at(3, 0, 0), at(2, 0, 1), at(3, 0, 1)],
                "voxel {x}"
            );
        }
        // The brick of 8 holding it, one box (clipped to the volume).
        assert_eq!(delta.boxes(8), vec![([8, 0, 0], [8, 6, 5])]);
        // No change: nothing to redo; other dims: not comparable.
        let same = StepDelta::between(&after, &after).unwrap();
        assert!(!same.any() && same.bricks_changed(4).is_empty() && same.boxes(16).is_empty());
        assert!(StepDelta::between(&before, &volume([20, 6, 4], vec![0; 480])).is_none());
    }

    #[test]
    fn copying_the_changed_segments_turns_the_step_before_into_the_step_after() {
        // Rows of 23 two-byte texels: a last segment of 3 voxels.
        let dims = [23u32, 5, 3];
        let n = 23 * 5 * 3 * 2;
        let before: Vec<u8> = (0..n).map(|i| (i * 7 % 251) as u8).collect();
        let mut after = before.clone();
        // The first texel, one mid-row, and the last texel of a row.
        for at in [0, 2 * (9 + 23 * 2) + 1, 2 * (22 + 23 * 4)] {
            after[at] ^= 0x5a;
        }
        let delta = StepDelta::of_texels(dims, &before, &after).unwrap();
        let mut dst = before.clone();
        assert!(delta.copy_changed(&after, &mut dst));
        assert_eq!(dst, after);
        // Only the changed segments were copied: a byte changed elsewhere
        // in `after` alone stays as it was.
        let mut other = after.clone();
        other[2 * (3 + 23 * 3)] ^= 1;
        let mut dst = before.clone();
        assert!(delta.copy_changed(&other, &mut dst));
        assert_eq!(dst[2 * (3 + 23 * 3)], before[2 * (3 + 23 * 3)]);
        assert!(!delta.copy_changed(&after[2..], &mut dst[2..]));
    }

    /// Comparing while updating finds the same delta as comparing, for
    /// texels of 1, 2 and 4 bytes, and leaves the step before as the step
    /// after; a size that does not fit changes nothing.
    #[test]
    fn the_updating_compare_equals_the_compare_and_updates() {
        let dims = [23u32, 5, 3];
        for texel in [1usize, 2, 4] {
            let n = 23 * 5 * 3 * texel;
            let before: Vec<u8> = (0..n).map(|i| (i * 7 % 251) as u8).collect();
            let mut after = before.clone();
            for at in [0, texel * (9 + 23 * 2), texel * (22 + 23 * 4) + texel - 1, n - 1] {
                after[at] ^= 0x5a;
            }
            let want = StepDelta::of_texels(dims, &before, &after).unwrap();
            assert!(want.any());
            let mut updated = before.clone();
            assert_eq!(StepDelta::of_texels_updating(dims, &mut updated, &after), Some(want));
            assert_eq!(updated, after, "{texel}-byte texels");
            let mut short = before[1..].to_vec();
            assert_eq!(StepDelta::of_texels_updating(dims, &mut short, &after[1..]), None);
            assert_eq!(short, before[1..]);
        }
    }

    #[test]
    fn the_byte_compare_marks_segments_and_their_ends() {
        for len in [1usize, 3, 4, 15, 16, 17, 63, 64, 65, 255, 256, 257, 300] {
            let a: Vec<u8> = (0..len).map(|i| (i * 13 % 7) as u8).collect();
            for flip in [0, len / 3, len / 2, len - 1] {
                let mut b = a.clone();
                b[flip] ^= 1;
                b[len - 1 - flip / 2] ^= 2;
                let words = len.div_ceil(4).div_ceil(64);
                let mut want = vec![vec![0u64; words]; 3];
                for s in 0..len.div_ceil(4) {
                    let seg = 4 * s..(4 * s + 4).min(len);
                    let short = seg.len() < 4;
                    let any = seg.clone().any(|i| a[i] != b[i]);
                    let ends = [a[seg.start] != b[seg.start], a[seg.end - 1] != b[seg.end - 1]];
                    for (set, on) in want
                        .iter_mut()
                        .zip([any, ends[0] || short && any, ends[1] || short && any])
                    {
                        set[s / 64] |= (on as u64) << (s % 64);
                    }
                }
                // The 16-byte mask is the per-byte one (the portable form).
                if len >= 16 {
                    let per_byte = (0..16).fold(0, |m, k| m | ((a[k] != b[k]) as u32) << k);
                    assert_eq!(differing_bytes(&a, &b, 0), per_byte, "row of {len} bytes");
                }
                let mut got = vec![vec![0u64; words]; 3];
                let [x, y, z] = &mut got[..] else { unreachable!() };
                mark_segments_u8(&a, &b, [x, y, z]);
                assert_eq!(got, want, "row of {len} bytes, byte {flip} changed");
                // The whole-segment compare marks the same segments.
                let mut segments = vec![0u64; words];
                mark_segments::<4>(&a, &b, &mut segments);
                assert_eq!(segments, want[0]);
            }
        }
    }
}
