//! Macro-cell grid (OSPRay style): per-cell value ranges over a one-voxel
//! apron computed once per volume, reclassified in O(cells) per transfer
//! function; `glsl/march/grid.comp` steps through the cells by 3D-DDA.

use super::bricks::GpuBricks;
use super::classify::{Classifier, Classify};
use super::registry::{BuildInput, BuildOptions, Builder, Built, March, Method, RangeKind, Ranges};
use super::stats::Stats;
use super::tree::STORAGE_XFER;
use crate::error::{Error, Result};
use crate::gpu::{check_push, shaders, vk, Binding, Buffer, Context, MemoryLocation, OptionalTimer, Timer};
use crate::tf::GpuTransferFunction;
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
        let active = count_active(&self.flags, self.total, &self.active)?;
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
    pub fn push(&self) -> GridPush {
        GridPush {
            counts: self.counts,
            cell: self.cell,
        }
    }
}

/// Active cells of a u32-per-cell flag buffer, read back once into `cache`
/// (statistics only; builds never read back).
pub(crate) fn count_active(flags: &Buffer, total: u64, cache: &std::sync::OnceLock<u64>) -> Result<u64> {
    if let Some(a) = cache.get() {
        return Ok(*a);
    }
    let host: Vec<u32> = bytemuck::pod_collect_to_vec(&flags.download(0, total * 4)?);
    let a = host.iter().filter(|&&f| f != 0).count() as u64;
    Ok(*cache.get_or_init(|| a))
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

/// Records the classification of the cells of `cells` (ranges of `cell`^3
/// bricks) for a TF into a new flag buffer ("classify"). Ends with compute
/// writes.
#[allow(clippy::too_many_arguments)]
pub fn record(
    ctx: &Context,
    classifier: &Classifier,
    cmd: vk::CommandBuffer,
    mut timer: Option<&mut Timer>,
    volume: &GpuVolume,
    cells: &GpuBricks,
    tf: &GpuTransferFunction,
) -> Result<Grid> {
    let flags = Buffer::new(
        ctx,
        "grid cell flags",
        cells.total * 4,
        STORAGE_XFER,
        MemoryLocation::GpuOnly,
    )?;
    let pass = timer.begin(cmd, "classify")?;
    classifier.record(cmd, Classify::Range, volume, cells, tf, &flags)?;
    timer.end(cmd, pass);
    Ok(Grid {
        cell: cells.brick,
        counts: cells.counts,
        flags,
        total: cells.total,
        active: std::sync::OnceLock::new(),
    })
}

/// Push block of `glsl/march/grid.comp` and `hybrid.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GridPush {
    /// Cells per axis.
    pub counts: [u32; 3],
    /// Cell edge in voxels.
    pub cell: u32,
}
check_push!(GridPush, shaders::MARCH_GRID);
check_push!(GridPush, shaders::MARCH_HYBRID);

/// `--accel grid`.
pub struct GridMethod;

impl Method for GridMethod {
    fn name(&self) -> &'static str {
        "grid"
    }
    fn description(&self) -> &'static str {
        "macro-cell grid (OSPRay style), 3D-DDA traversal"
    }
    fn ranges(&self) -> RangeKind {
        RangeKind::Cells
    }
    fn params(&self, o: &BuildOptions) -> Vec<(&'static str, String)> {
        vec![("cell", o.cell.to_string())]
    }
    fn march(&self) -> March {
        March {
            shader: shaders::MARCH_GRID,
            constants: &[],
            push_size: std::mem::size_of::<GridPush>(),
        }
    }
    fn record_build(
        &self,
        builder: &Builder,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        options: &BuildOptions,
    ) -> Result<Box<dyn Built>> {
        let classifier = builder.kernels::<Classifier>()?;
        let grid = record(
            builder.context(),
            &classifier,
            cmd,
            timer,
            input.gpu_volume,
            ranges.cells(options.cell)?,
            input.gpu_tf,
        )?;
        Ok(Box::new(grid))
    }
}

impl Built for Grid {
    fn bindings(&self) -> Vec<Binding<'_>> {
        vec![Binding::Storage(&self.flags)]
    }
    fn push(&self) -> Vec<u8> {
        bytemuck::bytes_of(&self.push()).to_vec()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        Grid::stats(self).map(Some)
    }
}
