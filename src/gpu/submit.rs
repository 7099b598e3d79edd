//! lacuna's own submissions (`Context::submit_and_wait`, `submit_while`):
//! one command buffer recorded by a closure, submitted and waited for, with
//! the state its recordings' host accesses follow (`Completion`).

use super::record::{Access, Completion, Recording};
use super::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use std::sync::Arc;

impl Context {
    /// Records commands with `record`, submits them and waits for completion.
    /// Objects dropped meanwhile, in the closure or on another thread, are
    /// destroyed after the wait, so what the commands use cannot go before
    /// they ran.
    ///
    /// Submissions on one context run on the device one after another, in
    /// the order they were submitted (not recorded), except beside a
    /// `submit_while`'s commands, which run alongside what is submitted
    /// during its `meanwhile`. Their closures may record at the same time
    /// on several threads (each submission records with a command pool of
    /// its own), so a closure may wait for another thread that submits. A
    /// submission on the same context from inside the closure, on the same
    /// thread, is an error: it would run before the commands being
    /// recorded. A wait that fails (a lost device) leaks the submission's
    /// command buffer and every object dropped while it was open.
    pub fn submit_and_wait<T>(&self, record: impl FnOnce(Recording<'_>) -> Result<T>) -> Result<T> {
        let (value, _) = self.submit_inner(record, || Ok(()), false)?;
        Ok(value)
    }

    /// As `submit_and_wait`, running `meanwhile` on the host between the
    /// submission and the wait: host work that needs nothing the commands
    /// write overlaps the device's (on a CPU device, its queue thread's).
    /// `meanwhile` may submit work of its own. The wait comes even when
    /// `meanwhile` fails or panics (its error is returned, its panic
    /// resumed, after it), so nothing the commands read is dropped while
    /// they run.
    pub fn submit_while<T, U>(
        &self,
        record: impl FnOnce(Recording<'_>) -> Result<T>,
        meanwhile: impl FnOnce() -> Result<U>,
    ) -> Result<(T, U)> {
        match self.submit_inner(record, meanwhile, true)? {
            (value, Ok(host)) => Ok((value, host?)),
            (_, Err(panic)) => std::panic::resume_unwind(panic),
        }
    }

    /// The submission of `submit_and_wait` and `submit_while`: `meanwhile`
    /// runs (its panic caught) between the submission and the wait, with
    /// the device order released where `unlock` (it may then submit).
    fn submit_inner<T, U>(
        &self,
        record: impl FnOnce(Recording<'_>) -> Result<T>,
        meanwhile: impl FnOnce() -> Result<U>,
        unlock: bool,
    ) -> Result<(T, std::thread::Result<Result<U>>)> {
        let device = self.device();
        let me = Arc::as_ptr(&self.inner) as usize;
        if RECORDING.with(|r| r.borrow().contains(&me)) {
            return Err(Error::invalid(
                "submission",
                "inside another's recording closure",
                "record into the command buffer the closure was given (the record_* forms): a submission from there would run before the commands being recorded",
            ));
        }
        // Open before anything is recorded, until after the wait.
        let _open = self.open_submission();
        let lease = CommandLease::new(self)?;
        let cmd = lease.cmd;
        let done = Completion::recording();
        // A closure that fails or unwinds leaves it abandoned: never run.
        let _abandoned = Abandon(&done);
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe { device.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        let value = {
            let _recording = SubmitGuard::on(me);
            record(Recording::own(self, cmd, &done))
        };
        if value.is_ok() {
            // A fence wait alone makes no device write visible to the
            // host: after it, whatever the commands wrote is readable.
            Recording::own(self, cmd, &done).barrier(Access::ALL_WRITES, Access::HOST_READ);
        }
        unsafe { device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
        let value = value?;
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        let mut order = Some(self.inner.order.take());
        let submitted = {
            let queue = self.inner.queue.lock().unwrap_or_else(|p| p.into_inner());
            self.inner
                .submissions
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            unsafe { device.queue_submit2(*queue, &submit, fence) }.vk("vkQueueSubmit2")
        };
        if let Err(e) = submitted {
            unsafe { device.destroy_fence(fence, None) };
            return Err(e);
        }
        done.running();
        if unlock {
            // `meanwhile` may submit its own commands, which then run
            // beside these.
            order.take();
        }
        let host = std::panic::catch_unwind(std::panic::AssertUnwindSafe(meanwhile));
        let waited = unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences");
        if let Err(e) = waited {
            // The commands may still run (a lost device, or out of memory):
            // leak their command buffer, and keep the submission open so
            // nothing dropped since is destroyed under them.
            std::mem::forget(lease);
            std::mem::forget(_open);
            return Err(e);
        }
        unsafe { device.destroy_fence(fence, None) };
        done.completed();
        Ok((value, host))
    }
}

/// One primary command buffer in a command pool no other submission
/// records with; dropping it frees the buffer and leaves the pool idle.
struct CommandLease<'a> {
    ctx: &'a Context,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
}

impl<'a> CommandLease<'a> {
    fn new(ctx: &'a Context) -> Result<Self> {
        let device = ctx.device();
        let idle = ctx.inner.command_pools.lock().unwrap_or_else(|p| p.into_inner()).pop();
        let pool = match idle {
            Some(pool) => pool,
            None => {
                let info = vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.inner.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
                unsafe { device.create_command_pool(&info, None) }.vk("vkCreateCommandPool")?
            }
        };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        match unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers") {
            Ok(cmds) => Ok(CommandLease {
                ctx,
                pool,
                cmd: cmds[0],
            }),
            Err(e) => {
                ctx.inner
                    .command_pools
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .push(pool);
                Err(e)
            }
        }
    }
}

/// Idle command pools a context keeps; more are destroyed when returned
/// (a burst of concurrent submissions does not hold their memory).
const IDLE_POOLS: usize = 4;

impl Drop for CommandLease<'_> {
    fn drop(&mut self) {
        // After the wait, or never submitted.
        let device = self.ctx.device();
        unsafe { device.free_command_buffers(self.pool, &[self.cmd]) };
        let mut idle = self.ctx.inner.command_pools.lock().unwrap_or_else(|p| p.into_inner());
        match idle.len() < IDLE_POOLS {
            true => idle.push(self.pool),
            false => unsafe { device.destroy_command_pool(self.pool, None) },
        }
    }
}

/// Abandons a submission still recording when dropped.
struct Abandon<'a>(&'a Completion);

impl Drop for Abandon<'_> {
    fn drop(&mut self) {
        self.0.abandon();
    }
}

thread_local! {
    /// The contexts this thread is recording a submission's commands for
    /// (`submit_inner`): a submission on one of them from its closure
    /// would run before the commands being recorded.
    static RECORDING: std::cell::RefCell<Vec<usize>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Marks a context as recording on this thread until dropped (also when
/// the closure panics).
struct SubmitGuard(usize);

impl SubmitGuard {
    fn on(context: usize) -> SubmitGuard {
        RECORDING.with(|r| r.borrow_mut().push(context));
        SubmitGuard(context)
    }
}

impl Drop for SubmitGuard {
    fn drop(&mut self) {
        RECORDING.with(|r| {
            let mut r = r.borrow_mut();
            if let Some(i) = r.iter().rposition(|c| *c == self.0) {
                r.remove(i);
            }
        });
    }
}
