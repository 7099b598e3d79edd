//! GPU timestamps for named passes. Ticks are masked to the queue's
//! `timestampValidBits` and scaled by `timestampPeriod` (ns per tick).

use super::record::{Completion, Recording};
use super::retire::Retired;
use super::timings::Timings;
use super::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;

/// GPU timestamps around named passes of recorded work, read back as
/// `Timings` once the work completed.
pub struct Timer {
    ctx: Context,
    pool: vk::QueryPool,
    capacity: u32,
    /// Each pass: its name, first query and whether it was ended.
    passes: Vec<(String, u32, bool)>,
    open: Option<usize>,
    /// Recordings so far (`reset`): a pass handle of an earlier one closes
    /// nothing.
    recording: u64,
    /// The last `reset` was given another context's command buffer.
    reset_elsewhere: bool,
    /// Set once lacuna's own submission that recorded the last `reset` has
    /// completed (None: a host's command buffer, or no reset yet).
    completed: Option<Completion>,
}

/// Handle of a pass opened with [`Timer::begin`] (its index and recording).
#[derive(Clone, Copy, Debug)]
pub struct Pass(usize, u64);

impl Timer {
    /// A timer for up to `max_passes` passes per recording.
    pub fn new(ctx: &Context, max_passes: u32) -> Result<Self> {
        let capacity = max_passes.clamp(1, u32::MAX / 2) * 2;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        let pool = unsafe { ctx.device().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(Timer {
            ctx: ctx.clone(),
            pool,
            capacity,
            passes: Vec::new(),
            open: None,
            recording: 0,
            reset_elsewhere: false,
            completed: None,
        })
    }

    /// Whether this device's queue writes timestamps at all.
    pub fn supported(&self) -> bool {
        self.ctx.info().timestamp_valid_bits > 0 && self.ctx.info().timestamp_period > 0.0
    }

    /// Resets every query; record before the first pass of a recording.
    /// Into another context's command buffer it records nothing, and the
    /// next `begin` is an error.
    pub fn reset(&mut self, cmd: Recording<'_>) {
        self.passes.clear();
        self.open = None;
        self.recording += 1;
        self.reset_elsewhere = !self.ctx.is(cmd.context());
        self.completed = cmd.completion();
        if self.reset_elsewhere {
            return;
        }
        // SAFETY: the pool is this device's, as the command buffer is.
        unsafe {
            self.ctx
                .device()
                .cmd_reset_query_pool(cmd.raw(), self.pool, 0, self.capacity)
        };
    }

    fn write(&self, cmd: Recording<'_>, query: u32) {
        // ALL_COMMANDS: the timestamp waits for all earlier work, so a pass
        // measures its own commands, not the tail of the one before.
        unsafe {
            self.ctx
                .device()
                .cmd_write_timestamp2(cmd.raw(), vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, query)
        };
    }

    /// Opens pass `name`; passes do not nest (opening one while another is
    /// open is an error). On a queue without timestamps nothing is
    /// written, and `results` is empty.
    pub fn begin(&mut self, cmd: Recording<'_>, name: &str) -> Result<Pass> {
        self.ctx.check_is(cmd.context(), "timer's command buffer")?;
        if self.reset_elsewhere {
            return Err(Error::invalid(
                "timer pass",
                name,
                "the timer's last reset went to another lacuna Context's command buffer",
            ));
        }
        if let Some(open) = self.open {
            return Err(Error::invalid(
                "timer pass",
                name,
                format!(
                    "opened while pass '{}' is open: passes do not nest",
                    self.passes[open].0
                ),
            ));
        }
        let first = self.passes.len() as u32 * 2;
        if first + 2 > self.capacity {
            return Err(Error::invalid(
                "timer pass",
                name,
                format!("more than {} passes in one recording", self.capacity / 2),
            ));
        }
        if self.supported() {
            self.write(cmd, first);
        }
        self.passes.push((name.to_string(), first, false));
        self.open = Some(self.passes.len() - 1);
        Ok(Pass(self.passes.len() - 1, self.recording))
    }

    /// Closes `pass`, the open one; any other pass (an earlier recording's,
    /// or one already closed), or a command buffer of another context,
    /// leaves it as it is, and `results` names a pass that was never closed.
    pub fn end(&mut self, cmd: Recording<'_>, pass: Pass) {
        if self.open != Some(pass.0) || pass.1 != self.recording || !self.ctx.is(cmd.context()) {
            return;
        }
        if self.supported() {
            self.write(cmd, self.passes[pass.0].1 + 1);
        }
        self.passes[pass.0].2 = true;
        self.open = None;
    }

    /// Reads the passes recorded since the last reset; call after the
    /// submission completed. Empty when the queue has no timestamps.
    pub fn results(&self) -> Result<Timings> {
        let mut timings = Timings::default();
        if self.passes.is_empty() || !self.supported() {
            return Ok(timings);
        }
        // Queries of a submission not yet run (or never submitted: its
        // closure failed) hold nothing to read.
        if self.completed.as_ref().is_some_and(|d| !d.has_completed()) {
            return Err(Error::invalid(
                "timer results",
                "before the submission that recorded them completed",
                "read them after submit_and_wait returned Ok",
            ));
        }
        // Its end query was never written: waiting for it would not return.
        if let Some((name, ..)) = self.passes.iter().find(|p| !p.2) {
            return Err(Error::invalid("timer pass", name, "was opened and never closed"));
        }
        let n = self.passes.len() as u32 * 2;
        let mut ticks = vec![0u64; n as usize];
        unsafe {
            self.ctx.device().get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let info = self.ctx.info();
        let mask = if info.timestamp_valid_bits >= 64 {
            u64::MAX
        } else {
            (1u64 << info.timestamp_valid_bits) - 1
        };
        for (name, first, _) in &self.passes {
            let start = ticks[*first as usize] & mask;
            let end = ticks[*first as usize + 1] & mask;
            // Wraps around once at most within a pass.
            let delta = end.wrapping_sub(start) & mask;
            timings.push(name.clone(), delta as f64 * info.timestamp_period as f64 / 1e6);
        }
        Ok(timings)
    }
}

impl Drop for Timer {
    fn drop(&mut self) {
        self.ctx.retire([Retired::QueryPool(self.pool)]);
    }
}

/// The one timer convention of every `record_*` function: an optional
/// `&mut Timer` (None: untimed). Passes open and close through this so the
/// recording code reads the same either way.
pub trait OptionalTimer {
    /// Opens pass `name` when there is a timer.
    fn begin(&mut self, cmd: Recording<'_>, name: &str) -> Result<Option<Pass>>;
    /// Closes a pass opened by `begin`.
    fn end(&mut self, cmd: Recording<'_>, pass: Option<Pass>);
}

impl OptionalTimer for Option<&mut Timer> {
    fn begin(&mut self, cmd: Recording<'_>, name: &str) -> Result<Option<Pass>> {
        match self {
            Some(t) => t.begin(cmd, name).map(Some),
            None => Ok(None),
        }
    }

    fn end(&mut self, cmd: Recording<'_>, pass: Option<Pass>) {
        if let (Some(t), Some(p)) = (self, pass) {
            t.end(cmd, p);
        }
    }
}
