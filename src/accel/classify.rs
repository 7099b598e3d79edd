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
use crate::gpu::{shaders, vk, Binding, Buffer, Context, Kernel};
use crate::prims::{entry_barrier, words};
use crate::tf::{GpuTransferFunction, LUT_SIZE};
use crate::volume::GpuVolume;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
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

pub struct Classifier {
    ctx: Context,
    range: Kernel,
    voxel: Kernel,
}

impl Classifier {
    pub fn new(ctx: &Context) -> Result<Self> {
        use vk::DescriptorType as D;
        Ok(Classifier {
            ctx: ctx.clone(),
            range: Kernel::new(
                ctx,
                "build/classify_range",
                shaders::BUILD_CLASSIFY_RANGE,
                &[D::STORAGE_BUFFER; 3],
                16,
            )?,
            voxel: Kernel::new(
                ctx,
                "build/classify_voxel",
                shaders::BUILD_CLASSIFY_VOXEL,
                &[
                    D::COMBINED_IMAGE_SAMPLER,
                    D::STORAGE_BUFFER,
                    D::STORAGE_BUFFER,
                    D::STORAGE_BUFFER,
                ],
                64,
            )?,
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
        let groups = record::groups_linear(self.ctx.info(), "classify", bricks.total, 64)?;
        match mode {
            Classify::Range => {
                let push = words(&[bricks.total as u32, groups[0], LUT_SIZE as u32, 0]);
                self.range.dispatch(
                    cmd,
                    &[
                        Binding::Storage(&bricks.ranges),
                        Binding::Storage(&tf.max_table),
                        Binding::Storage(flags),
                    ],
                    &push,
                    groups,
                );
            }
            Classify::Voxel { apron } => {
                let c = bricks.counts;
                let mut push = words(&[
                    volume.dims[0],
                    volume.dims[1],
                    volume.dims[2],
                    bricks.brick,
                    c[0],
                    c[1],
                    c[2],
                    bricks.total as u32,
                ]);
                push.extend(bytemuck::cast_slice(&volume.norm));
                push.extend(words(&[apron as u32, groups[0], LUT_SIZE as u32, 0, 0, 0]));
                self.voxel.dispatch(
                    cmd,
                    &[
                        Binding::Sampled(volume.image.view, volume.sampler),
                        Binding::Storage(&tf.lut),
                        Binding::Storage(&tf.max_table),
                        Binding::Storage(flags),
                    ],
                    &push,
                    groups,
                );
            }
        }
        Ok(())
    }
}
