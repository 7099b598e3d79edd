//! Macro-cell grid (OSPRay style): per-cell value ranges over a one-voxel
//! apron computed once per volume, reclassified in O(cells) per transfer
//! function; `glsl/march/grid.comp` steps through the cells by 3D-DDA. In
//! MIP and MinIP frames the cells keep their ranges instead of flags, and
//! each ray decides per cell whether it can beat the ray's running max
//! (min) (`accel::mode`).

use super::bricks::GpuBricks;
use super::builder::{Builder, RangeKind, Ranges};
use super::classify::{Classifier, Classify};
use super::method::{BuildInput, Built, March, Method};
use super::params::{self, Param, Params, Value};
use super::stats::Stats;
use super::tree::STORAGE_TEXELS;
use crate::desc::Mode;
use crate::error::Result;
use crate::gpu::record::Access;
use crate::gpu::shaders::{self, march_grid};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Bound, Buffer, MemoryLocation, OptionalTimer, TexelBuffer, Timer};

/// Default cell edge in voxels.
pub const CELL: u32 = 16;

/// A macro-cell grid (`--accel grid`): one flag or value range per cell,
/// marched with a 3D DDA.
pub struct Grid {
    pub cell: u32,
    pub counts: [u32; 3],
    /// u32 per cell, 1 = active; or, when `ranges`, vec2(min, max) per
    /// cell: one texel a cell, which the grid's march reads as a texel
    /// buffer (a storage buffer is loaded lane by lane on a CPU device; see
    /// `distance::DistanceMap::distances`).
    pub flags: TexelBuffer,
    /// The cells hold value ranges, decided per ray (MIP, MinIP).
    pub ranges: bool,
    total: u64,
    /// Counted from a flag readback only when statistics are asked for.
    active: std::sync::OnceLock<u64>,
}

impl Grid {
    /// The paper's Table 1 statistics (counts the active cells once).
    pub fn stats(&self) -> Result<Stats> {
        // Ranges are decided per ray: every cell may be marched.
        let active = if self.ranges {
            self.total
        } else {
            count_active(self.flags.buffer(), self.total, &self.active)?
        };
        let unit = if self.cell == 16 { "16^3 cells" } else { "cells" };
        Ok(Stats {
            unit,
            total_bricks: self.total,
            active_bricks: active,
            nodes: self.total,
            leaves: active,
            height: 1,
            bytes: self.flags.buffer().size(),
        })
    }

