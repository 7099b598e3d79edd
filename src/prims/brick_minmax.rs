//! Per-brick min/max of normalised voxel values over an apron, one invocation
//! per brick, straight from the volume image (from its cells copy where it
//! has one: an eighth of the fetches), or from the ranges of finer
//! bricks over the same apron (`record_coarsen`: exactly the same ranges,
//! `glsl/prims/ranges_coarsen.comp` says why, for a fraction of the reads).

use super::{check_range, entry_barrier};
use crate::error::{Error, Result};
use crate::gpu::record;
use crate::gpu::shaders::{self, prims_brick_minmax as k, prims_ranges_coarsen as coarsen};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation};
use crate::volume::GpuVolume;

/// Per-brick value ranges (apron included) of a volume on the device.
pub struct BrickMinMax {
    ctx: Context,
    coarsen: Kernel,
    /// Bound as the brick list where the kernel reads none.
    no_list: Buffer,
}

/// The ranges kernel's constants (`brick_minmax.comp`): where the voxels
/// come from, their kind and the channels, so each variant compiles only
/// its own path.
const SOURCE_IMAGE: u32 = 0;
const SOURCE_CELLS: u32 = 1;
const SOURCE_POOL: u32 = 2;

/// Bricks per axis for a volume.
pub fn brick_counts(dims: [u32; 3], brick: u32) -> [u32; 3] {
    dims.map(|d| d.div_ceil(brick))
}

impl BrickMinMax {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(BrickMinMax {
            ctx: ctx.clone(),
            coarsen: Kernel::new::<coarsen::Push>(ctx, &shaders::PRIMS_RANGES_COARSEN)?,
            no_list: Buffer::new(
                ctx,
                "no brick list",
                4,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?,
        })
    }

    /// Records `out[b * channels + c] = vec2(min, max)` for every `brick`^3
    /// brick and channel with an apron of `apron` voxels. Ends with compute
    /// writes.
    pub fn record(&self, cmd: Recording<'_>, volume: &GpuVolume, brick: u32, apron: u32, out: &Buffer) -> Result<()> {
        self.record_bricks(cmd, volume, (brick, apron), out, None)
    }

    /// As `record`, for the bricks `listed` only (`list` holds `count` brick
    /// indices, u32): the others of `out` are left as they are.
    pub fn record_listed(
        &self,
        cmd: Recording<'_>,
        volume: &GpuVolume,
        (brick, apron): (u32, u32),
        out: &Buffer,
        (list, count): (&Buffer, u32),
    ) -> Result<()> {
        self.record_bricks(cmd, volume, (brick, apron), out, Some((list, count)))
    }

