//! The viewer's one use of lacuna's renderer: the volume on the GPU, the
//! transfer function, the structure (rebuilt only when the TF, the mode,
//! the structure or the time step changes, before the next frame, for that
//! frame: auto prices its candidates on it, and a new time step keeps
//! auto's choice while its active share holds, `Builder::build_step`), and
//! a frame recorded into the host's command buffer and copied into the
//! host's canvas image. Everything else in the viewer is the host.

use super::host::Canvas;
use lacuna::accel::auto::{self, Choice};
use lacuna::accel::{Accel, BuildInput, Builder, Params, Ranges, Structure};
use lacuna::frame::Frame;
use lacuna::gpu::record::Access;
use lacuna::gpu::Recording;
use lacuna::gpu::{vk, Context, Timer};
use lacuna::render::{Filter, FrameDesc, Mode, Output, RenderTarget, Renderer};
use lacuna::tf::GpuTransferFunction;
use lacuna::volume::{GpuVolume, Storage};
use lacuna::{Error, Result, Timings, TransferFunction, Volume};

pub struct Scene {
    ctx: Context,
    renderer: Renderer,
    builder: Builder,
    pub volume: Volume,
    /// None only after a new step failed to upload (the viewer stops then).
    gpu_volume: Option<GpuVolume>,
    pub tf: TransferFunction,
    lut: GpuTransferFunction,
    pub accel: Accel,
    params: Params,
    /// The frames' mode the structure is built for.
    pub mode: Mode,
    /// The per-volume ranges the structure reads, and for which structure.
    ranges: Option<((Accel, Params), Ranges)>,
    pub structure: Structure,
    /// auto's choice on the last time step, for the next one to keep
    /// (None after a TF, mode or structure change: those price anew).
    step_choice: Option<Choice>,
    /// The structure is to be built before the next frame.
    stale: bool,
    target: Option<RenderTarget>,
    timer: Timer,
    /// The last build's phases (empty for naive) and frame's passes.
    build: Timings,
    march: Timings,
    /// SIMD groups of the last frame the device's loop cap cut short
    /// (`RenderTarget::cut_groups`): that frame is not the exact one.
    pub cut_groups: u32,
    /// The sample filter asked for (None: the default), for new steps.
    filter: Option<Filter>,
    /// The voxel storage asked for, for new steps.
    storage: Storage,
    /// The last new time step's upload (with what its frames read), ms.
    upload_ms: f64,
}

/// What a scene whose last time step failed to upload answers.
fn no_step() -> Error {
    Error::Device("the last time step failed to upload".into())
}

