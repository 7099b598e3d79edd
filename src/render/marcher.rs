//! Marcher dispatch: one kernel per traversal style (and output format), and
//! the `record` function that only records into a caller's command buffer.

use super::target::{Output, RenderTarget};
use crate::accel::kernels::{MarchKernels, ProbeConstants};
use crate::accel::{March, Structure};
use crate::desc::FrameDesc;
use crate::error::{Error, Result, VkContext};
use crate::frame::Frame;
use crate::gpu::record::Access;
use crate::gpu::shaders::{self, build_opacity_lut, render_depth_limit, MarchCommon};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Bound, Context, Kernel, OptionalTimer, TexelBuffer, Timer, Timings};
use crate::tf::GpuTransferFunction;
use crate::volume::GpuVolume;

use std::sync::Arc;

/// What a frame shows: the structure (built for `tf`), the volume and the
/// transfer function on the GPU.
#[derive(Clone, Copy)]
pub struct Scene<'a> {
    pub structure: &'a Structure,
    pub volume: &'a GpuVolume,
    pub tf: &'a GpuTransferFunction,
}

/// The march kernels, created once per context and filter when a structure
/// first needs them (each structure names its kernel: `Method::march`), and
/// the kernels that write each frame's LUT and depth limits.
pub struct Renderer {
    ctx: Context,
    kernels: MarchKernels,
    opacity: Kernel,
    depth_limit: Kernel,
    /// Reads host depth images (texelFetch: its filter is irrelevant).
    depth_sampler: vk::Sampler,
    /// Bound as the cells copy of a volume without one (nothing reads it).
    no_cells: TexelBuffer,
}

/// Pixel rows `[first_row, first_row + rows)` of a frame, one submission's
/// share of it (`Renderer::bands`, `Renderer::record_band`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Band {
    pub first_row: u32,
    pub rows: u32,
}

/// What the march writes: the kernel's output variant (None: the frame
/// buffer), the resource, and the workgroup rows `[first, count]` (None: all).
struct Destination<'a> {
    variant: Option<&'static str>,
    output: Binding<'a>,
    /// Where depth goes, and whether it is written (iso frames and a
    /// segment's MIP/MinIP ray values to the target's buffer, every frame
    /// to a host's).
    depth: Binding<'a>,
    write_depth: bool,
    rows: Option<[u32; 2]>,
}

impl Renderer {
    /// A renderer. Its kernels come from the context, which creates each
    /// once: a second renderer on it compiles nothing it made before.
    pub fn new(ctx: &Context) -> Result<Self> {
        let opacity = Kernel::new::<build_opacity_lut::Push>(ctx, &shaders::BUILD_OPACITY_LUT)?;
        let depth_limit = Kernel::new::<()>(ctx, &shaders::RENDER_DEPTH_LIMIT)?;
        let info = vk::SamplerCreateInfo::default()
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        let depth_sampler = unsafe { ctx.device().create_sampler(&info, None) }.vk("vkCreateSampler")?;
        let no_cells = crate::volume::no_cells(ctx)?;
        Ok(Renderer {
            ctx: ctx.clone(),
            kernels: MarchKernels::new(ctx),
            opacity,
            depth_limit,
            depth_sampler,
            no_cells,
        })
    }

    /// The march kernel `march` sampling `volume` for frames of `desc`,
    /// writing the frame buffer (and its depth where `desc` writes depth);
    /// created on first use.
    pub fn kernel(&self, march: March, desc: &FrameDesc, volume: &GpuVolume) -> Result<Arc<Kernel>> {
        self.output_kernel(march, desc, volume, None, desc.writes_depth())
    }

    /// The march kernel's workgroup size for frames of `desc`, without
    /// creating the kernel (bands are cut by it).
    fn local_size(&self, scene: Scene, desc: &FrameDesc) -> [u32; 3] {
        let constants = frame_constants(desc, scene.volume, desc.writes_depth());
        self.kernels.local_size(scene.structure.march(), constants)
    }

    /// Creates now the kernel that `record` of `scene` and `desc` to an
    /// output like `output` (its kind and host image format) would create
    /// on first use: a host warms a new look before its frame loop, so the
    /// first frame's recording does not stall on a pipeline compile.
    pub fn prepare(&self, scene: Scene, desc: &FrameDesc, output: Output) -> Result<()> {
        let (variant, write_depth) = match output {
            Output::Buffer => (None, desc.writes_depth()),
            Output::Image(image) => (Some(image.variant()?), false),
            Output::ImageAndDepth(image, _) => (Some(image.variant()?), true),
        };
        self.output_kernel(scene.structure.march(), desc, scene.volume, variant, write_depth)?;
        Ok(())
    }

