//! GPU primitives: exclusive scan, stream compaction, LSD radix sort and
//! per-brick min/max. Each owns no device state beyond its kernels and only
//! records into the caller's command buffer.
//!
//! Barrier convention, the same for every primitive: `record` begins with one
//! global barrier that makes earlier compute-shader and transfer writes
//! visible to its own reads, and separates its internal passes with global
//! barriers. It ends right after its last write (a compute-shader write, or a
//! transfer write where it says so); the caller orders its next use of the
//! outputs with a barrier from `Access::COMPUTE_WRITE` (and `TRANSFER_WRITE`).
//! Dispatches larger than `maxComputeWorkGroupCount[0]` workgroups use a 2-D
//! grid; no primitive uses subgroup operations, so no subgroup size is assumed.

pub mod brick_minmax;
pub mod compact;
pub mod layout;
pub mod radix_sort;
pub mod scan;

pub use brick_minmax::BrickMinMax;
pub use compact::{Compact, CompactScratch};
pub use layout::BlockLayout;
pub use radix_sort::{RadixSort, SortScratch};
pub use scan::{Scan, ScanScratch};

use crate::gpu::record::Access;
use crate::gpu::vk;
use crate::gpu::Recording;

/// Push-constant bytes from u32 words.
pub fn words(w: &[u32]) -> Vec<u8> {
    bytemuck::cast_slice(w).to_vec()
}

/// Earlier compute and transfer writes become visible to compute and transfer reads.
pub fn entry_barrier(cmd: Recording<'_>) {
    let src = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER,
        access: vk::AccessFlags2::SHADER_WRITE | vk::AccessFlags2::TRANSFER_WRITE,
    };
    let dst = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER,
        access: vk::AccessFlags2::SHADER_READ
            | vk::AccessFlags2::SHADER_WRITE
            | vk::AccessFlags2::TRANSFER_READ
            | vk::AccessFlags2::TRANSFER_WRITE,
    };
    cmd.barrier(src, dst);
}

/// Checks that `bytes` of one storage binding fit `maxStorageBufferRange`.
pub fn check_range(info: &crate::gpu::DeviceInfo, what: &str, bytes: u64) -> crate::Result<()> {
    info.check(
        format!("{what} ({bytes} bytes)"),
        "maxStorageBufferRange",
        bytes,
        info.max_storage_buffer_range,
    )
}

/// Checks a primitive's `n` 32-bit elements against its scratch's
/// `capacity` and the size of each buffer in `buffers` it reads or writes.
pub fn check_elements(what: &'static str, n: u64, capacity: u64, buffers: &[&crate::gpu::Buffer]) -> crate::Result<()> {
    use crate::error::Error;
    if n > capacity {
        return Err(Error::invalid(
            what,
            format!("of {n} elements"),
            format!("its scratch holds {capacity}"),
        ));
    }
    for b in buffers {
        if b.size() < n.saturating_mul(4) {
            return Err(Error::invalid(
                what,
                format!("of {n} elements"),
                format!("buffer '{}' holds {} bytes", b.name(), b.size()),
            ));
        }
    }
    Ok(())
}
