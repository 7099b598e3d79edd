//! Stream compaction by flag: the indices i with flags[i] != 0, in order, and
//! their count.

use super::scan::{Scan, ScanScratch};
use super::{check_elements, entry_barrier};
use crate::error::Result;
use crate::gpu::record::{self, Access};
use crate::gpu::shaders::{self, prims_compact as k};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation};

/// Stream compaction on the device: the indices of flagged elements, in order.
pub struct Compact {
    ctx: Context,
    kernel: Kernel,
    scan: Scan,
}

/// Device memory a `Compact` of up to `capacity` elements needs.
pub struct CompactScratch {
    capacity: u64,
    offsets: Buffer,
    scan: ScanScratch,
}

impl Compact {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Compact {
            ctx: ctx.clone(),
            kernel: Kernel::new::<k::Push>(ctx, &shaders::PRIMS_COMPACT)?,
            scan: Scan::new(ctx)?,
        })
    }

    pub fn scratch(&self, capacity: u64) -> Result<CompactScratch> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        Ok(CompactScratch {
            capacity,
            offsets: Buffer::new(
                &self.ctx,
                "compact offsets",
                capacity * 4,
                usage,
                MemoryLocation::GpuOnly,
            )?,
            scan: self.scan.scratch(capacity)?,
        })
    }

    /// Flags must be 0 or 1 (they are summed to place each index).
    /// Records: `indices[0..count]` = the i < n with `flags[i] == 1`, in
    /// increasing order; `count[0]` = how many. `flags` needs TRANSFER_SRC
    /// usage, `count` TRANSFER_DST. Ends with compute writes.
    pub fn record(
        &self,
        cmd: Recording<'_>,
        flags: &Buffer,
        n: u64,
        indices: &Buffer,
        count: &Buffer,
        scratch: &CompactScratch,
    ) -> Result<()> {
        check_elements("compaction", n, scratch.capacity, &[flags, indices])?;
        check_elements("compaction count", 1, 1, &[count])?;
        entry_barrier(cmd);
        cmd.fill_buffer(count, 0, 4, 0)?;
        if n == 0 {
            return Ok(());
        }
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: n * 4,
        }];
        cmd.copy_buffer(flags, &scratch.offsets, &region)?;
        self.scan.record(cmd, &scratch.offsets, n, &scratch.scan)?;
        cmd.barrier(Access::COMPUTE_WRITE, Access::COMPUTE_READ);
        let groups = record::groups_linear(self.ctx.info(), "compact", n, self.kernel.local_size()[0])?;
        let push = k::Push {
            n: n as u32,
            groups_x: groups[0],
            ..Default::default()
        };
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.kernel.dispatch(
                cmd,
                &k::Bindings {
                    flags: Binding::Storage(flags),
                    offsets: Binding::Storage(&scratch.offsets),
                    out: Binding::Storage(indices),
                    count: Binding::Storage(count),
                }
                .list(),
                bytemuck::bytes_of(&push),
                groups,
            )
        }
    }
}