impl Scene {
    /// `filter`: the sample filter asked for (None: the default);
    /// `storage`: the voxel storage.
    pub fn new(
        builder: Builder,
        volume: Volume,
        tf: TransferFunction,
        accel: Accel,
        mode: Mode,
        (filter, storage): (Option<Filter>, Storage),
    ) -> Result<Scene> {
        let ctx = &builder.context().clone();
        // A series' first step: the next ones start from its work.
        let gpu_volume = GpuVolume::upload_step(ctx, None, &volume, storage, false, filter)?;
        let lut = tf.upload(ctx)?;
        let mut scene = Scene {
            ctx: ctx.clone(),
            renderer: Renderer::new(builder.context())?,
            builder,
            volume,
            gpu_volume: Some(gpu_volume),
            tf,
            lut,
            accel,
            params: accel.defaults(),
            mode,
            ranges: None,
            structure: Structure::naive(),
            step_choice: None,
            stale: true,
            target: None,
            timer: Timer::new(ctx, 1)?,
            build: Timings::default(),
            march: Timings::default(),
            cut_groups: 0,
            filter,
            storage,
            upload_ms: 0.0,
        };
        scene.set_accel(accel);
        Ok(scene)
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// The sample filter `render` would use for this volume.
    pub fn default_filter(&self) -> Result<Filter> {
        Ok(self.gpu_volume()?.default_filter())
    }

    fn gpu_volume(&self) -> Result<&GpuVolume> {
        self.gpu_volume.as_ref().ok_or_else(no_step)
    }

    /// A new transfer function: upload it; the structure is rebuilt for it.
    pub fn set_tf(&mut self, tf: TransferFunction) -> Result<()> {
        self.lut = tf.upload(&self.ctx)?;
        self.tf = tf;
        self.stale = true;
        self.step_choice = None;
        Ok(())
    }

    /// A new time step on the same grid: upload it (with its gradient when
    /// frames are lit) in place of the last, into the last one's memory
    /// where it fits (`GpuVolume::upload_step`; every frame has completed
    /// here); its ranges and structure are computed before the next frame.
    /// The last step's ranges and structure are freed first, and where the
    /// step does not fit (bricked storage: the large volumes) the last
    /// step's memory too, so two steps never coexist on the device.
    pub fn set_volume(&mut self, volume: Volume, lit: bool) -> Result<()> {
        let t = std::time::Instant::now();
        // A frame the loop cap cut prices anew: auto leaves cut candidates out.
        let whole = self.cut_groups == 0;
        if let Some(choice) = auto::choice_of(&self.structure).filter(|_| !self.stale && whole) {
            self.step_choice = Some(choice.clone());
        }
        self.ranges = None;
        self.structure = Structure::naive();
        self.stale = true;
        let last = self.gpu_volume.take();
        // Only what changed since this step is written (`GpuVolume::replace`).
        let last = last.map(|gv| (gv, Some(&self.volume)));
        let step = GpuVolume::upload_step(&self.ctx, last, &volume, self.storage, lit, self.filter)?;
        self.gpu_volume = Some(step);
        self.upload_ms = t.elapsed().as_secs_f64() * 1000.0;
        // The step before's voxels freed on another thread: unmapping them
        // (16 MB for nbody:256, up to 4 ms) is no part of the next frame.
        let before = std::mem::replace(&mut self.volume, volume);
        // Where no thread can be made, freed here (the closure is dropped).
        let _ = std::thread::Builder::new().spawn(move || drop(before));
        Ok(())
    }

    /// The last new step's upload time, ms (0 before any).
    pub fn upload_ms(&self) -> f64 {
        self.upload_ms
    }

    /// Uploads the volume's gradient, once, before the first lit frame.
    pub fn ensure_gradient(&mut self) -> Result<()> {
        let gpu_volume = self.gpu_volume.as_mut().ok_or_else(no_step)?;
        gpu_volume.add_gradient(&self.volume)
    }

    /// Frames of a new mode: the structure is built for it.
    pub fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
        self.stale = true;
        self.step_choice = None;
    }

    /// A new structure, with `render`'s defaults for its parameters.
    pub fn set_accel(&mut self, accel: Accel) {
        self.accel = accel;
        self.params = accel.defaults();
        self.stale = true;
        self.step_choice = None;
    }

    /// Builds the structure, if a change asked for it, for frames like
    /// `desc`; ranges only when the structure or the step changed (they are
    /// per volume). A new step's build keeps auto's last choice where it
    /// may (`Builder::build_step`). An octant map holds the ray directions
    /// of the frames since: a frame with others adds them (a rebuild, which
    /// auto prices anew) rather than walking them cell by cell.
    pub fn prepare(&mut self, desc: &FrameDesc) -> Result<()> {
        let need = desc.octants(self.volume.dims, self.volume.spacing)?;
        let held = self.structure.octants();
        let octants = match self.stale {
            true => need,
            false if held.contains(need) => return Ok(()),
            false => need.union(held),
        };
        self.stale = false;
        self.build = Timings::default();
        if self.accel.is_naive() {
            self.structure = Structure::naive();
            return Ok(());
        }
        let which = (self.accel, self.params.clone());
        let input = BuildInput {
            volume: &self.volume,
            gpu_volume: self.gpu_volume.as_ref().ok_or_else(no_step)?,
            tf: &self.tf,
            gpu_tf: &self.lut,
            mode: self.mode,
            frames: std::slice::from_ref(desc),
            octants,
        };
        match &self.ranges {
            Some((w, ranges)) if *w == which => {
                let (structure, build) = self.builder.build(self.accel, &input, ranges, &self.params)?;
                self.structure = structure;
                self.build = build;
            }
            _ => {
                let step =
                    self.builder
                        .build_step(self.accel, &self.params, self.step_choice.take().as_ref(), &input)?;
                self.structure = step.structure;
                self.build = step.build_timings;
                self.ranges = step.ranges.map(|r| (which, r));
            }
        }
        Ok(())
    }

