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
//! (`glsl/prims/brick_minmax.comp`, `take_cells`; tests/integration/series.rs).

use super::bricks::GpuBricks;
use crate::gpu::Buffer;
use crate::volume::{GpuVolume, Volume, VoxelData};
use rayon::prelude::*;

/// The apron of every structure's ranges: one voxel each side.
const APRON: usize = 1;

/// Whether `changed_ranges` makes `gv`'s ranges of `brick`^3 bricks as
/// the device would: a one-channel volume of unorm texels (float extremes
/// would depend on the device's min of signed zeros) with a finite
/// normalisation, that the device reads through its cells copy, on a
/// device whose memory the host maps.
pub fn serves(gv: &GpuVolume, host: &Volume) -> bool {
    gv.context().info().is_cpu()
        && gv.channels == 1
        && gv.cells().is_some()
        && gv.dims == host.dims
        && gv.norms[0].iter().all(|n| n.is_finite())
        && matches!(host.data, VoxelData::U8(_) | VoxelData::U16(_))
}

/// `RangesFrom::Step` on the host, for a volume `serves` takes: `b`'s
/// ranges are the step before's (`kept`) with the `changed` bricks'
/// computed from `host` (the step's voxels, normalised by `norm`), and
/// `kept` then holds them for the next step. False where the host does not
/// see both buffers coherently or their sizes differ (`b`'s ranges may be
/// written then, `kept` is not): record the device's pass instead, which
/// writes all of `b`'s. No submission may be using either buffer.
pub fn step_on_host(host: &Volume, norm: [f32; 2], changed: &[u32], kept: &mut Buffer, b: &mut GpuBricks) -> bool {
    let bytes = b.ranges.size() as usize;
    let coherent = |buffer: &Buffer| buffer.mapped_coherent().is_some_and(|m| m.len() >= bytes);
    if !coherent(kept) || !coherent(&b.ranges) || kept.size() != b.ranges.size() {
        return false;
    }
    let (Some(before), Some(out)) = (kept.mapped(), b.ranges.mapped_mut()) else {
        return false;
    };
    // Mapped memory starts at a word boundary (Vulkan's map alignment).
    let Ok(out) = bytemuck::try_cast_slice_mut::<u8, f32>(&mut out[..bytes]) else {
        return false;
    };
    bytemuck::cast_slice_mut(out).copy_from_slice(&before[..bytes]);
    if !changed_ranges(host, b.brick, norm, changed, out) {
        return false;
    }
    let ranges: &[u8] = bytemuck::cast_slice(out);
    match kept.mapped_mut() {
        Some(kept) => kept[..bytes].copy_from_slice(ranges),
        None => return false,
    }
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
    let span = |b: usize, n: usize| (b * e).saturating_sub(APRON)..=(b * e + e - 1 + APRON).min(n - 1);
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
