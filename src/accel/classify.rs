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
use crate::error::{Error, Result};
use crate::gpu::record;
use crate::gpu::{check_push, shaders, vk, Binding, Buffer, Context, Kernel};
use crate::prims::entry_barrier;
use crate::tf::{GpuTransferFunction, LUT_SIZE};
use crate::volume::GpuVolume;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Classify {
    Range,
    Voxel { apron: bool },
}

impl Classify {
    /// From `--classify range|voxel` and `--apron on|off`.
    pub fn parse(mode: &str, apron: &str) -> Result<Self> {
        let apron = match apron {
            "on" => true,
            "off" => false,
            other => return Err(Error::invalid("apron", other, "expected on or off")),
        };
        match (mode, apron) {
            ("range", true) => Ok(Classify::Range),
            ("range", false) => Err(Error::invalid(
                "apron",
                "off",
                "only --classify voxel can drop the apron (range classification is always conservative)",
            )),
            ("voxel", apron) => Ok(Classify::Voxel { apron }),
            (other, _) => Err(Error::invalid("classify", other, "expected range or voxel")),
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            Classify::Range => "range",
            Classify::Voxel { apron: true } => "voxel, apron on",
            Classify::Voxel { apron: false } => "voxel, apron off (paper)",
        }
    }
}

/// Push block of `classify_range.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RangePush {
    bricks: u32,
    groups_x: u32,
    lut_size: u32,
    pad: u32,
}
check_push!(RangePush, shaders::BUILD_CLASSIFY_RANGE);

/// Push block of `classify_voxel.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct VoxelPush {
    /// xyz: volume dims; w: brick edge.
    dims: [u32; 4],
    /// xyz: bricks per axis; w: total bricks.
    counts: [u32; 4],
    norm: [f32; 2],
    apron: u32,
    groups_x: u32,
    lut_size: u32,
    pad: [u32; 3],
}
check_push!(VoxelPush, shaders::BUILD_CLASSIFY_VOXEL);

pub struct Classifier {
    ctx: Context,
    range: Kernel,
    voxel: Kernel,
}

impl Classifier {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Classifier {
            ctx: ctx.clone(),
            range: Kernel::new::<RangePush>(ctx, &shaders::BUILD_CLASSIFY_RANGE)?,
            voxel: Kernel::new::<VoxelPush>(ctx, &shaders::BUILD_CLASSIFY_VOXEL)?,
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
        let groups = record::groups_linear(self.ctx.info(), "classify", bricks.total, self.range.local_size()[0])?;
        match mode {
            Classify::Range => {
                let push = RangePush {
                    bricks: bricks.total as u32,
                    groups_x: groups[0],
                    lut_size: LUT_SIZE as u32,
                    pad: 0,
                };
                self.range.dispatch(
                    cmd,
                    &[
                        Binding::Storage(&bricks.ranges),
                        Binding::Storage(&tf.max_table),
                        Binding::Storage(flags),
                    ],
                    bytemuck::bytes_of(&push),
                    groups,
                )
            }
            Classify::Voxel { apron } => {
                let c = bricks.counts;
                let push = VoxelPush {
                    dims: [volume.dims[0], volume.dims[1], volume.dims[2], bricks.brick],
                    counts: [c[0], c[1], c[2], bricks.total as u32],
                    norm: volume.norm,
                    apron: apron as u32,
                    groups_x: groups[0],
                    lut_size: LUT_SIZE as u32,
                    pad: [0; 3],
                };
                self.voxel.dispatch(
                    cmd,
                    &[
                        Binding::Sampled(volume.image.view, volume.sampler),
                        Binding::Storage(&tf.lut),
                        Binding::Storage(&tf.max_table),
                        Binding::Storage(flags),
                    ],
                    bytemuck::bytes_of(&push),
                    groups,
                )
            }
        }
    }
}
