//! The distance maps' transform on the host's cores, for CPU devices.
//!
//! On a CPU device (lavapipe) the device's "cores" are the host's, and the
//! GPU transform (`distance_octant_rows.comp`, `distance_rows.comp`) runs
//! a row per SIMD lane through storage-buffer accesses it makes one lane at
//! a time with a bounds check each: nbody:256's octant map at cell 4 took
//! 16 to 24 ms in its three passes. The same distances by sequential sweeps
//! take a few milliseconds on the host, so `Builder::build` classifies on
//! the device and transforms here when the device is the CPU
//! (`distance::build_on_host`); recorded builds (`record_build`) stay on
//! the device. The two give the same distances, every byte the march reads
//! (tests/integration/distance.rs).
//!
//! Each channel is one dynamic-programming sweep over the cells, which is
//! exact for the Chebyshev (chessboard) distance:
//! - an octant channel: a cell's distance is 0 where it is of the kind
//!   sought, else one more than the least distance among its seven
//!   neighbours one cell ahead of the octant's rays on some axes (a shortest
//!   king's path to a cell ahead takes such a step first, and the rest of it
//!   stays ahead), so one sweep from the far corner computes it;
//! - a cube channel: the same over all 26 neighbours, in the two raster
//!   sweeps of Rosenfeld and Pfaltz (forward with the 13 neighbours before a
//!   cell, backward with the 13 after it).
//!
//! Distances are capped at [`CAP`] as the device caps them: a capped
//! neighbour plus one stays capped, which is the capped true distance.
//! The map's byte layout ([`channels`], [`CAP`]) and its brute-force
//! transform ([`reference`], for tests) live here too, below `distance`.

use crate::desc::Octants;
use rayon::prelude::*;

/// Largest stored distance (`DISTANCE_CAP` in `distance_map.glsl`).
pub const CAP: u32 = 255;

/// Byte distances per cell: to the nearest active cell, then to the nearest
/// empty cell, one each (cube maps) or one per octant each (`distance_map.glsl`).
pub fn channels(octants: bool) -> usize {
    if octants {
        16
    } else {
        2
    }
}

/// The distance map on the host, for tests: per cell, [`channels`] distances
/// in channel order, each the Chebyshev distance in cells to the nearest
/// cell of the kind sought (`octants`: only cells ahead of that octant, and
/// 1 for an octant not `built`), capped at [`CAP`]. Brute force: O(cells^2).
pub fn reference(counts: [u32; 3], active: &[bool], octants: bool, built: Octants) -> Vec<u32> {
    let [nx, ny, nz] = counts.map(|n| n as i64);
    let cells: Vec<[i64; 3]> = (0..nz)
        .flat_map(|z| (0..ny).flat_map(move |y| (0..nx).map(move |x| [x, y, z])))
        .collect();
    let half = channels(octants) / 2;
    let mut out = Vec::with_capacity(cells.len() * 2 * half);
    for c in &cells {
        for ch in 0..2 * half {
            let (seek_active, octant) = (ch < half, ch % half);
            if octants && !built.has(octant as u32) {
                out.push(1);
                continue;
            }
            let mut best = CAP as i64;
            for (o, other) in cells.iter().enumerate() {
                let off = [0, 1, 2].map(|k| other[k] - c[k]);
                let ahead = !octants || (0..3).all(|k| if octant >> k & 1 == 1 { off[k] <= 0 } else { off[k] >= 0 });
                if active[o] == seek_active && ahead {
                    best = best.min(off.iter().map(|v| v.abs()).max().unwrap_or(0));
                }
            }
            out.push(best as u32);
        }
    }
    out
}

/// Bytes of swept channels held at once before they are interleaved into
/// the map (a channel is a byte a cell).
pub const SWEPT_BYTES: usize = 256 << 20;

const CAP8: u8 = CAP as u8;
// A byte's saturation is the cap.
const _: () = assert!(CAP8 == u8::MAX);

/// The distance of a cell that is not of the kind sought, from the least
/// distance among its neighbours.
fn one_more(least: u8) -> u8 {
    least.saturating_add(1)
}

/// The cells of a grid of `counts`, x fastest.
#[derive(Clone, Copy)]
struct Grid {
    n: [usize; 3],
}

impl Grid {
    fn row(self, y: usize, z: usize) -> usize {
        self.n[0] * (y + self.n[1] * z)
    }

    /// Row (y + dy, z + dz)'s first cell, or None outside the grid.
    fn row_at(self, y: usize, z: usize, dy: isize, dz: isize) -> Option<usize> {
        let y = y.checked_add_signed(dy).filter(|&y| y < self.n[1])?;
        let z = z.checked_add_signed(dz).filter(|&z| z < self.n[2])?;
        Some(self.row(y, z))
    }

