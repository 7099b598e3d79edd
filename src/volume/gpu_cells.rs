//! The volume's cells copy on a `GpuVolume` (`cells.rs`): made once, by
//! the host in memory the device reads on a CPU device, else by a kernel
//! from the volume image, recorded or waited for.

use super::cells;
use super::{GpuVolume, Volume};
use crate::error::Result;
use crate::gpu::Recording;
use crate::gpu::{Kernel, TexelBuffer, Timer, Timings};

impl GpuVolume {
    /// Makes the cells copy (`volume`'s, the volume this was uploaded
    /// from) and waits: packed by the host in place on a CPU device, else
    /// made on the device from the volume image. The manual filter then
    /// fetches one texel per sample instead of eight, with the same result
    /// bit for bit. Costs `TexelKind::bytes_per_voxel` bytes
    /// per voxel (checked against the device's limits first); once is
    /// enough.
    /// Returns the GPU passes it ran (the device's packing, "cells"; none
    /// on a CPU device or where the copy was there).
    pub fn add_cells(&mut self, volume: &Volume) -> Result<Timings> {
        if self.cells.is_some() {
            return Ok(Timings::default());
        }
        self.check_cells_of(volume)?;
        if cells::host_shared(&self.ctx) {
            self.cells = Some(cells::shared_cells(&self.ctx, volume)?);
            return Ok(Timings::default());
        }
        let ctx = self.ctx.clone();
        let mut timer = Timer::new(&ctx, 1)?;
        let (cells, _kernel) = ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            self.record_pack_cells(cmd, Some(&mut timer))
        })?;
        self.cells = Some(cells);
        timer.results()
    }

    /// As `add_cells`, recorded into `cmd` after the volume's upload (see
    /// `record_upload`; timed as pass "cells" on `timer`), ending with a
    /// barrier to compute-shader reads;
    /// nothing to keep but this volume (it holds the kernel). On a CPU
    /// device the host packs the copy at once and nothing is recorded.
    /// Does nothing when the copy is already there.
    pub fn record_add_cells(&mut self, cmd: Recording<'_>, timer: Option<&mut Timer>, volume: &Volume) -> Result<()> {
        if self.cells.is_some() {
            return Ok(());
        }
        self.check_cells_of(volume)?;
        if cells::host_shared(&self.ctx) {
            self.cells = Some(cells::shared_cells(&self.ctx, volume)?);
            return Ok(());
        }
        let (cells, kernel) = self.record_pack_cells(cmd, timer)?;
        self.cells = Some(cells);
        self.cells_kernel = Some(kernel);
        Ok(())
    }

    /// Whether `volume` can have a cells copy here: dense, the volume this
    /// was uploaded from, one channel.
    fn check_cells_of(&self, volume: &Volume) -> Result<()> {
        self.check_dense("the cells copy")?;
        self.check_same(volume, "cells copy")?;
        self.check_one_channel("the cells copy")
    }

    fn record_pack_cells(&self, cmd: Recording<'_>, timer: Option<&mut Timer>) -> Result<(TexelBuffer, Kernel)> {
        self.ctx.check_is(cmd.context(), "command buffer")?;
        let image = (self.image.view, self.sampler);
        let range = self.ctx.info().max_storage_buffer_range;
        // SAFETY: the image and sampler are this volume's, alive while it is
        // (the caller's recording keeps it).
        unsafe { cells::record_pack_cells(cmd, timer, image, self.dims, self.kind, range) }
    }

    /// The cells copy, where `add_cells` (or `record_add_cells`) made it.
    pub fn cells(&self) -> Option<&TexelBuffer> {
        self.cells.as_ref()
    }
}
