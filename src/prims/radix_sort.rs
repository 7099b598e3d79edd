//! LSD radix sort of u32 keys with u32 payloads, stable, 4 bits per pass;
//! `key_bits` sets the number of passes (30-bit Morton codes need 8).

use super::layout::BlockLayout;
use super::layout::BLOCK;
use super::scan::{Scan, ScanScratch};
use super::{check_elements, check_range, entry_barrier};
use crate::error::{Error, Result};
use crate::gpu::record::{self, Access};
use crate::gpu::shaders::{self, prims_radix_hist, prims_radix_scatter};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation};

/// Key bits each pass of the radix sort orders.
pub const BITS_PER_PASS: u32 = 4;

/// A stable LSD radix sort of u32 keys with u32 payloads on the device.
pub struct RadixSort {
    ctx: Context,
    hist: Kernel,
    scatter: Kernel,
    scan: Scan,
}

/// Ping-pong and histogram buffers for sorts of up to `capacity` elements.
pub struct SortScratch {
    capacity: u64,
    keys: Buffer,
    vals: Buffer,
    hist: Buffer,
    scan: ScanScratch,
}

impl RadixSort {
    /// With the device's block layout (`BlockLayout::for_device`).
    pub fn new(ctx: &Context) -> Result<Self> {
        Self::with_layout(ctx, BlockLayout::for_device(ctx.info()))
    }

    pub fn with_layout(ctx: &Context, layout: BlockLayout) -> Result<Self> {
        let c = layout.check(ctx.info())?.constants();
        Ok(RadixSort {
            ctx: ctx.clone(),
            // SAFETY: the constants are the ones this kernel is written for (its own table).
            hist: unsafe { Kernel::with_constants::<prims_radix_hist::Push>(ctx, &shaders::PRIMS_RADIX_HIST, &c) }?,
            // SAFETY: the constants are the ones this kernel is written for (its own table).
            scatter: unsafe {
                Kernel::with_constants::<prims_radix_scatter::Push>(ctx, &shaders::PRIMS_RADIX_SCATTER, &c)
            }?,
            scan: Scan::with_layout(ctx, layout)?,
        })
    }

    pub fn scratch(&self, capacity: u64) -> Result<SortScratch> {
        let info = self.ctx.info();
        check_range(info, "sort keys", capacity * 4)?;
        if capacity > u32::MAX as u64 {
            return Err(Error::invalid(
                "sort size",
                capacity.to_string(),
                "at most 2^32 - 1 elements",
            ));
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        let hist_len = 16 * capacity.div_ceil(BLOCK).max(1);
        Ok(SortScratch {
            capacity,
            keys: Buffer::new(
                &self.ctx,
                "sort keys (ping-pong)",
                capacity * 4,
                usage,
                MemoryLocation::GpuOnly,
            )?,
            vals: Buffer::new(
                &self.ctx,
                "sort values (ping-pong)",
                capacity * 4,
                usage,
                MemoryLocation::GpuOnly,
            )?,
            hist: Buffer::new(
                &self.ctx,
                "sort histogram",
                hist_len * 4,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?,
            scan: self.scan.scratch(hist_len)?,
        })
    }

    /// Records a stable sort of `keys[0..n]` (and `vals` alongside) by their
    /// low `key_bits` bits, in place. Both buffers need TRANSFER_SRC and
    /// TRANSFER_DST usage. Ends with compute or transfer writes.
    pub fn record(
        &self,
        cmd: Recording<'_>,
        keys: &Buffer,
        vals: &Buffer,
        n: u64,
        key_bits: u32,
        scratch: &SortScratch,
    ) -> Result<()> {
        if !(1..=32).contains(&key_bits) {
            return Err(Error::invalid("key bits", key_bits.to_string(), "must be in 1..=32"));
        }
        check_elements("sort", n, scratch.capacity, &[keys, vals])?;
        entry_barrier(cmd);
        if n <= 1 {
            return Ok(());
        }
        let blocks = n.div_ceil(BLOCK);
        let groups = record::groups_linear(self.ctx.info(), "radix sort", blocks, 1)?;
        let passes = key_bits.div_ceil(BITS_PER_PASS);
        let bufs = [(keys, vals), (&scratch.keys, &scratch.vals)];
        for pass in 0..passes {
            let (src, dst) = (bufs[pass as usize % 2], bufs[(pass as usize + 1) % 2]);
            // The last pass of a key width that is not a multiple of 4 sees only the remaining bits.
            let shift = pass * BITS_PER_PASS;
            let digit_mask = (1u32 << (key_bits - shift).min(BITS_PER_PASS)) - 1;
            // One block for both kernels (`prims_radix_scatter::Push` is hist's).
            let push = prims_radix_hist::Push {
                n: n as u32,
                groups_x: groups[0],
                shift,
                blocks: blocks as u32,
                digit_mask,
                ..Default::default()
            };
            let push = bytemuck::bytes_of(&push);
            if pass > 0 {
                cmd.compute_to_compute();
            }
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.hist.dispatch(
                    cmd,
                    &prims_radix_hist::Bindings {
                        keys: Binding::Storage(src.0),
                        hist: Binding::Storage(&scratch.hist),
                    }
                    .list(),
                    push,
                    groups,
                )
            }?;
            self.scan.record(cmd, &scratch.hist, 16 * blocks, &scratch.scan)?;
            cmd.compute_to_compute();
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.scatter.dispatch(
                    cmd,
                    &prims_radix_scatter::Bindings {
                        keys_in: Binding::Storage(src.0),
                        vals_in: Binding::Storage(src.1),
                        keys_out: Binding::Storage(dst.0),
                        vals_out: Binding::Storage(dst.1),
                        offsets: Binding::Storage(&scratch.hist),
                    }
                    .list(),
                    push,
                    groups,
                )
            }?;
        }
        if passes % 2 == 1 {
            cmd.barrier(Access::COMPUTE_WRITE, Access::TRANSFER_READ);
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: n * 4,
            }];
            cmd.copy_buffer(&scratch.keys, keys, &region)?;
            cmd.copy_buffer(&scratch.vals, vals, &region)?;
        }
        Ok(())
    }
}
