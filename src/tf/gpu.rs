//! A transfer function on the device (`TransferFunction::upload`).

use super::ONE_TF_EACH;
use crate::error::{Error, Result};
use crate::gpu::Buffer;

/// A transfer function on the GPU: the LUT the marchers sample and the
/// max-alpha table classification queries. Uploads wait, so both are visible
/// to compute reads when `upload` returns. Read through its methods: the
/// kernels index its buffers by what its fields say.
pub struct GpuTransferFunction {
    pub(crate) lut: Buffer,
    pub(crate) max_table: Buffer,
    /// `TransferFunction::visible_entries` of channel 1 (MIP and MinIP of
    /// one channel skip by it).
    pub(crate) visible: Option<[u32; 2]>,
    /// Transfer functions held, channel after channel (1: one for every
    /// channel of the volume).
    pub(crate) channels: u32,
    /// Entries of one channel's max table (`tf_range.glsl`).
    pub(crate) max_stride: u32,
    /// `TransferFunction::alpha_key` of what was uploaded.
    pub(crate) alpha_key: u64,
}

impl GpuTransferFunction {
    /// The LUT the marchers sample (RGBA f32 entries, channel after channel).
    pub fn lut(&self) -> &Buffer {
        &self.lut
    }

    /// The max-alpha table classification queries.
    pub fn max_table(&self) -> &Buffer {
        &self.max_table
    }

    /// The context it was uploaded with.
    pub fn context(&self) -> &crate::gpu::Context {
        self.lut.context()
    }

    /// `TransferFunction::alpha_key` of the transfer function uploaded.
    pub fn alpha_key(&self) -> u64 {
        self.alpha_key
    }

    /// `TransferFunction::visible_entries` of channel 1.
    pub fn visible(&self) -> Option<[u32; 2]> {
        self.visible
    }

    /// Transfer functions held (1: one for every channel of the volume).
    pub fn channels(&self) -> u32 {
        self.channels
    }

    /// An error unless it suits `volume` (`TransferFunction::check_channels`).
    pub fn check_channels(&self, volume_channels: u32) -> Result<()> {
        if self.channels != 1 && self.channels != volume_channels {
            return Err(Error::invalid(
                "transfer function",
                format!("{} channels", self.channels),
                format!("the volume has {volume_channels}: {ONE_TF_EACH}"),
            ));
        }
        Ok(())
    }

    /// How far apart channels' tables are, in tables (0: one for all).
    pub fn channel_step(&self) -> u32 {
        (self.channels > 1) as u32
    }
}