    fn record_bricks(
        &self,
        cmd: Recording<'_>,
        volume: &GpuVolume,
        (brick, apron): (u32, u32),
        out: &Buffer,
        listed: Option<(&Buffer, u32)>,
    ) -> Result<()> {
        self.ctx.check_is(volume.context(), "volume")?;
        let counts = brick_counts(volume.dims, brick);
        let total = counts.iter().map(|&c| c as u64).product::<u64>();
        check_range(self.ctx.info(), "brick ranges", total * 8 * volume.channels as u64)?;
        check_holds(out, "brick ranges", total * 8 * volume.channels as u64)?;
        if let Some((list, count)) = listed {
            check_holds(list, "brick list", count as u64 * 4)?;
        }
        let (list, n) = listed.unwrap_or((&self.no_list, total as u32));
        // The cells copy serves every box but a one-voxel one inside the
        // volume (brick 1 without apron): its cells pair voxels.
        // (A one-channel copy: the kernel reads it for one channel only.)
        let cells = volume.cells().filter(|_| brick + apron >= 2 && volume.channels == 1);
        let (source, kind) = match (cells, volume.brick_edge()) {
            (Some(_), _) => (SOURCE_CELLS, volume.kind.constant()),
            (None, 0) => (SOURCE_IMAGE, 0),
            (None, _) => (SOURCE_POOL, 0),
        };
        // SAFETY: the constants are the ones this kernel is written for (its own table).
        let kernel = unsafe {
            Kernel::specialized(
                &self.ctx,
                &shaders::PRIMS_BRICK_MINMAX,
                std::mem::size_of::<k::Push>(),
                &[
                    (0, source),
                    (1, kind),
                    (2, volume.channels),
                    (3, listed.is_some() as u32),
                ],
            )
        }?;
        entry_barrier(cmd);
        let groups = record::groups_linear(self.ctx.info(), "brick ranges", n as u64, kernel.local_size()[0])?;
        // dims.w: brick edge; counts.w: total bricks.
        let push = k::Push {
            dims: [volume.dims[0], volume.dims[1], volume.dims[2], brick],
            counts: [counts[0], counts[1], counts[2], n],
            lo: volume.norms.map(|n| n[0]),
            scale: volume.norms.map(|n| n[1]),
            apron,
            groups_x: groups[0],
            pool_brick: volume.brick_edge(),
        };
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            kernel.dispatch(
                cmd,
                &k::Bindings {
                    volume_tex: Binding::Sampled(volume.image.view, volume.sampler),
                    ranges: Binding::Storage(out),
                    brick_table: Binding::Texels(volume.brick_table()),
                    pool_1: Binding::Sampled(volume.pool_views()[0], volume.sampler),
                    pool_2: Binding::Sampled(volume.pool_views()[1], volume.sampler),
                    pool_3: Binding::Sampled(volume.pool_views()[2], volume.sampler),
                    cells: Binding::Texels(cells.unwrap_or(volume.brick_table())),
                    // Not read unless listed (a constant).
                    listed: Binding::Storage(list),
                }
                .list(),
                bytemuck::bytes_of(&push),
                groups,
            )
        }
    }

    /// Records the ranges of `volume`'s `brick`^3 bricks into `out` from
    /// `fine`, the ranges of its (`brick` / `ratio`)^3 bricks over the same
    /// apron (as `record` wrote them). Exact only where every channel's
    /// normalisation scale is finite (`coarsens_exactly`). Ends with compute
    /// writes.
    pub fn record_coarsen(
        &self,
        cmd: Recording<'_>,
        volume: &GpuVolume,
        (fine, ratio): (&Buffer, u32),
        brick: u32,
        out: &Buffer,
    ) -> Result<()> {
        if ratio == 0 || !brick.is_multiple_of(ratio) {
            return Err(Error::invalid(
                "coarsening ratio",
                ratio.to_string(),
                format!("must divide the brick edge {brick}"),
            ));
        }
        let counts = brick_counts(volume.dims, brick);
        let fine_counts = brick_counts(volume.dims, brick / ratio);
        let total = counts.iter().map(|&c| c as u64).product::<u64>();
        check_range(self.ctx.info(), "brick ranges", total * 8 * volume.channels as u64)?;
        check_holds(out, "brick ranges", total * 8 * volume.channels as u64)?;
        let fine_total = fine_counts.iter().map(|&c| c as u64).product::<u64>();
        check_holds(fine, "finer brick ranges", fine_total * 8 * volume.channels as u64)?;
        check_range(
            self.ctx.info(),
            "finer brick ranges",
            fine_total * 8 * volume.channels as u64,
        )?;
        entry_barrier(cmd);
        let groups = record::groups_linear(self.ctx.info(), "brick ranges", total, self.coarsen.local_size()[0])?;
        let push = coarsen::Push {
            fine_counts: [fine_counts[0], fine_counts[1], fine_counts[2], volume.channels],
            counts: [counts[0], counts[1], counts[2], total as u32],
            ratio,
            groups_x: groups[0],
        };
        let bindings = coarsen::Bindings {
            fine: Binding::Storage(fine),
            coarse: Binding::Storage(out),
        };
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.coarsen
                .dispatch(cmd, &bindings.list(), bytemuck::bytes_of(&push), groups)
        }
    }
}

/// Whether coarser ranges of `volume` may be made from finer ones: every
/// channel's normalisation is finite with a scale >= 0, so it keeps the
/// order of values (`glsl/prims/ranges_coarsen.comp`).
pub fn coarsens_exactly(volume: &GpuVolume) -> bool {
    volume.norms[..volume.channels as usize]
        .iter()
        .all(|[lo, scale]| lo.is_finite() && scale.is_finite() && *scale >= 0.0)
}

/// An error unless `buffer` holds `bytes` (what a kernel writes or reads).
fn check_holds(buffer: &Buffer, what: &'static str, bytes: u64) -> Result<()> {
    match buffer.holds(0, bytes) {
        true => Ok(()),
        false => Err(Error::invalid(
            what,
            format!("{} bytes", buffer.size()),
            format!("needs {bytes}"),
        )),
    }
}