    /// The push constants of the grid kernels (grid, hybrid): cells per
    /// axis and edge.
    pub fn push(&self) -> march_grid::Push {
        march_grid::Push {
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

/// Records the classification of the cells of `cells` (ranges of `cell`^3
/// bricks) for a TF into a new flag buffer ("classify"). Ends with compute
/// writes.
pub fn record(
    builder: &Builder,
    cmd: Recording<'_>,
    mut timer: Option<&mut Timer>,
    input: &BuildInput,
    cells: &GpuBricks,
) -> Result<Grid> {
    let classifier = builder.shared::<Classifier>()?;
    let ctx = builder.context();
    check_texels(ctx.info(), cells.total)?;
    let flags = Buffer::new(
        ctx,
        "grid cell flags",
        cells.total * 4,
        STORAGE_TEXELS,
        MemoryLocation::GpuOnly,
    )?;
    let flags = TexelBuffer::new(ctx, flags, vk::Format::R32_UINT)?;
    let pass = timer.begin(cmd, "classify")?;
    classifier.record(
        cmd,
        Classify::Range,
        input.gpu_volume,
        cells,
        input.gpu_tf,
        flags.buffer(),
    )?;
    timer.end(cmd, pass);
    Ok(Grid {
        cell: cells.brick,
        counts: cells.counts,
        flags,
        ranges: false,
        total: cells.total,
        active: std::sync::OnceLock::new(),
    })
}

/// Records a copy of the value ranges of `cells` into a new buffer the
/// grid's MIP and MinIP frames read ("classify": what replaces it). Ends
/// with the copy made visible to compute reads.
pub fn record_ranges(
    builder: &Builder,
    cmd: Recording<'_>,
    mut timer: Option<&mut Timer>,
    cells: &GpuBricks,
) -> Result<Grid> {
    let bytes = cells.total * 8;
    check_texels(builder.context().info(), cells.total)?;
    let ranges = Buffer::new(
        builder.context(),
        "grid cell ranges",
        bytes,
        STORAGE_TEXELS,
        MemoryLocation::GpuOnly,
    )?;
    let ranges = TexelBuffer::new(builder.context(), ranges, vk::Format::R32G32_UINT)?;
    let pass = timer.begin(cmd, "classify")?;
    cmd.barrier(Access::COMPUTE_WRITE, Access::TRANSFER_READ);
    let region = [vk::BufferCopy {
        src_offset: 0,
        dst_offset: 0,
        size: bytes,
    }];
    cmd.copy_buffer(&cells.ranges, ranges.buffer(), &region)?;
    cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ);
    timer.end(cmd, pass);
    Ok(Grid {
        cell: cells.brick,
        counts: cells.counts,
        flags: ranges,
        ranges: true,
        total: cells.total,
        active: std::sync::OnceLock::new(),
    })
}

/// The device limit a grid of `cells` cells exceeds, if any: value ranges
/// (MIP, MinIP) take 8 bytes a cell, flags 4, within `maxStorageBufferRange`,
/// and the march reads a texel a cell, within `maxTexelBufferElements`.
pub fn exceeded_limit(info: &crate::gpu::DeviceInfo, cells: u64) -> Option<&'static str> {
    info.exceeded_buffer_limit(cells * 8, cells)
}

/// A grid's march reads a texel a cell: its cells within
/// `maxTexelBufferElements`, checked before anything is allocated.
fn check_texels(info: &crate::gpu::DeviceInfo, cells: u64) -> Result<()> {
    info.check(
        format!("grid of {cells} cells"),
        "maxTexelBufferElements",
        cells,
        info.max_texel_buffer_elements as u64,
    )
}

/// The cell parameter of the grid and the hybrid (default [`CELL`]).
pub(crate) const CELL_PARAM: Param = params::CELL.with_default(Value::Int(CELL));

/// `--accel grid`.
pub struct GridMethod;

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for GridMethod {
    fn name(&self) -> &'static str {
        "grid"
    }
    fn description(&self) -> &'static str {
        "macro-cell grid (OSPRay style), 3D-DDA traversal"
    }
    fn params(&self) -> &'static [Param] {
        &[CELL_PARAM]
    }
    fn ranges(&self, p: &Params) -> Result<RangeKind> {
        Ok(RangeKind::Cells(p.int("cell")?))
    }
    fn march(&self) -> March {
        March::plain(shaders::MARCH_GRID)
    }
    fn record_build(
        &self,
        builder: &Builder,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<Box<dyn Built>> {
        let cells = ranges.cells(p.int("cell")?)?;
        let grid = match input.mode {
            // Several channels classify by the union of their activity
            // functions instead: per-channel running extremes per cell
            // would need per-channel ranges and bounds in the march.
            Mode::Mip | Mode::MinIp if input.gpu_volume.channels == 1 => record_ranges(builder, cmd, timer, cells)?,
            _ => record(builder, cmd, timer, input, cells)?,
        };
        Ok(Box::new(grid))
    }
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for Grid {
    fn bindings(&self) -> Vec<Bound<'_>> {
        march_grid::Own {
            cell_texels: Binding::Texels(&self.flags),
        }
        .list()
    }
    fn push(&self) -> Vec<u8> {
        bytemuck::bytes_of(&self.push()).to_vec()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        Grid::stats(self).map(Some)
    }
}
