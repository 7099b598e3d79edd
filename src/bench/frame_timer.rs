//! Frames rendered into one target, the march pass of each timed.

use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::{Context, Timer};
use crate::render::{FrameDesc, Output, RenderTarget, Renderer, Scene};

/// Renders frames into one target, timing the march pass of each.
pub struct FrameTimer<'a> {
    ctx: &'a Context,
    renderer: &'a Renderer,
    target: RenderTarget,
    timer: Timer,
}

impl<'a> FrameTimer<'a> {
    pub fn new(ctx: &'a Context, renderer: &'a Renderer, width: u32, height: u32) -> Result<Self> {
        Ok(FrameTimer {
            ctx,
            renderer,
            target: RenderTarget::new(ctx, width, height)?,
            timer: Timer::new(ctx, 2)?,
        })
    }

    /// One frame: GPU ms of the march pass, and the frame when `read`.
    pub fn frame(&mut self, scene: Scene, desc: &FrameDesc, read: bool) -> Result<(f64, Option<Frame>)> {
        let (renderer, target, timer) = (self.renderer, &self.target, &mut self.timer);
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            renderer.record(cmd, Some(timer), target, scene, desc, Output::Buffer)?;
            if read {
                renderer.record_readback(cmd, target)?;
            }
            Ok(())
        })?;
        self.renderer.check_whole(&self.target, scene.structure)?;
        let ms = self.timer.results()?.phase("march")?;
        let frame = if read { Some(self.target.read()?) } else { None };
        Ok((ms, frame))
    }
}
