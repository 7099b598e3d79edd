//! Per-brick value ranges on the GPU, over a one-voxel apron (DESIGN
//! invariant 2). Computed once per volume upload; every transfer-function
//! change then reclassifies in O(bricks).

use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, Context, MemoryLocation, Timer};
use crate::prims::brick_minmax::{brick_counts, BrickMinMax};
use crate::volume::GpuVolume;

/// Brick edge in voxels for the LBVH and classification.
pub const BRICK: u32 = crate::volume::BRICK;

pub struct GpuBricks {
    pub brick: u32,
    pub counts: [u32; 3],
    pub total: u64,
    /// vec2(min, max) of normalised values per brick, apron included.
    pub ranges: Buffer,
}

impl GpuBricks {
    /// Computes the ranges of `volume`'s `brick`^3 bricks; returns them and
    /// the GPU milliseconds it took.
    pub fn compute(ctx: &Context, minmax: &BrickMinMax, volume: &GpuVolume, brick: u32) -> Result<(Self, f64)> {
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
            total * 8,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        let mut timer = Timer::new(ctx, 1)?;
        ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            let pass = timer.begin(cmd, "ranges")?;
            minmax.record(cmd, volume, brick, 1, &ranges)?;
            timer.end(cmd, pass);
            Ok(())
        })?;
        Ok((
            GpuBricks {
                brick,
                counts,
                total,
                ranges,
            },
            timer.results()?.phase("ranges")?,
        ))
    }
}