    /// Indices 0..n in the order a sweep visits them: from the far end when
    /// its neighbours lie at +1 (`s` = 1), from 0 when they lie at -1.
    fn order(n: usize, s: isize) -> Box<dyn Iterator<Item = usize>> {
        if s > 0 {
            Box::new((0..n).rev())
        } else {
            Box::new(0..n)
        }
    }
}

/// `m[x] = min(m[x], row[x + dx] for dx in dxs)`, cells past the row's ends left out.
fn min_into(m: &mut [u8], row: &[u8], dxs: &[isize]) {
    let n = row.len();
    for &dx in dxs {
        match dx {
            0 => m.iter_mut().zip(row).for_each(|(a, &b)| *a = (*a).min(b)),
            1 => m[..n - 1]
                .iter_mut()
                .zip(&row[1..])
                .for_each(|(a, &b)| *a = (*a).min(b)),
            _ => m[1..]
                .iter_mut()
                .zip(&row[..n - 1])
                .for_each(|(a, &b)| *a = (*a).min(b)),
        }
    }
}

/// One octant channel: per cell, the distance to the nearest cell whose
/// flag is `seek_active` among the cells ahead of a ray of `octant` (bit a
/// set: the ray runs towards lower coordinates along axis a).
fn sweep_octant(grid: Grid, flags: &[u32], seek_active: bool, octant: u32) -> Vec<u8> {
    let s = [0, 1, 2].map(|a| if octant >> a & 1 == 1 { -1isize } else { 1 });
    let [nx, ny, nz] = grid.n;
    let mut d = vec![CAP8; nx * ny * nz];
    let mut m = vec![CAP8; nx];
    for z in Grid::order(nz, s[2]) {
        for y in Grid::order(ny, s[1]) {
            // The six neighbours ahead on y or z (at x and one cell ahead on x).
            m.fill(CAP8);
            for (dy, dz) in [(s[1], 0), (0, s[2]), (s[1], s[2])] {
                if let Some(r) = grid.row_at(y, z, dy, dz) {
                    min_into(&mut m, &d[r..r + nx], &[0, s[0]]);
                }
            }
            // Then along the row from its far end: the neighbour ahead on x.
            let at = grid.row(y, z);
            let (row, fl) = (&mut d[at..at + nx], &flags[at..at + nx]);
            let mut ahead = CAP8;
            for x in Grid::order(nx, s[0]) {
                let v = match (fl[x] != 0) == seek_active {
                    true => 0,
                    false => one_more(m[x].min(ahead)),
                };
                row[x] = v;
                ahead = v;
            }
        }
    }
    d
}

/// One cube channel: per cell, the distance to the nearest cell whose flag
/// is `seek_active`, in any direction.
fn sweep_cube(grid: Grid, flags: &[u32], seek_active: bool) -> Vec<u8> {
    let [nx, ny, nz] = grid.n;
    let mut d = vec![CAP8; nx * ny * nz];
    let mut m = vec![CAP8; nx];
    // Forward (s = -1: the neighbours before a cell), then backward (s = 1).
    for s in [-1isize, 1] {
        for z in Grid::order(nz, s) {
            for y in Grid::order(ny, s) {
                m.fill(CAP8);
                for (dy, dz) in [(s, 0), (-1, s), (0, s), (1, s)] {
                    if let Some(r) = grid.row_at(y, z, dy, dz) {
                        min_into(&mut m, &d[r..r + nx], &[-1, 0, 1]);
                    }
                }
                let at = grid.row(y, z);
                let (row, fl) = (&mut d[at..at + nx], &flags[at..at + nx]);
                let mut before = CAP8;
                for x in Grid::order(nx, s) {
                    let v = match (fl[x] != 0) == seek_active {
                        true => 0,
                        false => row[x].min(one_more(m[x].min(before))),
                    };
                    row[x] = v;
                    before = v;
                }
            }
        }
    }
    d
}

