//! Per-brick min/max of normalised voxel values over an apron, one invocation
//! per brick, straight from the volume image.

use super::{check_range, entry_barrier};
use crate::error::Result;
use crate::gpu::record;
use crate::gpu::shaders::{self, prims_brick_minmax as k};
use crate::gpu::{vk, Binding, Buffer, Context, Kernel};
use crate::volume::GpuVolume;

pub struct BrickMinMax {
    ctx: Context,
    kernel: Kernel,
}

/// Bricks per axis for a volume.
pub fn brick_counts(dims: [u32; 3], brick: u32) -> [u32; 3] {
    dims.map(|d| d.div_ceil(brick))
}

impl BrickMinMax {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(BrickMinMax {
            ctx: ctx.clone(),
            kernel: Kernel::new::<k::Push>(ctx, &shaders::PRIMS_BRICK_MINMAX)?,
        })
    }

    /// Records `out[b * channels + c] = vec2(min, max)` for every `brick`^3
    /// brick and channel with an apron of `apron` voxels. Ends with compute
    /// writes.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        volume: &GpuVolume,
        brick: u32,
        apron: u32,
        out: &Buffer,
    ) -> Result<()> {
        let counts = brick_counts(volume.dims, brick);
        let total = counts.iter().map(|&c| c as u64).product::<u64>();
        check_range(self.ctx.info(), "brick ranges", total * 8 * volume.channels as u64)?;
        entry_barrier(self.ctx.device(), cmd);
        let groups = record::groups_linear(self.ctx.info(), "brick ranges", total, self.kernel.local_size()[0])?;
        // dims.w: brick edge; counts.w: total bricks.
        let push = k::Push {
            dims: [volume.dims[0], volume.dims[1], volume.dims[2], brick],
            counts: [counts[0], counts[1], counts[2], total as u32],
            lo: volume.norms.map(|n| n[0]),
            scale: volume.norms.map(|n| n[1]),
            apron,
            groups_x: groups[0],
            channels: volume.channels,
            pool_brick: volume.brick_edge(),
        };
        self.kernel.dispatch(
            cmd,
            &k::Bindings {
                volume_tex: Binding::Sampled(volume.image.view, volume.sampler),
                ranges: Binding::Storage(out),
                brick_table: Binding::TexelBuffer(volume.brick_table().view()),
                pool_1: Binding::Sampled(volume.pool_views()[0], volume.sampler),
                pool_2: Binding::Sampled(volume.pool_views()[1], volume.sampler),
                pool_3: Binding::Sampled(volume.pool_views()[2], volume.sampler),
            }
            .list(),
            bytemuck::bytes_of(&push),
            groups,
        )
    }
}
