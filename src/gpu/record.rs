//! Recording: the command buffer lacuna's `record_*` calls record into
//! (`Recording`), its synchronization2 barriers between dependent passes,
//! and dispatch sizing that respects `maxComputeWorkGroupCount`.
//!
//! Dependent compute passes are separated by one global memory barrier
//! (`barrier(.., Access::COMPUTE_WRITE, Access::COMPUTE_READ_WRITE)`); buffer-
//! or image-range barriers buy nothing on current drivers.

use super::{Context, DeviceInfo};
use crate::error::Result;
use ash::vk;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

/// A command buffer in the recording state on a lacuna `Context`'s device:
/// what every `record_*` call records into. lacuna's own submissions
/// (`Context::submit_and_wait`) hand one to their closure; a host adopts its
/// own command buffer with [`Recording::adopt`], whose contract is what
/// makes the recording calls safe to call.
///
/// It cannot leave the thread that made it (command buffers are externally
/// synchronized), nor the closure that was given it. Recording in the
/// closure compiles:
///
/// ```no_run
/// fn record(ctx: &lacuna::gpu::Context) -> lacuna::Result<()> {
///     ctx.submit_and_wait(|cmd| {
///         cmd.compute_to_compute();
///         Ok(())
///     })
/// }
/// ```
///
/// keeping the recording past the submission does not:
///
/// ```compile_fail
/// fn record(ctx: &lacuna::gpu::Context) -> lacuna::Result<()> {
///     let mut kept = None;
///     ctx.submit_and_wait(|cmd| {
///         kept = Some(cmd);
///         Ok(())
///     })?;
///     kept.map(|cmd| cmd.compute_to_compute());
///     Ok(())
/// }
/// ```
///
/// and neither does recording from another thread:
///
/// ```compile_fail
/// fn record(ctx: &lacuna::gpu::Context) -> lacuna::Result<()> {
///     ctx.submit_and_wait(|cmd| {
///         std::thread::scope(|s| {
///             s.spawn(move || cmd.compute_to_compute());
///         });
///         Ok(())
///     })
/// }
/// ```
#[derive(Clone, Copy)]
pub struct Recording<'r> {
    ctx: &'r Context,
    raw: vk::CommandBuffer,
    /// Where lacuna's own submission is (None: a host's command buffer).
    done: Option<&'r Completion>,
    _one_thread: PhantomData<*const ()>,
}

impl<'r> Recording<'r> {
    /// Records lacuna's commands into the host's command buffer `raw`.
    ///
    /// # Safety
    /// - `raw` is a primary or secondary command buffer allocated on `ctx`'s
    ///   device, not protected, in the recording state and outside any
    ///   render pass instance while the `Recording` (or a copy) is used, and
    ///   nothing else records into it meanwhile.
    /// - It is submitted, if at all, to a queue of the family `ctx` was
    ///   adopted with, and never after a lacuna call recording into it
    ///   returned an error: reset or free it then (a call that fails may
    ///   have recorded uses of what it made and dropped).
    /// - Until its execution has completed (or it was reset or freed without
    ///   being submitted): every lacuna object passed to a call recording
    ///   through it, and every object such a call returned (volumes,
    ///   transfer functions, ranges, structures, targets, the renderer and
    ///   builder that recorded, timers, and each `Staging`), stays alive; none
    ///   is changed by another lacuna call (`GpuVolume::replace`,
    ///   `Builder::put`, `Buffer::upload`, say); and no result is read on the
    ///   host (`RenderTarget::read`, `cut_groups`, `Timer::results`,
    ///   `Buffer::download` or `host`, a tree's `stats`).
    /// - Every raw handle given with it (`HostImage`, `HostDepth`,
    ///   `HostDepthOut`, `Binding`'s raw variants) is a live object of
    ///   `ctx`'s device, in the usage, format, extent and layout its type
    ///   states, until then too.
    pub unsafe fn adopt(ctx: &'r Context, raw: vk::CommandBuffer) -> Self {
        Recording {
            ctx,
            raw,
            done: None,
            _one_thread: PhantomData,
        }
    }

    /// A command buffer lacuna allocated and begun, submits and waits for;
    /// `done` follows it.
    pub(super) fn own(ctx: &'r Context, raw: vk::CommandBuffer, done: &'r Completion) -> Self {
        Recording {
            ctx,
            raw,
            done: Some(done),
            _one_thread: PhantomData,
        }
    }

