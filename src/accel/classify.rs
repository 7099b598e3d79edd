//! Brick classification for a transfer function.
//!
//! - `Range` (default): active iff the TF's max alpha over the brick's value
//!   range (apron included) is > 0. O(bricks) per TF change; conservative.
//! - `Voxel { apron: true }`: every trilinear cell a sample in the brick can
//!   read goes through the TF (O(voxels) per TF change); gives exactly the
//!   same active bricks as `Range`.
//! - `Voxel { apron: false }`: the paper's brick voting, each voxel of the
//!   brick through the TF at its own value; not conservative (interpolated
//!   samples near brick faces can be lost), kept to reproduce the paper.

use super::bricks::GpuBricks;
use super::params::{Param, Params};
use crate::error::{Error, Result};
use crate::gpu::record;
use crate::gpu::shaders::{self, build_classify_range, build_classify_voxel};
use crate::gpu::{vk, Binding, Buffer, Context, Kernel};
use crate::prims::entry_barrier;
use crate::tf::{GpuTransferFunction, LUT_SIZE};
use crate::volume::GpuVolume;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Classify {
    Range,
    Voxel { apron: bool },
}

/// `--classify range|voxel`.
pub const CLASSIFY: Param = Param::choice(
    "classify",
    &["range", "voxel"],
    "range",
    "Brick classification: range (O(bricks) per TF change) or voxel (every voxel through the TF)",
);
/// `--apron on|off` (with `--classify voxel`).
pub const APRON: Param = Param::switch(
    "apron",
    true,
    "With --classify voxel: keep the one-voxel apron (on), or drop it as the paper does (off; not conservative)",
);

impl Classify {
    /// From a structure's `classify` and `apron` parameters: dropping the
    /// apron is the paper's voxel voting only (range classification is
    /// always conservative).
    pub fn from_params(p: &Params) -> Result<Self> {
        match (p.choice("classify")?, p.switch("apron")?) {
            ("range", true) => Ok(Classify::Range),
            ("range", false) => Err(Error::invalid(
                "apron",
                "off",
                "only --classify voxel can drop the apron (range classification is always conservative)",
            )),
            (_, apron) => Ok(Classify::Voxel { apron }),
        }
    }
}

/// The classification kernels (`Builder::shared`).
pub struct Classifier {
    ctx: Context,
    voxel: Kernel,
}

impl Classifier {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Classifier {
            ctx: ctx.clone(),
            voxel: Kernel::new::<build_classify_voxel::Push>(ctx, &shaders::BUILD_CLASSIFY_VOXEL)?,
        })
    }

    /// Records `flags[b] = 1` for active bricks, 0 otherwise (u32 per brick).
    /// Follows the `prims` barrier convention; ends with compute writes.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        mode: Classify,
        volume: &GpuVolume,
        bricks: &GpuBricks,
        tf: &GpuTransferFunction,
        flags: &Buffer,
    ) -> Result<()> {
        entry_barrier(self.ctx.device(), cmd);
        tf.check_channels(volume.channels)?;
        match mode {
            Classify::Range => {
                // One kernel per channel count (made on first use).
                let range = Kernel::specialized(
                    &self.ctx,
                    &shaders::BUILD_CLASSIFY_RANGE,
                    std::mem::size_of::<build_classify_range::Push>(),
                    &[(0, bricks.channels)],
                )?;
                let groups = record::groups_linear(self.ctx.info(), "classify", bricks.total, range.local_size()[0])?;
                let push = build_classify_range::Push {
                    bricks: bricks.total as u32,
                    groups_x: groups[0],
                    lut_size: LUT_SIZE as u32,
                    tf_stride: tf.channel_step() * tf.max_stride,
                };
                range.dispatch(
                    cmd,
                    &build_classify_range::Bindings {
                        ranges: Binding::Storage(&bricks.ranges),
                        transfer_max: Binding::Storage(&tf.max_table),
                        flags: Binding::Storage(flags),
                    }
                    .list(),
                    bytemuck::bytes_of(&push),
                    groups,
                )
            }
            Classify::Voxel { apron } => {
                let groups =
                    record::groups_linear(self.ctx.info(), "classify", bricks.total, self.voxel.local_size()[0])?;
                let c = bricks.counts;
                // dims.w: brick edge; counts.w: total bricks.
                let push = build_classify_voxel::Push {
                    dims: [volume.dims[0], volume.dims[1], volume.dims[2], bricks.brick],
                    counts: [c[0], c[1], c[2], bricks.total as u32],
                    lo: volume.norms.map(|n| n[0]),
                    scale: volume.norms.map(|n| n[1]),
                    apron: apron as u32,
                    groups_x: groups[0],
                    lut_size: LUT_SIZE as u32,
                    channels: volume.channels,
                    tf_step: tf.channel_step(),
                    max_stride: tf.max_stride,
                    pool_brick: volume.brick_edge(),
                    ..Default::default()
                };
                self.voxel.dispatch(
                    cmd,
                    &build_classify_voxel::Bindings {
                        volume_tex: Binding::Sampled(volume.image.view, volume.sampler),
                        transfer_lut: Binding::Storage(&tf.lut),
                        transfer_max: Binding::Storage(&tf.max_table),
                        flags: Binding::Storage(flags),
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
    }
}

impl super::builder::PerContext for Classifier {
    fn new(ctx: &Context) -> Result<Self> {
        Classifier::new(ctx)
    }
}
