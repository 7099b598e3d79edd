//! The cells copy (`cells.rs`) of a series step that changed in places
//! (`StepDelta`): only the cells that read a changed voxel are packed
//! again, in the memory the step before's were packed into.

use super::cells::{cell_dims, cells_bytes, pack_into, pack_u8_blocks, PackBlocks, TexelKind};
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
    let out = &mut out[..bytes];
    let dims = volume.dims;
    match &volume.data {
        VoxelData::U8(v) => cell_rows_changed(v, dims, out, 8, put_corners, Some(pack_u8_blocks), delta),
        VoxelData::U16(v) => cell_rows_changed(v, dims, bytemuck::cast_slice_mut(out), 8, put_corners, None, delta),
        VoxelData::F32(v) => cell_rows_changed(v, dims, bytemuck::cast_slice_mut(out), 8, put_corners, None, delta),
        VoxelData::Bricks(_) => pack_into(volume, out),
    }
    Ok(())
}

/// A cell's eight voxels as its words (every kind's layout: `pack_rows`).
fn put_corners<T: Copy>(cell: &mut [T], corners: [T; 8]) {
    cell.copy_from_slice(&corners);
}

/// Cells per block of `cell_rows_changed`'s test for change (what
/// `pack_u8_blocks` packs at once).
const CHANGE_BLOCK: usize = 16;

/// As `cell_layers` over every layer, for the cells that read a voxel of a
/// segment `delta` marks: per row of cells, the segments its four voxel
/// rows changed; a row without any is skipped, and its cells between the
/// edges are packed in blocks of `CHANGE_BLOCK` where the block reads one.
fn cell_rows_changed<T: Copy + Sync, U: Send>(
    v: &[T],
    dims: [u32; 3],
    out: &mut [U],
    per_cell: usize,
    put: impl Fn(&mut [U], [T; 8]) + Sync,
    blocks: Option<PackBlocks<T, U>>,
    delta: &StepDelta,
) {
    let [w, h, d] = dims.map(|n| n as usize);
    let [cw, ch, _] = cell_dims(dims).map(|n| n as usize);
    let clamp = |a: usize, n: usize| a.saturating_sub(1).min(n - 1);
    out.par_chunks_mut(cw * per_cell).enumerate().for_each(|(r, out)| {
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
                        Some(pack) if n == CHANGE_BLOCK => pack(cells, rows.map(|r| &r[m0..=m0 + n])),
                        _ => 0,
                    };
                    for (i, cell) in cells.chunks_exact_mut(per_cell).enumerate().skip(done) {
                        put(cell, corners(m0 + i, m0 + i + 1));
                    }
                }
                next = next.max(last + 1);
            }
        }
    });
}
