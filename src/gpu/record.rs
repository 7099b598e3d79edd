//! Recording helpers: synchronization2 barriers between dependent passes and
//! dispatch sizing that respects `maxComputeWorkGroupCount`.
//!
//! Dependent compute passes are separated by one global memory barrier
//! (`barrier(.., Access::COMPUTE_WRITE, Access::COMPUTE_READ_WRITE)`); buffer-
//! or image-range barriers buy nothing on current drivers.

use super::DeviceInfo;
use crate::error::Result;
use ash::vk;

/// A pipeline stage together with the memory accesses made there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
}

impl Access {
    pub const NONE: Access = Access {
        stage: vk::PipelineStageFlags2::NONE,
        access: vk::AccessFlags2::NONE,
    };
    pub const COMPUTE_READ: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::SHADER_READ,
    };
    pub const COMPUTE_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::SHADER_WRITE,
    };
    pub const COMPUTE_READ_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::SHADER_READ.as_raw() | vk::AccessFlags2::SHADER_WRITE.as_raw(),
        ),
    };
    /// Any transfer write. The source stage is ALL_TRANSFER rather than CLEAR or
    /// COPY: Debian's validation layer 1.3.239 reports a false hazard after
    /// `vkCmdFillBuffer` when the source stage is CLEAR.
    pub const TRANSFER_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::ALL_TRANSFER,
        access: vk::AccessFlags2::TRANSFER_WRITE,
    };
    pub const TRANSFER_READ: Access = Access {
        stage: vk::PipelineStageFlags2::ALL_TRANSFER,
        access: vk::AccessFlags2::TRANSFER_READ,
    };
    pub const HOST_READ: Access = Access {
        stage: vk::PipelineStageFlags2::HOST,
        access: vk::AccessFlags2::HOST_READ,
    };
}

/// The one mip level and layer of a colour image.
pub const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// One global memory barrier: everything `src` wrote is visible to `dst`.
pub fn barrier(device: &ash::Device, cmd: vk::CommandBuffer, src: Access, dst: Access) {
    let barriers = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.stage)
        .src_access_mask(src.access)
        .dst_stage_mask(dst.stage)
        .dst_access_mask(dst.access)];
    let info = vk::DependencyInfo::default().memory_barriers(&barriers);
    unsafe { device.cmd_pipeline_barrier2(cmd, &info) };
}

/// The barrier between two dependent compute dispatches.
pub fn compute_to_compute(device: &ash::Device, cmd: vk::CommandBuffer) {
    barrier(device, cmd, Access::COMPUTE_WRITE, Access::COMPUTE_READ_WRITE);
}

/// An image layout transition with its memory dependency.
pub fn image_barrier(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    src: Access,
    dst: Access,
) {
    let barriers = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src.stage)
        .src_access_mask(src.access)
        .dst_stage_mask(dst.stage)
        .dst_access_mask(dst.access)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(COLOR_RANGE)];
    let info = vk::DependencyInfo::default().image_memory_barriers(&barriers);
    unsafe { device.cmd_pipeline_barrier2(cmd, &info) };
}

/// Workgroup counts covering `threads` invocations with `local` threads per
/// group along each axis, checked against `maxComputeWorkGroupCount`.
pub fn groups_for(info: &DeviceInfo, what: &str, threads: [u32; 3], local: [u32; 3]) -> Result<[u32; 3]> {
    let mut groups = [0; 3];
    if local.contains(&0) {
        return Err(crate::error::Error::invalid(
            "workgroup size",
            format!("{local:?}"),
            format!("{what}: every axis needs at least one invocation"),
        ));
    }
    for a in 0..3 {
        groups[a] = threads[a].div_ceil(local[a]);
        let limit = [
            "maxComputeWorkGroupCount[0]",
            "maxComputeWorkGroupCount[1]",
            "maxComputeWorkGroupCount[2]",
        ][a];
        info.check(
            format!("{what}: {} workgroups", groups[a]),
            limit,
            groups[a] as u64,
            info.max_compute_work_group_count[a] as u64,
        )?;
    }
    Ok(groups)
}

/// A 2-D grid of groups for a 1-D problem of `count` items in groups of
/// `local`, for counts beyond `maxComputeWorkGroupCount[0]`. Returns the
/// group counts; the kernel reconstructs `group = y * groups[0] + x`.
pub fn groups_linear(info: &DeviceInfo, what: &str, count: u64, local: u32) -> Result<[u32; 3]> {
    let total = count.div_ceil(local as u64).max(1);
    let max_x = info.max_compute_work_group_count[0] as u64;
    let x = total.min(max_x);
    let y = total.div_ceil(x);
    info.check(
        format!("{what}: {count} items"),
        "maxComputeWorkGroupCount[1]",
        y,
        info.max_compute_work_group_count[1] as u64,
    )?;
    Ok([x as u32, y as u32, 1])
}
