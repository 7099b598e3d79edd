//! Macro-cell grid (OSPRay style): per-cell value ranges over a one-voxel
//! apron computed once per volume, reclassified in O(cells) per transfer
//! function; `glsl/march/grid.comp` steps through the cells by 3D-DDA.

use super::bricks::GpuBricks;
use super::classify::{Classifier, Classify};
use super::stats::Stats;
use super::tree::STORAGE_XFER;
use crate::error::{Error, Result};
use crate::gpu::{Buffer, Context, MemoryLocation, Timer};
use crate::tf::GpuTransferFunction;
use crate::timings::Timings;
use crate::volume::GpuVolume;

/// Default cell edge in voxels.
pub const CELL: u32 = 16;

pub struct Grid {
    pub cell: u32,
    pub counts: [u32; 3],
    /// u32 per cell, 1 = active.
    pub flags: Buffer,
    total: u64,
    /// Counted from a flag readback only when statistics are asked for.
    active: std::sync::OnceLock<u64>,
}

impl Grid {
    /// The paper's Table 1 statistics (counts the active cells once).
    pub fn stats(&self) -> Result<Stats> {
        let active = match self.active.get() {
            Some(a) => *a,
            None => {
                let host: Vec<u32> = bytemuck::pod_collect_to_vec(&self.flags.download(0, self.total * 4)?);
                let a = host.iter().filter(|&&f| f != 0).count() as u64;
                *self.active.get_or_init(|| a)
            }
        };
        let unit = if self.cell == 16 { "16^3 cells" } else { "cells" };
        Ok(Stats {
            unit,
            total_bricks: self.total,
            active_bricks: active,
            nodes: self.total,
            leaves: active,
            height: 1,
            bytes: self.total * 4,
        })
    }

    /// The push constants of the grid kernels: cells per axis and edge.
    pub fn push(&self) -> [u32; 4] {
        [self.counts[0], self.counts[1], self.counts[2], self.cell]
    }
}

/// Checks a `--cell` value.
pub fn check_cell(cell: u32) -> Result<()> {
    if !cell.is_power_of_two() || !(2..=256).contains(&cell) {
        return Err(Error::invalid(
            "cell",
            cell.to_string(),
            "must be a power of two in 2..=256",
        ));
    }
    Ok(())
}

/// Classifies the cells of `cells` (ranges of `cell`^3 bricks) for a TF
/// ("classify").
pub fn build(
    ctx: &Context,
    classifier: &Classifier,
    volume: &GpuVolume,
    cells: &GpuBricks,
    tf: &GpuTransferFunction,
) -> Result<(Grid, Timings)> {
    let flags = Buffer::new(
        ctx,
        "grid cell flags",
        cells.total * 4,
        STORAGE_XFER,
        MemoryLocation::GpuOnly,
    )?;
    let mut timer = Timer::new(ctx, 1)?;
    ctx.submit_and_wait(|cmd| {
        timer.reset(cmd);
        let pass = timer.begin(cmd, "classify")?;
        classifier.record(cmd, Classify::Range, volume, cells, tf, &flags)?;
        timer.end(cmd, pass);
        Ok(())
    })?;
    Ok((
        Grid {
            cell: cells.brick,
            counts: cells.counts,
            flags,
            total: cells.total,
            active: std::sync::OnceLock::new(),
        },
        timer.results()?,
    ))
}
