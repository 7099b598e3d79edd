//! The cells copy (`cells.rs`) of a series step that changed in places
//! (`StepDelta`): only the cells that read a changed voxel are packed
//! again, in the memory the step before's were packed into.

use super::cells::{cell_dims, cells_bytes, pack_into, TexelKind};
use super::cells_simd::stream_u8_blocks;
use super::delta::{StepDelta, SEGMENT};
use super::{Volume, VoxelData};
use crate::error::{Error, Result};
use crate::gpu::TexelBuffer;
use rayon::prelude::*;

/// As `repack_shared`, for a step whose texels differ from those `cells`
/// holds only where `delta` says: only the cells that read a changed
/// segment are packed again (nbody:256: about a fifth of them), each as
/// `repack_shared` packs it.
pub fn repack_changed(cells: &mut TexelBuffer, volume: &Volume, delta: &StepDelta) -> Result<()> {
    let bytes = cells_bytes(volume.dims, TexelKind::of(&volume.data)) as usize;
    let out = cells.host_mut()?;
    if out.len() < bytes || delta.dims() != volume.dims {
        return Err(Error::Interface(format!(
            "cells copy of {} bytes for {bytes}, or a delta of another grid",
            out.len()
        )));
    }
    repack_changed_into(&mut out[..bytes], volume, delta);
    Ok(())
}

/// `repack_changed` into `out`, the step before's cells copy (`volume`'s
/// `cells_bytes`).
fn repack_changed_into(out: &mut [u8], volume: &Volume, delta: &StepDelta) {
    let dims = volume.dims;
    match &volume.data {
        VoxelData::U8(v) => cell_rows_changed(v, dims, out, 8, put_corners, Some(stream_u8_blocks), delta),
        VoxelData::U16(v) => cell_rows_changed(v, dims, bytemuck::cast_slice_mut(out), 8, put_corners, None, delta),
        VoxelData::F32(v) => cell_rows_changed(v, dims, bytemuck::cast_slice_mut(out), 8, put_corners, None, delta),
        VoxelData::Bricks(_) => pack_into(volume, out),
    }
}

/// A cell's eight voxels as its words (every kind's layout: `pack_rows`).
fn put_corners<T: Copy>(cell: &mut [T], corners: [T; 8]) {
    cell.copy_from_slice(&corners);
}

/// As `cells::PackBlocks`, for a packer that may stream its stores
/// (`stream_u8_blocks`): its caller fences before the blocks are touched
/// again.
type StreamBlocks<T, U> = unsafe fn(&mut [U], [&[T]; 4]) -> usize;

/// Rows of cells a task packs before it fences its streamed stores (a
/// fence a row cost a third of what streaming saved).
const ROWS_PER_TASK: usize = 64;

/// Cells per block of `cell_rows_changed`'s test for change (what
/// `stream_u8_blocks` packs at once).
const CHANGE_BLOCK: usize = 16;