    /// For lacuna's own submissions, where this one is (None: a host's
    /// command buffer, whose completion is the host's to know).
    pub(crate) fn completion(self) -> Option<Completion> {
        self.done.cloned()
    }

    /// The command buffer, for the host's own `vkCmd*` calls.
    pub fn raw(self) -> vk::CommandBuffer {
        self.raw
    }

    /// The context whose device the command buffer belongs to.
    pub fn context(self) -> &'r Context {
        self.ctx
    }

    /// One global memory barrier: everything `src` wrote is visible to `dst`.
    pub fn barrier(self, src: Access, dst: Access) {
        let barriers = [vk::MemoryBarrier2::default()
            .src_stage_mask(src.stage)
            .src_access_mask(src.access)
            .dst_stage_mask(dst.stage)
            .dst_access_mask(dst.access)];
        let info = vk::DependencyInfo::default().memory_barriers(&barriers);
        // SAFETY: `raw` is recording on this device (`adopt`'s contract, or lacuna's own).
        unsafe { self.ctx.device().cmd_pipeline_barrier2(self.raw, &info) };
    }

    /// The barrier between two dependent compute dispatches.
    pub fn compute_to_compute(self) {
        self.barrier(Access::COMPUTE_WRITE, Access::COMPUTE_READ_WRITE);
    }

    /// An image layout transition with its memory dependency.
    ///
    /// # Safety
    /// `image` is a live colour image of this device with one mip level and
    /// layer, in layout `old` when the barrier executes; `new` is a layout
    /// its usage allows (not UNDEFINED or PREINITIALIZED).
    pub unsafe fn image_barrier(
        self,
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
        // SAFETY: as `barrier`; the caller vouches for the image.
        unsafe { self.ctx.device().cmd_pipeline_barrier2(self.raw, &info) };
    }
}

/// Where one of lacuna's own submissions is: recording, running,
/// completed, or abandoned (its closure failed, or the submit did, so its
/// commands never run). What its recordings wrote is read on the host only
/// once it completed (`Timer::results`) or settled (`Buffer::host`).
#[derive(Clone)]
pub(crate) struct Completion(Arc<AtomicU8>);

impl Completion {
    const RECORDING: u8 = 0;
    const RUNNING: u8 = 1;
    const COMPLETED: u8 = 2;
    const ABANDONED: u8 = 3;

    pub(super) fn recording() -> Self {
        Completion(Arc::new(AtomicU8::new(Self::RECORDING)))
    }

    pub(super) fn running(&self) {
        self.0.store(Self::RUNNING, Ordering::Release);
    }

    /// After the wait: everything its commands wrote is the host's to read.
    pub(super) fn completed(&self) {
        self.0.store(Self::COMPLETED, Ordering::Release);
    }

    /// Where it was never submitted (a recording that is not running
    /// stays so when its closure unwinds).
    pub(super) fn abandon(&self) {
        let _ = self
            .0
            .compare_exchange(Self::RECORDING, Self::ABANDONED, Ordering::AcqRel, Ordering::Acquire);
    }

    /// Whether it ran to completion.
    pub(crate) fn has_completed(&self) -> bool {
        self.0.load(Ordering::Acquire) == Self::COMPLETED
    }

    /// Whether its commands can no longer touch memory: completed, or
    /// never submitted.
    pub(crate) fn is_settled(&self) -> bool {
        self.0.load(Ordering::Acquire) >= Self::COMPLETED
    }

    /// Whether both follow one submission.
    pub(crate) fn same(&self, other: &Completion) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// A pipeline stage together with the memory accesses made there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    pub(crate) stage: vk::PipelineStageFlags2,
    pub(crate) access: vk::AccessFlags2,
}

impl Access {
    /// Another pair than the constants below.
    ///
    /// # Safety
    /// `access` is made at `stage` (Vulkan's table of supported accesses),
    /// and both are of features the device was created with.
    pub const unsafe fn new(stage: vk::PipelineStageFlags2, access: vk::AccessFlags2) -> Self {
        Access { stage, access }
    }

    /// Its pipeline stages.
    pub fn stage(&self) -> vk::PipelineStageFlags2 {
        self.stage
    }

    /// Its memory accesses.
    pub fn access(&self) -> vk::AccessFlags2 {
        self.access
    }

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
    /// Every write of every command before.
    pub const ALL_WRITES: Access = Access {
        stage: vk::PipelineStageFlags2::ALL_COMMANDS,
        access: vk::AccessFlags2::MEMORY_WRITE,
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