    /// Records one frame into the host's `cmd`: lacuna's march (timed),
    /// then the frame buffer copied into `canvas`, left in
    /// TRANSFER_SRC_OPTIMAL and visible to transfer reads; with `readback`,
    /// also the copy to host memory that `frame` reads.
    pub fn record(&mut self, cmd: Recording<'_>, canvas: &Canvas, desc: &FrameDesc, readback: bool) -> Result<()> {
        let (w, h) = (canvas.extent.width, canvas.extent.height);
        if self.target.as_ref().map(|t| (t.width(), t.height())) != Some((w, h)) {
            self.target = Some(RenderTarget::new(&self.ctx, w, h)?);
        }
        let Some(target) = &self.target else {
            unreachable!("target was just made")
        };
        self.timer.reset(cmd);
        let scene = lacuna::render::Scene {
            structure: &self.structure,
            volume: self.gpu_volume.as_ref().ok_or_else(no_step)?,
            tf: &self.lut,
        };
        self.renderer
            .record(cmd, Some(&mut self.timer), target, scene, desc, Output::Buffer)?;
        let device = self.ctx.device();
        let frame_buffer = target
            .frame()
            .ok_or_else(|| Error::Unsupported("the viewer's render target has no frame buffer".into()))?
            .raw();
        let (undefined, dst, src) = (
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        );
        // SAFETY: the canvas is the host's colour image on this device, alive
        // until the frame has been waited for (`Host::frame`), in `old`.
        let canvas_to = |old, new, from, to| unsafe { cmd.image_barrier(canvas.image, old, new, from, to) };
        // The previous frame's blit read the canvas; the whole frame is
        // written, so its old contents are discarded.
        canvas_to(undefined, dst, Access::TRANSFER_READ, Access::TRANSFER_WRITE);
        cmd.barrier(Access::COMPUTE_WRITE, Access::TRANSFER_READ);
        let region = [vk::BufferImageCopy {
            buffer_offset: 0,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            },
            image_offset: vk::Offset3D::default(),
            image_extent: vk::Extent3D {
                width: w,
                height: h,
                depth: 1,
            },
        }];
        unsafe {
            device.cmd_copy_buffer_to_image(
                cmd.raw(),
                frame_buffer,
                canvas.image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &region,
            )
        };
        canvas_to(dst, src, Access::TRANSFER_WRITE, Access::TRANSFER_READ);
        if readback {
            self.renderer.record_readback(cmd, target)?;
        }
        Ok(())
    }

    /// The last build's time, ms (0 for naive).
    pub fn rebuild_ms(&self) -> f64 {
        self.build.total()
    }

    /// The last frame's march time, ms.
    pub fn march_ms(&self) -> f64 {
        self.march.get("march").unwrap_or(0.0)
    }

    /// After the recorded frame completed: its GPU pass times.
    pub fn finish(&mut self) -> Result<()> {
        self.march = self.timer.results()?;
        self.cut_groups = match &self.target {
            Some(target) => target.cut_groups()?,
            None => 0,
        };
        Ok(())
    }

    /// The last frame as an error where the device's loop cap may have cut
    /// it short (`Renderer::check_whole`).
    pub fn check_whole(&self) -> Result<()> {
        match &self.target {
            Some(target) => self.renderer.check_whole(target, &self.structure),
            None => Ok(()),
        }
    }

    /// The frame a `record` with `readback` produced, as the renderer wrote it.
    pub fn frame(&self) -> Result<Option<Frame>> {
        self.target.as_ref().map(RenderTarget::read).transpose()
    }

    /// The frame's metadata, as `render` writes it, with this scene's state.
    pub fn describe(&self, frame: &mut Frame, desc: &FrameDesc, time: Option<u32>) -> Result<()> {
        let scene = lacuna::render::Scene {
            structure: &self.structure,
            volume: self.gpu_volume()?,
            tf: &self.lut,
        };
        let march = Some(self.march.phase("march")?);
        let source = lacuna::render::metadata::Source {
            volume: &self.volume,
            time,
            tf: &self.tf,
        };
        lacuna::render::metadata::describe(frame, source, scene, desc, self.ctx.info(), march)
    }
}
