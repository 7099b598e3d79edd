//! A series step's changed brick ranges made on the host, for a CPU device.
//!
//! On lavapipe the device pass over a step's changed bricks
//! (`RangesFrom::Step`: a copy of the step before's ranges, then the
//! listed bricks from the cells copy) took 3 to 4 ms of nbody:256's new
//! step, one invocation a brick reading 27 cells. The host reads the same
//! voxels a row of bricks at a time instead: the rows of a row of bricks'
//! apron reduced to one row of minima and one of maxima (vector min/max
//! over whole rows), then each changed brick's span of those. The ranges
//! are the cells pass's bit for bit: the extremes of the stored integers,
//! scaled and normalised by the same float operations
//! (`glsl/prims/brick_minmax.comp`, `take_cells`; tests/integration/cells.rs).

use super::bricks::GpuBricks;
use crate::gpu::Buffer;
use crate::volume::APRON;
use crate::volume::{GpuVolume, Volume, VoxelData};
use rayon::prelude::*;

/// Whether `changed_ranges` makes `gv`'s ranges of bricks as the device
/// would: a one-channel volume of unorm texels (float extremes would
/// depend on the device's min of signed zeros) with a finite, positive
/// normalisation scale (a clamped -0 likewise), that a CPU device reads
/// through its cells copy. Whether the host maps the ranges is
/// `step_on_host`'s to check.
pub fn serves(gv: &GpuVolume, host: &Volume) -> bool {
    gv.context().info().is_cpu()
        && gv.channels == 1
        && gv.cells().is_some()
        && gv.dims == host.dims
        && gv.norms[0][0].is_finite()
        && gv.norms[0][1].is_finite()
        && gv.norms[0][1] > 0.0
        && matches!(host.data, VoxelData::U8(_) | VoxelData::U16(_))
}

/// `RangesFrom::Step` on the host, for a volume `serves` takes: the
/// `changed` bricks' ranges computed from `host` (the step's voxels,
/// normalised by `norm`) into `kept` (the step before's, which then hold
/// this step's for the next), then copied whole into `b`'s. False, writing
/// nothing, where the host does not see both buffers coherently or their
/// sizes differ: record the device's pass instead. No submission may be
/// using either buffer.
pub fn step_on_host(host: &Volume, norm: [f32; 2], changed: &[u32], kept: &mut Buffer, b: &mut GpuBricks) -> bool {
    let bytes = b.ranges.size() as usize;
    let coherent = |buffer: &Buffer| buffer.is_host_coherent() && buffer.size() as usize >= bytes;
    if !coherent(kept) || !coherent(&b.ranges) || kept.size() != b.ranges.size() {
        return false;
    }
    let (Ok(kept), Ok(out)) = (kept.host_mut(), b.ranges.host_mut()) else {
        return false;
    };
    // Mapped memory starts at a word boundary (Vulkan's map alignment).
    let Ok(ranges) = bytemuck::try_cast_slice_mut::<u8, f32>(&mut kept[..bytes]) else {
        return false;
    };
    if !changed_ranges(host, b.brick, norm, changed, ranges) {
        return false;
    }
    out[..bytes].copy_from_slice(&kept[..bytes]);
    b.computed = changed.len() as u64;
    true
}

/// Writes the ranges of the bricks `changed` lists (ascending brick
/// indices, x fastest) into `out` (a (min, max) pair per brick, as
/// `GpuBricks::ranges` holds one channel), each brick's box widened by the
/// apron and clamped to the volume, normalised by `norm` as a sample is
/// (the texel less `norm[0]`, times `norm[1]`) and clamped to [0, 1]; the
/// other bricks' pairs are left as they are. False, writing nothing, for
/// data `serves` does not take or an `out` of another size.
pub fn changed_ranges(volume: &Volume, brick: u32, norm: [f32; 2], changed: &[u32], out: &mut [f32]) -> bool {
    match &volume.data {
        VoxelData::U8(v) => ranges_of(v, volume.dims, brick, (norm, 1.0 / 255.0), changed, out),
        VoxelData::U16(v) => ranges_of(v, volume.dims, brick, (norm, 1.0 / 65535.0), changed, out),
        _ => false,
    }
}