    /// The march kernel writing the output `variant` (None: the frame
    /// buffer), with depth written or not.
    fn output_kernel(
        &self,
        march: March,
        desc: &FrameDesc,
        volume: &GpuVolume,
        variant: Option<&'static str>,
        write_depth: bool,
    ) -> Result<Arc<Kernel>> {
        self.kernels.get(
            march,
            variant,
            frame_constants(desc, volume, write_depth),
            ProbeConstants::PLAIN,
        )
    }

    /// Records one frame of `desc` into `cmd` (timed as "march" when `timer`
    /// is given): the parameter update, the per-pixel ray limits from the
    /// frame's host depth image when it has one, the frame's LUT corrected
    /// for its step, then the march kernel of the structure
    /// (`Structure::marched_as`) writing `output`. Nothing is submitted.
    ///
    /// Before (the caller's barriers): the volume image is in
    /// SHADER_READ_ONLY_OPTIMAL and it, the TF buffer and the structure's
    /// buffers are visible to compute-shader reads (true after the
    /// convenience uploads and `Builder::build`, which wait; after `record_*`
    /// forms, a barrier from `Access::COMPUTE_WRITE` / `TRANSFER_WRITE` to
    /// `Access::COMPUTE_READ`); a host image is in GENERAL with earlier
    /// accesses ordered before COMPUTE_SHADER storage writes; a host depth
    /// image is in its stated layout with its depth-attachment writes made
    /// visible to COMPUTE_SHADER sampled reads (e.g. from
    /// LATE_FRAGMENT_TESTS / DEPTH_STENCIL_ATTACHMENT_WRITE).
    ///
    /// Recorded here: earlier frames on `target` in the same command buffer
    /// (their parameter and LUT reads, the frame's transfer read) are ordered
    /// before this frame's writes.
    ///
    /// After: the frame (buffer or host image) is written in COMPUTE_SHADER
    /// with SHADER_WRITE; the host orders its own use after a barrier from
    /// `Access::COMPUTE_WRITE` (`record_readback` records one for the
    /// buffer). A last barrier makes the target's march status visible to
    /// the host: once the submission completes, `target.cut_groups()` is 0
    /// unless a device that caps a shader's loop passes (lavapipe) may have
    /// cut the march short (`check_whole`); it covers the last frame
    /// recorded on the target. State
    /// left bound: the compute pipeline, pipeline layout, push descriptors
    /// and push constants of the last lacuna kernel; the graphics bind point
    /// is untouched, but the host binds its compute pipeline, descriptor
    /// sets and push constants again (the pushed set 0 disturbs them).
    ///
    /// One dispatch: a frame of many samples is split into submissions of
    /// your own with `bands` and `record_band` (as `render` marches).
    pub fn record(
        &self,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        target: &RenderTarget,
        scene: Scene,
        desc: &FrameDesc,
        output: Output,
    ) -> Result<()> {
        let to = self.destination(target, desc, output)?;
        self.record_frame(cmd, timer, target, scene, desc, to)
    }

    /// The bands of rows a frame splits into so that none marches more
    /// than `max_samples` samples (rays x the longest ray's samples; `render`
    /// takes `limits::MAX_SAMPLES_PER_SUBMIT`): submit each band's
    /// `record_band` on its own, so no submission runs long enough for a
    /// driver's watchdog. Every band but the last starts and ends on a
    /// workgroup row (8 pixel rows); together they cover the frame once. A
    /// band is at least one workgroup row, so a budget below one row's
    /// samples gives bands of one row each, over the budget.
    pub fn bands(&self, scene: Scene, desc: &FrameDesc, max_samples: u64) -> Result<Vec<Band>> {
        let (_, height) = desc.size();
        let local = self.local_size(scene, desc);
        let rows = band_rows(self.ctx.info(), local, scene, desc, max_samples)?;
        let local = local[1];
        let groups = height.div_ceil(local);
        Ok((0..groups)
            .step_by(rows as usize)
            .map(|g| Band {
                first_row: g * local,
                rows: (rows.min(groups - g) * local).min(height - g * local),
            })
            .collect())
    }

