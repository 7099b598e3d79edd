//! Exclusive scan (prefix sum) of u32, in place, over any length: blocks of
//! 1024 are scanned in shared memory, block totals are scanned recursively,
//! then added back.

use super::layout::{BlockLayout, BLOCK};
use super::{check_elements, check_range, entry_barrier};
use crate::error::Result;
use crate::gpu::record::{self};
use crate::gpu::shaders::{self, prims_scan_add, prims_scan_blocks};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation};

/// An exclusive prefix sum of u32 on the device.
pub struct Scan {
    ctx: Context,
    blocks: Kernel,
    add: Kernel,
}

/// Block-total buffers for every level of a scan of up to `capacity` elements.
pub struct ScanScratch {
    capacity: u64,
    levels: Vec<Buffer>,
    dummy: Buffer,
}

impl Scan {
    /// With the device's block layout (`BlockLayout::for_device`).
    pub fn new(ctx: &Context) -> Result<Self> {
        Self::with_layout(ctx, BlockLayout::for_device(ctx.info()))
    }

    pub fn with_layout(ctx: &Context, layout: BlockLayout) -> Result<Self> {
        let c = layout.check(ctx.info())?.constants();
        Ok(Scan {
            ctx: ctx.clone(),
            // SAFETY: the constants are the ones this kernel is written for (its own table).
            blocks: unsafe { Kernel::with_constants::<prims_scan_blocks::Push>(ctx, &shaders::PRIMS_SCAN_BLOCKS, &c) }?,
            // SAFETY: the constants are the ones this kernel is written for (its own table).
            add: unsafe { Kernel::with_constants::<prims_scan_add::Push>(ctx, &shaders::PRIMS_SCAN_ADD, &c) }?,
        })
    }

    pub fn scratch(&self, capacity: u64) -> Result<ScanScratch> {
        check_range(self.ctx.info(), "scan input", capacity * 4)?;
        let mut levels = Vec::new();
        let mut n = capacity;
        while n > BLOCK {
            n = n.div_ceil(BLOCK);
            levels.push(Buffer::new(
                &self.ctx,
                "scan block sums",
                n * 4,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?);
        }
        let dummy = Buffer::new(
            &self.ctx,
            "scan dummy",
            4,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        Ok(ScanScratch {
            capacity,
            levels,
            dummy,
        })
    }

    /// Records an exclusive scan of `data[0..n]` in place (see the barrier
    /// convention in `prims`).
    pub fn record(&self, cmd: Recording<'_>, data: &Buffer, n: u64, scratch: &ScanScratch) -> Result<()> {
        check_elements("scan", n, scratch.capacity, &[data])?;
        entry_barrier(cmd);
        self.level(cmd, data, n, scratch, 0)
    }

    fn level(&self, cmd: Recording<'_>, data: &Buffer, n: u64, scratch: &ScanScratch, depth: usize) -> Result<()> {
        if n == 0 {
            return Ok(());
        }
        let info = self.ctx.info();
        let blocks = n.div_ceil(BLOCK);
        let groups = record::groups_linear(info, "scan", blocks, 1)?;
        let sums = if blocks > 1 {
            &scratch.levels[depth]
        } else {
            &scratch.dummy
        };
        let push = prims_scan_blocks::Push {
            n: n as u32,
            groups_x: groups[0],
            write_sums: (blocks > 1) as u32,
            pad: 0,
        };
        let bindings = prims_scan_blocks::Bindings {
            data: Binding::Storage(data),
            sums: Binding::Storage(sums),
        };
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.blocks
                .dispatch(cmd, &bindings.list(), bytemuck::bytes_of(&push), groups)
        }?;
        if blocks > 1 {
            cmd.compute_to_compute();
            self.level(cmd, sums, blocks, scratch, depth + 1)?;
            cmd.compute_to_compute();
            let push = prims_scan_add::Push {
                n: n as u32,
                groups_x: groups[0],
                ..Default::default()
            };
            let bindings = prims_scan_add::Bindings {
                data: Binding::Storage(data),
                offsets: Binding::Storage(sums),
            };
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.add
                    .dispatch(cmd, &bindings.list(), bytemuck::bytes_of(&push), groups)
            }?;
        }
        Ok(())
    }
}