/// As `cell_layers` over every layer, for the cells that read a voxel of a
/// segment `delta` marks: per row of cells, the segments its four voxel
/// rows changed; a row without any is skipped, and its cells between the
/// edges are packed in blocks of `CHANGE_BLOCK` where the block reads one.
/// `blocks` may stream (`stream_u8_blocks`): each task of `ROWS_PER_TASK`
/// rows fences after its last.
fn cell_rows_changed<T: Copy + Sync, U: Send>(
    v: &[T],
    dims: [u32; 3],
    out: &mut [U],
    per_cell: usize,
    put: impl Fn(&mut [U], [T; 8]) + Sync,
    blocks: Option<StreamBlocks<T, U>>,
    delta: &StepDelta,
) {
    let [w, h, d] = dims.map(|n| n as usize);
    let [cw, ch, _] = cell_dims(dims).map(|n| n as usize);
    let clamp = |a: usize, n: usize| a.saturating_sub(1).min(n - 1);
    let pack_row = |r: usize, out: &mut [U]| {
        let (j, k) = (r % ch, r / ch);
        let (ys, zs) = ([clamp(j, h), clamp(j + 1, h)], [clamp(k, d), clamp(k + 1, d)]);
        // On the stack for rows of up to 16384 voxels.
        let (mut small, mut large) = ([0u64; 64], Vec::new());
        let words = delta.row(0, 0).len();
        let changed = match words <= small.len() {
            true => &mut small[..words],
            false => {
                large.resize(words, 0);
                &mut large[..]
            }
        };
        delta.rows_or(ys[0] as u32..=ys[1] as u32, zs[0] as u32..=zs[1] as u32, changed);
        let changed = &*changed;
        if changed.iter().all(|&c| c == 0) {
            return;
        }
        let any = |x0: usize, x1: usize| StepDelta::row_any(changed, x0 as u32, x1 as u32);
        let row = |y: usize, z: usize| &v[(y + h * z) * w..][..w];
        let rows = [
            row(ys[0], zs[0]),
            row(ys[1], zs[0]),
            row(ys[0], zs[1]),
            row(ys[1], zs[1]),
        ];
        let [r0, r1, r2, r3] = rows;
        let corners = |x: usize, x1: usize| [r0[x], r0[x1], r1[x], r1[x1], r2[x], r2[x1], r3[x], r3[x1]];
        let (head, rest) = out.split_at_mut(per_cell);
        let (middle, tail) = rest.split_at_mut((cw - 2) * per_cell);
        if any(0, 0) {
            put(head, corners(0, 0));
        }
        if any(w - 1, w - 1) {
            put(tail, corners(w - 1, w - 1));
        }
        // Middle cell m reads voxels m and m + 1: block b (cells 16b on)
        // reads voxels 16b to 16b + 16. Changed segments in order, each
        // packing the blocks that read it and were not packed yet (a row
        // is mostly unchanged: testing every block cost as much as packing).
        let seg = SEGMENT as usize;
        let blocks_in_row = (cw - 2).div_ceil(CHANGE_BLOCK);
        let mut next = 0; // the first block not packed yet
        for (wi, &word) in changed.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let s = 64 * wi + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let (x0, x1) = (seg * s, seg * s + seg - 1);
                let first = x0.saturating_sub(CHANGE_BLOCK).div_ceil(CHANGE_BLOCK).max(next);
                let last = (x1 / CHANGE_BLOCK).min(blocks_in_row - 1);
                for b in first..=last {
                    let m0 = b * CHANGE_BLOCK;
                    let cells = &mut middle[m0 * per_cell..((m0 + CHANGE_BLOCK).min(cw - 2)) * per_cell];
                    let n = cells.len() / per_cell;
                    let done = match blocks {
                        // SAFETY: a streamed block is not touched again
                        // before the fence that ends this task (below).
                        Some(pack) if n == CHANGE_BLOCK => unsafe { pack(cells, rows.map(|r| &r[m0..=m0 + n])) },
                        _ => 0,
                    };
                    for (i, cell) in cells.chunks_exact_mut(per_cell).enumerate().skip(done) {
                        put(cell, corners(m0 + i, m0 + i + 1));
                    }
                }
                next = next.max(last + 1);
            }
        }
    };
    let row_len = cw * per_cell;
    out.par_chunks_mut(row_len * ROWS_PER_TASK)
        .enumerate()
        .for_each(|(g, rows)| {
            for (i, out) in rows.chunks_mut(row_len).enumerate() {
                pack_row(ROWS_PER_TASK * g + i, out);
            }
            // The streamed blocks' stores made visible before this task
            // reports done (the device reads them after the submission).
            #[cfg(target_arch = "x86_64")]
            if blocks.is_some() {
                // SAFETY: SSE is part of x86-64.
                unsafe { std::arch::x86_64::_mm_sfence() };
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    fn packed(v: &Volume) -> Vec<u8> {
        let mut out = vec![0u8; cells_bytes(v.dims, TexelKind::of(&v.data)) as usize];
        pack_into(v, &mut out);
        out
    }

    /// Rows wide enough for several blocks of 16 cells (packed by SIMD,
    /// with streaming stores) beside the row's edge cells and a short last
    /// block and segment: changes at a row's first and last voxel, inside
    /// blocks, across a block's edge and in a lone row, each in every
    /// kind, repacked over the step before's copy, equal a whole pack.
    #[test]
    fn a_repacked_step_equals_its_whole_pack() {
        let dims = [70u32, 9, 7];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let at = |x: u32, y: u32, z: u32| (x + dims[0] * (y + dims[1] * z)) as usize;
        let changed = [
            at(0, 0, 0),
            at(69, 8, 6),
            at(17, 4, 3),
            at(31, 4, 3),
            at(32, 5, 3),
            at(47, 0, 6),
            at(66, 2, 1),
        ];
        let before: Vec<u8> = (0..n).map(|i| (i * 37 % 251) as u8).collect();
        let mut after = before.clone();
        for &i in &changed {
            after[i] = after[i].wrapping_add(101);
        }
        type Of = fn(&[u8]) -> VoxelData;
        let kinds: [(VoxelType, Of); 3] = [
            (VoxelType::U8, |b| VoxelData::U8(b.to_vec())),
            (VoxelType::U16, |b| {
                VoxelData::U16(b.iter().map(|&x| x as u16 * 257).collect())
            }),
            (VoxelType::F32, |b| {
                VoxelData::F32(b.iter().map(|&x| x as f32 / 7.0).collect())
            }),
        ];
        for (ty, data) in kinds {
            let volume = |b: &[u8]| Volume::new("step", dims, [1.0; 3], ty, data(b)).unwrap();
            let (a, b) = (volume(&before), volume(&after));
            let delta = crate::volume::StepDelta::between(&a, &b).unwrap();
            assert!(delta.any());
            let mut out = packed(&a);
            assert!(out != packed(&b), "{ty:?}: the steps' copies are the same");
            repack_changed_into(&mut out, &b, &delta);
            assert!(out == packed(&b), "{ty:?}: the repacked copy differs from a whole pack");
        }
    }
}