/// `changed_ranges` of integer texels `v`, scaled by `unit` (the manual
/// filter's reciprocal of the largest texel).
fn ranges_of<T: Copy + Ord + Into<u32> + Send + Sync>(
    v: &[T],
    dims: [u32; 3],
    brick: u32,
    (norm, unit): ([f32; 2], f32),
    changed: &[u32],
    out: &mut [f32],
) -> bool {
    let [w, h, d] = dims.map(|n| n as usize);
    let e = brick as usize;
    let [cx, cy, cz] = dims.map(|n| n.div_ceil(brick) as usize);
    if e == 0 || v.len() != w * h * d || out.len() != 2 * cx * cy * cz {
        return false;
    }
    // A brick's voxels along one axis, apron included, clamped.
    let apron = APRON as usize;
    let span = |b: usize, n: usize| (b * e).saturating_sub(apron)..=(b * e + e - 1 + apron).min(n - 1);
    // As the kernel: the extremes scaled by the constant reciprocal, then
    // normalised as a sample is, then clamped (finite: `serves`).
    let normalised = |t: T| ((t.into() as f32 * unit - norm[0]) * norm[1]).clamp(0.0, 1.0);
    out.par_chunks_mut(2 * cx).enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |(lo, hi): &mut (Vec<T>, Vec<T>), (row, out)| {
            // This row of bricks' changed ones.
            let first = changed.partition_point(|&b| (b as usize) < row * cx);
            let last = changed.partition_point(|&b| (b as usize) < (row + 1) * cx);
            let bricks = &changed[first..last];
            let (Some(&b0), Some(&b1)) = (bricks.first(), bricks.last()) else {
                return;
            };
            let (by, bz) = (row % cy, row / cy);
            // Only the voxels between the first and last changed brick's.
            let xs = *span(b0 as usize - row * cx, w).start()..=*span(b1 as usize - row * cx, w).end();
            let x0 = *xs.start();
            let n = xs.end() - x0 + 1;
            lo.clear();
            hi.clear();
            for (i, (z, y)) in span(bz, d).flat_map(|z| span(by, h).map(move |y| (z, y))).enumerate() {
                let voxels = &v[(y + h * z) * w + x0..][..n];
                if i == 0 {
                    lo.extend_from_slice(voxels);
                    hi.extend_from_slice(voxels);
                    continue;
                }
                // Element by element: vector min and max.
                for ((l, u), &t) in lo.iter_mut().zip(hi.iter_mut()).zip(voxels) {
                    *l = (*l).min(t);
                    *u = (*u).max(t);
                }
            }
            for &b in bricks {
                let bx = b as usize - row * cx;
                let x = span(bx, w);
                let at = (*x.start() - x0)..=(*x.end() - x0);
                let (mn, mx) = (lo[at.clone()].iter().min(), hi[at].iter().max());
                if let (Some(&mn), Some(&mx)) = (mn, mx) {
                    out[2 * bx] = normalised(mn);
                    out[2 * bx + 1] = normalised(mx);
                }
            }
        },
    );
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    /// Every listed brick's pair is the brute-force extreme of its apron'd
    /// box, normalised; the others are left alone: ragged edges (dims not
    /// multiples of the brick), an axis of one voxel, 8- and 16-bit texels,
    /// a list across rows of bricks.
    #[test]
    fn changed_ranges_are_the_extremes_of_each_listed_bricks_box() {
        let norm = [0.1f32, 1.25];
        for (dims, brick) in [([11u32, 7, 5], 4u32), ([9, 1, 6], 4), ([17, 9, 3], 8)] {
            let [w, h, d] = dims.map(|n| n as usize);
            let n = w * h * d;
            let counts = dims.map(|n| n.div_ceil(brick) as usize);
            let total = counts.iter().product::<usize>();
            let listed: Vec<u32> = (0..total as u32).filter(|b| b % 3 != 1).collect();
            let words: Vec<u16> = (0..n)
                .map(|i| ((i as u32).wrapping_mul(2654435761) >> 7) as u16)
                .collect();
            let volumes = [
                (
                    VoxelType::U8,
                    VoxelData::U8(words.iter().map(|&x| x as u8).collect()),
                    255.0,
                ),
                (VoxelType::U16, VoxelData::U16(words.clone()), 65535.0),
            ];
            for (ty, data, max) in volumes {
                let v = Volume::new("ranges", dims, [1.0; 3], ty, data).unwrap();
                let texel = |i: usize| match &v.data {
                    VoxelData::U8(t) => t[i] as u32,
                    VoxelData::U16(t) => t[i] as u32,
                    _ => unreachable!(),
                };
                let mut out = vec![-7.0f32; 2 * total];
                assert!(changed_ranges(&v, brick, norm, &listed, &mut out));
                for b in 0..total {
                    let at = [b % counts[0], b / counts[0] % counts[1], b / (counts[0] * counts[1])];
                    let (mut lo, mut hi) = (u32::MAX, 0);
                    for z in 0..d {
                        for y in 0..h {
                            for x in 0..w {
                                let p = [x, y, z];
                                let inside = (0..3).all(|a| {
                                    let first = (at[a] * brick as usize) as i64 - 1;
                                    (first..=first + brick as i64 + 1).contains(&(p[a] as i64))
                                });
                                if inside {
                                    let t = texel(x + w * (y + h * z));
                                    (lo, hi) = (lo.min(t), hi.max(t));
                                }
                            }
                        }
                    }
                    let unit = 1.0 / max as f32;
                    let normal = |t: u32| ((t as f32 * unit - norm[0]) * norm[1]).clamp(0.0, 1.0);
                    let want = match listed.contains(&(b as u32)) {
                        true => [normal(lo), normal(hi)],
                        false => [-7.0, -7.0],
                    };
                    assert_eq!(out[2 * b..2 * b + 2], want, "{ty:?} {dims:?} brick {b}");
                }
            }
            let mut short = vec![0.0f32; 2 * total - 2];
            let v = Volume::new("ranges", dims, [1.0; 3], VoxelType::U16, VoxelData::U16(words)).unwrap();
            assert!(!changed_ranges(&v, brick, norm, &listed, &mut short));
        }
    }
}
