//! Workgroup layout of the block-wise primitives (scan, radix sort): a block
//! of 1024 elements is `width` invocations x `items` consecutive elements,
//! passed as specialization constants. GPUs want wide workgroups; CPU drivers
//! (lavapipe) pay for every workgroup barrier per invocation batch, so a
//! narrow workgroup with long serial runs is several times faster there.

use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;

/// Elements per workgroup of the block-wise primitives.
pub const BLOCK: u64 = 1024;

/// How the scan and sort kernels cut their input: `width` invocations a
/// workgroup, `items` elements each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockLayout {
    pub width: u32,
    pub items: u32,
}

impl BlockLayout {
    /// 256 x 4 on GPUs, 32 x 32 on CPU devices.
    pub fn for_device(info: &DeviceInfo) -> Self {
        if info.is_cpu() {
            BlockLayout { width: 32, items: 32 }
        } else {
            BlockLayout { width: 256, items: 4 }
        }
    }

    /// Checks `width * items` is the block size and the width fits the device.
    pub fn check(self, info: &DeviceInfo) -> Result<Self> {
        if self.width as u64 * self.items as u64 != BLOCK || !self.width.is_power_of_two() || self.width < 16 {
            return Err(Error::invalid(
                "block layout",
                format!("{}x{}", self.width, self.items),
                format!("width (a power of two, at least 16: one invocation per radix digit) x items must be {BLOCK}"),
            ));
        }
        info.check(
            format!("workgroup of {} invocations", self.width),
            "maxComputeWorkGroupInvocations",
            self.width as u64,
            info.max_compute_work_group_invocations as u64,
        )?;
        Ok(self)
    }

    pub fn constants(self) -> [u32; 2] {
        [self.width, self.items]
    }
}