/// Writes the distance map of the cells `flags` flags active (nonzero) on
/// a grid of `counts` into `out`, the map's bytes as the device reads them
/// (`distance_map.glsl`: a cell's [`channels`] bytes in channel order,
/// four to a word, little-endian; the first half to active cells). An
/// octant map holds the octants `built` (the others' bytes are 0: the
/// march reads 1 for them); a cube map holds all. Channels are swept in
/// parallel, as many at once as rayon's pool has threads and
/// [`SWEPT_BYTES`] holds.
pub fn transform(counts: [u32; 3], flags: &[u32], octants: bool, built: Octants, out: &mut [u8]) {
    let grid = Grid {
        n: counts.map(|n| n as usize),
    };
    let total = grid.n.iter().product::<usize>();
    if total == 0 {
        return;
    }
    let per_cell = 4 * channels(octants).div_ceil(4);
    let out = &mut out[..total * per_cell];
    out.fill(0);
    // (channel, whether it seeks active cells, its octant).
    let half = channels(octants) / 2;
    let jobs: Vec<(usize, bool, u32)> = (0..2 * half)
        .map(|ch| (ch, ch < half, (ch % half) as u32))
        .filter(|&(_, _, o)| !octants || built.has(o))
        .collect();
    let flags = &flags[..total];
    let at_once = rayon::current_num_threads().min(SWEPT_BYTES / total).max(1);
    for batch in jobs.chunks(at_once) {
        let swept: Vec<(usize, Vec<u8>)> = batch
            .par_iter()
            .map(|&(ch, seek, o)| {
                let d = match octants {
                    true => sweep_octant(grid, flags, seek, o),
                    false => sweep_cube(grid, flags, seek),
                };
                (ch, d)
            })
            .collect();
        out.par_chunks_mut(per_cell * 4096).enumerate().for_each(|(b, cells)| {
            for (ch, d) in &swept {
                let d = &d[b * 4096..];
                for (cell, &v) in cells.chunks_exact_mut(per_cell).zip(d) {
                    cell[*ch] = v;
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distances as `reference` lists them, from `transform`'s bytes.
    fn listed(out: &[u8], octants: bool, built: Octants) -> Vec<u32> {
        let per = 4 * channels(octants).div_ceil(4);
        let n = channels(octants);
        out.chunks(per)
            .flat_map(|cell| {
                (0..n).map(move |ch| match !octants || built.has((ch % 8) as u32) {
                    true => cell[ch] as u32,
                    false => 1,
                })
            })
            .collect()
    }

    #[test]
    fn sweeps_equal_the_brute_force_transform() {
        let mut s = 7u64;
        let mut next = move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 33) as u32
        };
        // Thin and odd grids (a row of one cell, a plane of one), sparse and
        // dense flags, every octant and some.
        for (counts, per_mille) in [
            ([9, 7, 5], 30),
            ([1, 6, 8], 100),
            ([7, 1, 6], 100),
            ([6, 5, 1], 500),
            ([12, 10, 11], 5),
            ([5, 5, 5], 0),
            ([4, 6, 3], 1000),
        ] {
            let total = counts.iter().product::<u32>() as usize;
            let flags: Vec<u32> = (0..total).map(|_| (next() % 1000 < per_mille) as u32).collect();
            let active: Vec<bool> = flags.iter().map(|&f| f != 0).collect();
            for (octants, built) in [
                (false, Octants::ALL),
                (true, Octants::ALL),
                (true, Octants::one(6)),
                (true, Octants::from_bits(0b1001_0010)),
            ] {
                let mut out = vec![0xaa; total * 4 * channels(octants).div_ceil(4) + 8];
                transform(counts, &flags, octants, built, &mut out);
                let got = listed(&out[..out.len() - 8], octants, built);
                let want = reference(counts, &active, octants, built);
                assert_eq!(got, want, "{counts:?} {per_mille}/1000 octants {octants} {built}");
                assert!(out[out.len() - 8..].iter().all(|&b| b == 0xaa), "wrote past the map");
            }
        }
    }

    #[test]
    fn distances_past_the_cap_stay_at_the_cap() {
        // One active cell at an end of rows longer than the cap, along each
        // axis: the distances count up to 255 and stay there.
        for (counts, at) in [([300, 1, 1], 0), ([1, 2, 400], 1), ([3, 270, 2], 0)] {
            let total = counts.iter().product::<u32>() as usize;
            let mut flags = vec![0u32; total];
            flags[at] = 1;
            let active: Vec<bool> = flags.iter().map(|&f| f != 0).collect();
            for (octants, built) in [(false, Octants::ALL), (true, Octants::ALL)] {
                let mut out = vec![0; total * 4 * channels(octants).div_ceil(4)];
                transform(counts, &flags, octants, built, &mut out);
                let got = listed(&out, octants, built);
                assert!(
                    got.contains(&CAP) && got.contains(&(CAP - 1)),
                    "{counts:?}: the cap reached"
                );
                assert_eq!(
                    got,
                    reference(counts, &active, octants, built),
                    "{counts:?} octants {octants}"
                );
            }
        }
    }

    #[test]
    fn an_empty_grid_writes_nothing() {
        let mut out = vec![7u8; 8];
        transform([0, 4, 4], &[], true, Octants::ALL, &mut out);
        assert_eq!(out, vec![7u8; 8]);
    }
}
