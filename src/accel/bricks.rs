//! Per-brick value ranges on the GPU, over a one-voxel apron (DESIGN
//! invariant 2). Computed once per volume upload; every transfer-function
//! change then reclassifies in O(bricks).

use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, Context, MemoryLocation, OptionalTimer, Timer};
use crate::prims::brick_minmax::{brick_counts, coarsens_exactly, BrickMinMax};
use crate::volume::GpuVolume;

/// Brick edge in voxels for the LBVH and classification.
pub const BRICK: u32 = crate::volume::BRICK;

pub struct GpuBricks {
    pub brick: u32,
    pub counts: [u32; 3],
    pub total: u64,
    /// vec2(min, max) of normalised values per brick and channel (at
    /// `brick * channels + channel`), apron included.
    pub ranges: Buffer,
    /// The volume's channels.
    pub channels: u32,
}

impl GpuBricks {
    /// Records the computation of the ranges (timed as `pass`) into `cmd`:
    /// from `finer` (ranges of smaller bricks whose edge divides this one's,
    /// recorded before) where the volume's normalisation allows it
    /// (`coarsens_exactly`), the same ranges from fewer reads; else from
    /// the volume. Ends with compute writes of `ranges` (the `prims`
    /// convention).
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        mut timer: Option<&mut Timer>,
        pass: &str,
        minmax: &BrickMinMax,
        volume: &GpuVolume,
        finer: Option<&GpuBricks>,
    ) -> Result<()> {
        let p = timer.begin(cmd, pass)?;
        match finer.filter(|f| self.brick.is_multiple_of(f.brick) && coarsens_exactly(volume)) {
            Some(f) => {
                minmax.record_coarsen(cmd, volume, (&f.ranges, self.brick / f.brick), self.brick, &self.ranges)?
            }
            None => minmax.record(cmd, volume, self.brick, 1, &self.ranges)?,
        }
        timer.end(cmd, p);
        Ok(())
    }

    /// The ranges buffer of `volume`'s `brick`^3 bricks, not yet computed.
    pub fn allocate(ctx: &Context, volume: &GpuVolume, brick: u32) -> Result<Self> {
        if !brick.is_power_of_two() {
            return Err(Error::invalid(
                "brick size",
                brick.to_string(),
                "must be a power of two",
            ));
        }
        let counts = brick_counts(volume.dims, brick);
        let total = counts.iter().map(|&c| c as u64).product::<u64>();
        if total > u32::MAX as u64 {
            return Err(Error::invalid(
                "volume",
                format!("{:?}", volume.dims),
                "too many bricks",
            ));
        }
        let ranges = Buffer::new(
            ctx,
            "brick ranges",
            total * 8 * volume.channels as u64,
            // A grid's MIP frames copy them (src/accel/grid.rs).
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        Ok(GpuBricks {
            brick,
            counts,
            total,
            ranges,
            channels: volume.channels,
        })
    }
}
