//! Per-brick value ranges on the GPU, over a one-voxel apron (DESIGN
//! invariant 2). Computed once per volume upload; every transfer-function
//! change then reclassifies in O(bricks).

use crate::error::{Error, Result};
use crate::gpu::record::Access;
use crate::gpu::Recording;
use crate::gpu::{vk, Buffer, Context, MemoryLocation, OptionalTimer, Staging, Timer};
use crate::prims::brick_minmax::{brick_counts, coarsens_exactly, BrickMinMax};
use crate::prims::entry_barrier;
use crate::volume::{GpuVolume, APRON};

/// Brick edge in voxels for the LBVH and classification.
pub const BRICK: u32 = crate::volume::BRICK;

/// The volume's bricks on the device: per brick and channel the value range
/// over the brick and its apron, which classification reads.
pub struct GpuBricks {
    pub(crate) brick: u32,
    pub(crate) counts: [u32; 3],
    pub(crate) total: u64,
    /// vec2(min, max) of normalised values per brick and channel (at
    /// `brick * channels + channel`), apron included.
    pub(crate) ranges: Buffer,
    /// The volume's channels.
    pub(crate) channels: u32,
    /// How many bricks' ranges were read from the voxels (`total`, or a
    /// series step's changed bricks; 0 when coarsened from finer ranges).
    pub(crate) computed: u64,
    /// The changed bricks' list a step's ranges were recorded with: kept
    /// until the submission completed.
    _list: Option<(Buffer, Staging)>,
}

/// Where `GpuBricks::record` takes the ranges from.
pub enum RangesFrom<'a> {
    /// The volume's voxels, every brick.
    Volume,
    /// Ranges of smaller bricks whose edge divides this one's, recorded
    /// before (used where the volume's normalisation allows it:
    /// `coarsens_exactly`; else the voxels).
    Finer(&'a GpuBricks),
    /// A series step's: the step before's ranges of these bricks (`ranges`,
    /// the same grid, normalisation and channels), and the bricks whose
    /// voxels changed since (`StepDelta::bricks_changed`), computed from
    /// the voxels; the others are copied.
    Step { ranges: &'a Buffer, changed: Vec<u32> },
}

impl GpuBricks {
    /// The brick edge in voxels.
    pub fn brick(&self) -> u32 {
        self.brick
    }

    /// Bricks per axis.
    pub fn counts(&self) -> [u32; 3] {
        self.counts
    }

    /// Bricks in all.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// vec2(min, max) of normalised values per brick and channel (at
    /// `brick * channels + channel`), apron included.
    pub fn ranges(&self) -> &Buffer {
        &self.ranges
    }

    /// The volume's channels.
    pub fn channels(&self) -> u32 {
        self.channels
    }

    /// How many bricks' ranges were read from the voxels (`total`, or a
    /// series step's changed bricks; 0 when coarsened from finer ranges).
    pub fn computed(&self) -> u64 {
        self.computed
    }

    /// Records the computation of the ranges (timed as `pass`) into `cmd`,
    /// `from` where it can (`RangesFrom`), the same ranges from fewer
    /// reads. Ends with compute and transfer writes of `ranges` (the
    /// `prims` convention; `entry_barrier` makes both visible).
    pub fn record(
        &mut self,
        cmd: Recording<'_>,
        mut timer: Option<&mut Timer>,
        pass: &str,
        minmax: &BrickMinMax,
        volume: &GpuVolume,
        from: RangesFrom,
    ) -> Result<()> {
        let p = timer.begin(cmd, pass)?;
        match from {
            RangesFrom::Finer(f) if self.brick.is_multiple_of(f.brick) && coarsens_exactly(volume) => {
                minmax.record_coarsen(cmd, volume, (&f.ranges, self.brick / f.brick), self.brick, &self.ranges)?;
                self.computed = 0;
            }
            RangesFrom::Step { ranges, changed } => {
                if ranges.size() != self.ranges.size() || changed.iter().any(|&b| b as u64 >= self.total) {
                    return Err(Error::invalid(
                        "step ranges",
                        format!("{} bytes", ranges.size()),
                        "must be ranges of the same bricks, and the changed bricks among them",
                    ));
                }
                entry_barrier(cmd);
                let region = [vk::BufferCopy::default().size(self.ranges.size())];
                cmd.copy_buffer(ranges, &self.ranges, &region)?;
                self.computed = changed.len() as u64;
                if !changed.is_empty() {
                    let (list, staging) = Buffer::record_with_data(
                        cmd,
                        "changed bricks",
                        bytemuck::cast_slice(&changed),
                        vk::BufferUsageFlags::STORAGE_BUFFER,
                    )?;
                    let count = changed.len() as u32;
                    minmax.record_listed(cmd, volume, (self.brick, APRON), &self.ranges, (&list, count))?;
                    self._list = Some((list, staging));
                } else {
                    cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ);
                }
            }
            _ => {
                minmax.record(cmd, volume, self.brick, APRON, &self.ranges)?;
                self.computed = self.total;
            }
        }
        timer.end(cmd, p);
        Ok(())
    }

    /// Records a copy of the ranges into `to` (a buffer of their size) for
    /// the next step (`RangesFrom::Step`), after `entry_barrier`; ends with
    /// one, so the copy's read is ordered before later writes.
    pub fn record_keep(&self, cmd: Recording<'_>, to: &Buffer) -> Result<()> {
        let region = [vk::BufferCopy::default().size(self.ranges.size())];
        entry_barrier(cmd);
        cmd.copy_buffer(&self.ranges, to, &region)?;
        entry_barrier(cmd);
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
            // A grid's MIP frames copy them (src/accel/grid.rs); a series
            // step's are copied from and to the step before's.
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(GpuBricks {
            brick,
            counts,
            total,
            ranges,
            channels: volume.channels,
            computed: 0,
            _list: None,
        })
    }
}