    /// As `record`, marching only `band`'s rows of the frame (one of
    /// `bands`); the rest of the output is left as it was. The barriers and
    /// state are `record`'s, so bands recorded one after another (in one
    /// command buffer or several) write the whole frame, the same as one
    /// `record` bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub fn record_band(
        &self,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        target: &RenderTarget,
        scene: Scene,
        desc: &FrameDesc,
        output: Output,
        band: Band,
    ) -> Result<()> {
        let local = self.local_size(scene, desc)[1];
        let (_, height) = desc.size();
        let end = band.first_row.checked_add(band.rows).filter(|&e| e <= height);
        if !band.first_row.is_multiple_of(local) || band.rows == 0 || end.is_none() {
            return Err(Error::invalid(
                "band",
                format!("rows {} + {}", band.first_row, band.rows),
                format!("a band of a {height}-row frame starts on a multiple of {local} (Renderer::bands)"),
            ));
        }
        let mut to = self.destination(target, desc, output)?;
        to.rows = Some([band.first_row / local, band.rows.div_ceil(local)]);
        self.record_frame(cmd, timer, target, scene, desc, to)
    }

    /// Where a frame of `desc` on `target` goes, its whole rows: after the
    /// checks that it fits.
    fn destination<'a>(&self, target: &'a RenderTarget, desc: &FrameDesc, output: Output) -> Result<Destination<'a>> {
        let (width, height) = desc.size();
        if (width, height) != (target.width, target.height) {
            return Err(Error::invalid(
                "size",
                format!("{width}x{height}"),
                format!("render target is {}x{}", target.width, target.height),
            ));
        }
        let own_depth = Binding::Storage(&target.depth);
        let (variant, output, depth, write_depth) = match output {
            Output::Buffer => (
                None,
                Binding::Storage(target.frame_buffer()?),
                own_depth,
                desc.writes_depth(),
            ),
            Output::Image(image) => {
                image.check(width, height)?;
                (
                    Some(image.variant()?),
                    Binding::StorageImage(image.view),
                    own_depth,
                    false,
                )
            }
            Output::ImageAndDepth(image, d) => {
                image.check(width, height)?;
                d.check(&self.ctx, width, height)?;
                // Exactly the frame's depths: a larger range could pass the
                // device's maxStorageBufferRange (or, at WHOLE_SIZE, the buffer).
                let depth = Binding::StorageRange(d.buffer, d.offset, width as u64 * height as u64 * 4);
                (Some(image.variant()?), Binding::StorageImage(image.view), depth, true)
            }
        };
        Ok(Destination {
            variant,
            output,
            depth,
            write_depth,
            rows: None,
        })
    }

    /// `record`, writing `to`.
    fn record_frame(
        &self,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        target: &RenderTarget,
        scene: Scene,
        desc: &FrameDesc,
        to: Destination,
    ) -> Result<()> {
        let Destination {
            variant,
            output,
            depth,
            write_depth,
            rows,
        } = to;
        let Scene { structure, volume, tf } = scene;
        self.ctx.check_is(cmd.context(), "command buffer")?;
        self.ctx.check_is(volume.context(), "volume")?;
        self.ctx.check_is(tf.context(), "transfer function")?;
        self.ctx.check_is(target.params.context(), "render target")?;
        structure.check_made_on(&self.ctx)?;
        tf.check_channels(volume.channels)?;
        if desc.lighting().is_some() {
            volume.check_one_channel("shaded and iso frames")?;
        }
        desc.check_loop_passes(self.ctx.info(), volume.dims)?;
        let mut params = desc.params(volume)?;
        params.tf_channel_step = tf.channel_step();
        params.value_bound = desc.mode().value_bound(tf.visible);
        if desc.writes_ray_values() {
            volume.check_one_channel("a segment's MIP and MinIP ray values")?;
        }
        params.depth_out = match write_depth {
            false => 0,
            true if desc.writes_ray_values() => 3,
            true if desc.camera_has_ndc() => 1,
            true => 2,
        };
        let filter = desc.filter_for(volume);
        let sampler = volume.sampler_for(filter)?;
        // Lit frames read the volume's gradient; the others bind the volume
        // in its place (nothing reads it).
        let gradient = match (desc.lighting().is_some(), volume.gradient_view()) {
            (false, _) => volume.image.view,
            (true, Some(view)) => view,
            (true, None) => {
                return Err(Error::invalid(
                    "volume",
                    "without its gradient",
                    "shaded and iso frames read the volume's gradient: upload it with GpuVolume::add_gradient (or record_add_gradient)",
                ))
            }
        };
        structure.check_mode(desc.mode())?;
        structure.check_built_for(volume, tf)?;
        let kernel = self.output_kernel(structure.march(), desc, volume, variant, write_depth)?;
        let groups = kernel.groups("frame", [target.width, target.height, 1])?;
        let n = crate::tf::LUT_SIZE as u32;
        let lut_groups = self.opacity.groups("frame LUT", [n * tf.channels, 1, 1])?;
        let lut_push = build_opacity_lut::Push {
            dt: params.step,
            n,
            channels: tf.channels,
        };
        let device = self.ctx.device();
        // Earlier frames on this target: their parameter reads and frame
        // readback must finish before this frame overwrites them.
        cmd.barrier(Access::COMPUTE_READ_WRITE, Access::TRANSFER_WRITE);
        cmd.barrier(Access::TRANSFER_READ, Access::COMPUTE_WRITE);
        unsafe { device.cmd_update_buffer(cmd.raw(), target.params.raw, 0, bytemuck::bytes_of(&params)) };
        let status = target.status_buffer();
        cmd.fill_buffer(status, 0, vk::WHOLE_SIZE, 0)?;
        cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ_WRITE);
        // The bindings every march kernel has, then the structure's own.
        let mut bindings: Vec<Bound> = MarchCommon {
            params: Binding::Storage(&target.params),
            volume_tex: Binding::Sampled(volume.image.view, sampler),
            tf_lut: Binding::Texels(&target.lut),
            frame: output,
            frame_depth: depth,
            gradient_tex: Binding::Sampled(gradient, sampler),
            volume_cells: Binding::Texels(volume.cells().unwrap_or(&self.no_cells)),
            gradient_cells: Binding::Texels(volume.gradient_cells().unwrap_or(&self.no_cells)),
            brick_table: Binding::Texels(volume.brick_table()),
            pool_1: Binding::Sampled(volume.pool_views()[0], volume.sampler),
            pool_2: Binding::Sampled(volume.pool_views()[1], volume.sampler),
            pool_3: Binding::Sampled(volume.pool_views()[2], volume.sampler),
            march_status: Binding::Storage(status),
        }
        .list();
        bindings.extend(structure.built.bindings());
        let push = structure.built.push();
        let mut timer = timer;
        let pass = timer.begin(cmd, "march")?;
        // The pass is closed whatever fails, so the timer stays usable.
        let recorded = (|| -> Result<()> {
            if let Some(d) = desc.depth() {
                let limits = render_depth_limit::Bindings {
                    params: Binding::Storage(&target.params),
                    depth_image: Binding::SampledIn(d.view, self.depth_sampler, d.layout),
                };
                let depth_groups = self
                    .depth_limit
                    .groups("depth limits", [target.width, target.height, 1])?;
                // SAFETY: every binding is a live object of this context borrowed for
                // the call, or the host's (`Recording::adopt`, `HostImage::new`).
                unsafe { self.depth_limit.dispatch(cmd, &limits.list(), &[], depth_groups) }?;
            }
            // An earlier frame's march reads the LUT this one rewrites.
            cmd.barrier(Access::COMPUTE_READ_WRITE, Access::COMPUTE_WRITE);
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.opacity.dispatch(
                    cmd,
                    &build_opacity_lut::Bindings {
                        raw: Binding::Storage(&tf.lut),
                        lut: Binding::Storage(target.lut.buffer()),
                    }
                    .list(),
                    bytemuck::bytes_of(&lut_push),
                    lut_groups,
                )
            }?;
            // The LUT and the depth limits, written above, are read by the march.
            cmd.barrier(Access::COMPUTE_WRITE, Access::COMPUTE_READ);
            // A band: workgroup rows [first, first + count).
            let [first, count] = rows.unwrap_or([0, groups[1]]);
            let rows = count.min(groups[1].saturating_sub(first));
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe { kernel.dispatch_base(cmd, &bindings, &push, [0, first, 0], [groups[0], rows, 1]) }
        })();
        timer.end(cmd, pass);
        recorded?;
        // The march status (`RenderTarget::cut_groups`) is read by the host.
        cmd.barrier(Access::COMPUTE_WRITE, Access::HOST_READ);
        Ok(())
    }

    /// Records the copy of the frame buffer and the depth buffer to the
    /// target's host-visible readback buffer, with the barriers before (compute write -> transfer
    /// read) and after (transfer write -> host read). A target without a
    /// readback buffer is an error.
    pub fn record_readback(&self, cmd: Recording<'_>, target: &RenderTarget) -> Result<()> {
        self.ctx.check_is(cmd.context(), "command buffer")?;
        let (frame, readback) = (target.frame_buffer()?, target.readback_buffer()?);
        cmd.barrier(Access::COMPUTE_WRITE, Access::TRANSFER_READ);
        // Checked copies: the target's buffers and the command buffer share a context.
        let copy = |src: &crate::gpu::Buffer, dst_offset: u64| {
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset,
                size: src.size(),
            }];
            cmd.copy_buffer(src, readback, &region)
        };
        copy(frame, 0)?;
        copy(&target.depth, frame.size())?;
        cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
        Ok(())
    }

    /// After the submission of the last frame `record`ed on `target` (with
    /// `structure`) completed: an error (`Error::LoopCap`) when the device's
    /// cap on a shader's loop passes may have cut some of its rays short, so
    /// that the frame may not be the exact one. Each `record` resets the
    /// target's count: check after each frame's submission.
    pub fn check_whole(&self, target: &RenderTarget, structure: &Structure) -> Result<()> {
        let groups = target.cut_groups()?;
        if groups == 0 {
            return Ok(());
        }
        Err(structure.cut_error(self.ctx.info(), groups))
    }

    /// Renders one frame: records, submits, waits, reads back. Returns the
    /// frame and the GPU time of each pass ("march", "readback"). A frame of
    /// more than `limits::MAX_SAMPLES_PER_SUBMIT` samples is marched in
    /// bands of rows, one submission each (`render_in_bands`).
    pub fn render(&self, scene: Scene, desc: &FrameDesc) -> Result<(Frame, Timings)> {
        let (frame, timings, _) = self.render_in_bands(scene, desc, crate::limits::MAX_SAMPLES_PER_SUBMIT)?;
        Ok((frame, timings))
    }

    /// As `render`, in bands of rows of at most `max_samples` samples (rays x
    /// the longest ray's samples), one submission each; phases are summed
    /// over the bands, which are counted. Rays end at no host depth here.
    pub fn render_in_bands(&self, scene: Scene, desc: &FrameDesc, max_samples: u64) -> Result<(Frame, Timings, u32)> {
        if desc.depth().is_some() {
            return Err(Error::invalid(
                "frame",
                "with a host depth image",
                "is recorded into the host's command buffer (Renderer::record), not rendered",
            ));
        }
        let (width, height) = desc.size();
        let target = RenderTarget::new(&self.ctx, width, height)?;
        let with_depth = desc.writes_depth();
        let kernel = self.kernel(scene.structure.march(), desc, scene.volume)?;
        let groups = kernel.groups("frame", [target.width, target.height, 1])?;
        let rows_per_band = band_rows(self.ctx.info(), kernel.local_size(), scene, desc, max_samples)?;
        let mut timings = Timings::default();
        let mut first = 0;
        let mut bands = 0u32;
        while first < groups[1] {
            let last = first + rows_per_band >= groups[1];
            let mut timer = Timer::new(&self.ctx, 4)?;
            self.ctx.submit_and_wait(|cmd| {
                timer.reset(cmd);
                let to = Destination {
                    variant: None,
                    output: Binding::Storage(target.frame_buffer()?),
                    depth: Binding::Storage(&target.depth),
                    write_depth: with_depth,
                    rows: Some([first, rows_per_band]),
                };
                self.record_frame(cmd, Some(&mut timer), &target, scene, desc, to)?;
                if last {
                    let pass = timer.begin(cmd, "readback")?;
                    self.record_readback(cmd, &target)?;
                    timer.end(cmd, pass);
                }
                Ok(())
            })?;
            self.check_whole(&target, scene.structure)?;
            for (name, ms) in timer.results()?.phases {
                match timings.phases.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, sum)) => *sum += ms,
                    None => timings.push(name, ms),
                }
            }
            first += rows_per_band;
            bands += 1;
        }
        let frame = if with_depth {
            target.read_with_depth()?
        } else {
            target.read()?
        };
        Ok((frame, timings, bands))
    }
}

/// The march kernel's constants for frames of `desc` on `volume`, with
/// depth written or not.
fn frame_constants(desc: &FrameDesc, volume: &GpuVolume, write_depth: bool) -> crate::desc::KernelConstants {
    crate::desc::with_depth_out(desc.kernel_constants(volume), write_depth)
}

/// Workgroup rows per band of at most `max_samples` samples, for a kernel
/// of workgroup size `local` marching `desc`.
fn band_rows(
    info: &crate::gpu::DeviceInfo,
    local: [u32; 3],
    scene: Scene,
    desc: &FrameDesc,
    max_samples: u64,
) -> Result<u32> {
    let (width, height) = desc.size();
    let per_ray = crate::limits::check_samples_per_ray(scene.volume.dims, desc.step())?;
    let groups = crate::gpu::record::groups_for(info, "frame", [width, height, 1], local)?;
    // Rays in one row of workgroups; at least one row per band.
    let row_rays = width as u64 * local[1] as u64;
    Ok((max_samples / per_ray.max(1) / row_rays.max(1)).clamp(1, groups[1] as u64) as u32)
}

impl Drop for Renderer {
    fn drop(&mut self) {
        self.ctx.retire([crate::gpu::Retired::Sampler(self.depth_sampler)]);
    }
}
