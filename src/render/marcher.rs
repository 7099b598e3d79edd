//! Marcher dispatch: one kernel per traversal style (and output format), and
//! the `record_*` functions that only record into a caller's command buffer.

use super::params::RenderParams;
use super::settings::RenderSettings;
use super::target::{HostDepth, Output, RenderTarget};
use super::view::View;
use crate::accel::{Accel, Structure};
use crate::error::{Error, Result, VkContext};
use crate::frame::Frame;
use crate::gpu::record::{self, Access};
use crate::gpu::timings::Timings;
use crate::gpu::{shaders, vk, Binding, Context, Kernel, OptionalTimer, Timer};
use crate::tf::GpuTransferFunction;
use crate::volume::{Filter, GpuVolume, FILTER_CONSTANT_ID};
use bytemuck::{Pod, Zeroable};

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A march kernel: shader name (with its output variant), the structure's
/// specialization constants, and the sample filter.
type KernelKey = (&'static str, &'static [u32], Filter);

/// Push block of `glsl/build/opacity_lut.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct OpacityPush {
    dt: f32,
    n: u32,
}

/// Bindings every march kernel starts with: render parameters, volume, LUT, frame.
const COMMON_BINDINGS: usize = 4;

/// Every input of one frame besides the target: what to march and how.
#[derive(Clone, Copy)]
pub struct Scene<'a> {
    pub structure: &'a Structure,
    pub volume: &'a GpuVolume,
    pub tf: &'a GpuTransferFunction,
}

/// The march kernels, created once per context and filter when a structure
/// first needs them (each structure names its kernel: `Method::march`), and
/// the kernel that writes each frame's LUT.
pub struct Renderer {
    ctx: Context,
    kernels: Mutex<HashMap<KernelKey, Arc<Kernel>>>,
    opacity: Kernel,
    depth_limit: Kernel,
    /// Reads host depth images (texelFetch: its filter is irrelevant).
    depth_sampler: vk::Sampler,
}

impl Renderer {
    pub fn new(ctx: &Context) -> Result<Self> {
        let opacity = Kernel::new::<OpacityPush>(ctx, &shaders::BUILD_OPACITY_LUT)?;
        let depth_limit = Kernel::new::<()>(ctx, &shaders::RENDER_DEPTH_LIMIT)?;
        let info = vk::SamplerCreateInfo::default()
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        let depth_sampler = unsafe { ctx.device().create_sampler(&info, None) }.vk("vkCreateSampler")?;
        Ok(Renderer {
            ctx: ctx.clone(),
            kernels: Mutex::new(HashMap::new()),
            opacity,
            depth_limit,
            depth_sampler,
        })
    }

    /// The march kernel of `accel` sampling with `filter` and writing the
    /// frame buffer, created on first use.
    pub fn kernel(&self, accel: Accel, filter: Filter) -> Result<Arc<Kernel>> {
        self.kernel_for(accel, filter, None)
    }

    /// As `kernel`, writing a storage image of the `variant` format instead
    /// (`march/NAME@rgba8`, ...: build.rs).
    fn kernel_for(&self, accel: Accel, filter: Filter, variant: Option<&str>) -> Result<Arc<Kernel>> {
        let mut march = accel.method().march();
        if let Some(v) = variant {
            let name = format!("{}@{v}", march.shader.name);
            march.shader = *shaders::ALL
                .iter()
                .find(|s| s.name == name)
                .ok_or_else(|| Error::Interface(format!("kernel {name}: no such shader variant")))?;
        }
        let key = (march.shader.name, march.constants, filter);
        let mut map = self.kernels.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(k) = map.get(&key) {
            return Ok(k.clone());
        }
        if march.shader.bindings.len() < COMMON_BINDINGS {
            return Err(Error::Interface(format!(
                "kernel {}: a march kernel has at least {COMMON_BINDINGS} bindings",
                march.shader.name
            )));
        }
        let mut constants: Vec<(u32, u32)> = (0..).zip(march.constants.iter().copied()).collect();
        constants.push((FILTER_CONSTANT_ID, filter.constant()));
        let k = Arc::new(Kernel::specialized(
            &self.ctx,
            &march.shader,
            march.push_size,
            &constants,
        )?);
        map.insert(key, k.clone());
        Ok(k)
    }

    /// Records one frame of the CLI's orbit `settings` into `target`'s frame
    /// buffer: `record_view` with `View::orbit` and `Output::Buffer`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        structure: &Structure,
        target: &RenderTarget,
        volume: &GpuVolume,
        tf: &GpuTransferFunction,
        settings: &RenderSettings,
    ) -> Result<()> {
        let scene = Scene { structure, volume, tf };
        let view = View::orbit(volume, settings)?;
        self.record_view(cmd, timer, target, scene, &view, Output::Buffer, None)
    }

    /// Records one frame into `cmd` (timed as "march" when `timer` is given):
    /// the parameter update, the per-pixel ray limits from `depth` when given,
    /// the frame's LUT corrected for its step, then the structure's march
    /// kernel writing `output`. Nothing is submitted.
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
    /// buffer). State left bound: the compute pipeline, pipeline layout, push
    /// descriptors and push constants of the last lacuna kernel; graphics
    /// state and the host's descriptor sets are untouched, but a host
    /// compute pipeline must be bound again.
    #[allow(clippy::too_many_arguments)]
    pub fn record_view(
        &self,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        target: &RenderTarget,
        scene: Scene,
        view: &View,
        output: Output,
        depth: Option<&HostDepth>,
    ) -> Result<()> {
        let (width, height) = view.size();
        if (width, height) != (target.width, target.height) {
            return Err(Error::invalid(
                "size",
                format!("{width}x{height}"),
                format!("render target is {}x{}", target.width, target.height),
            ));
        }
        let mut params = *view.params();
        let depth = match depth {
            Some(d) => {
                d.check(width, height)?;
                params.depth[1] = 1.0;
                Some(d)
            }
            None => None,
        };
        let output = match output {
            Output::Buffer => (None, Binding::Storage(target.frame_buffer()?)),
            Output::Image(image) => {
                image.check(width, height)?;
                (Some(image.variant()?), Binding::StorageImage(image.view))
            }
        };
        self.record_frame(
            cmd,
            timer,
            target,
            scene,
            &params,
            view.sample_filter(),
            output,
            depth,
            None,
        )
    }

    /// As `record`, with explicit shader parameters (`View` forms them; this
    /// is for rays of your own in voxel space). `params.image` must match the
    /// target and `params.dims` the volume; hardware `filter` needs a volume
    /// format the device filters linearly.
    #[allow(clippy::too_many_arguments)]
    pub fn record_params(
        &self,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        structure: &Structure,
        target: &RenderTarget,
        volume: &GpuVolume,
        tf: &GpuTransferFunction,
        params: &RenderParams,
        filter: Filter,
    ) -> Result<()> {
        let scene = Scene { structure, volume, tf };
        self.record_band(cmd, timer, target, scene, params, filter, None)
    }

    /// `record_params` for the workgroup rows `band` (`[first, count]`) only.
    #[allow(clippy::too_many_arguments)]
    fn record_band(
        &self,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        target: &RenderTarget,
        scene: Scene,
        params: &RenderParams,
        filter: Filter,
        band: Option<[u32; 2]>,
    ) -> Result<()> {
        if [params.image[0], params.image[1]] != [target.width, target.height] {
            return Err(Error::invalid(
                "render params",
                format!("{}x{}", params.image[0], params.image[1]),
                format!("render target is {}x{}", target.width, target.height),
            ));
        }
        let mut params = *params;
        params.depth[1] = 0.0;
        let output = (None, Binding::Storage(target.frame_buffer()?));
        self.record_frame(cmd, timer, target, scene, &params, filter, output, None, band)
    }

    #[allow(clippy::too_many_arguments)]
    fn record_frame(
        &self,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        target: &RenderTarget,
        scene: Scene,
        params: &RenderParams,
        filter: Filter,
        (variant, output): (Option<&str>, Binding),
        depth: Option<&HostDepth>,
        band: Option<[u32; 2]>,
    ) -> Result<()> {
        let Scene { structure, volume, tf } = scene;
        if params.dims[..3] != volume.dims || params.dims[3] != crate::tf::LUT_SIZE as u32 {
            return Err(Error::invalid(
                "render params",
                format!("{:?}", params.dims),
                "dims do not match the volume and LUT",
            ));
        }
        if !(params.march[0].is_finite() && params.march[0] > 0.0) {
            return Err(Error::invalid(
                "step",
                params.march[0].to_string(),
                "must be a finite number > 0 (voxels)",
            ));
        }
        crate::limits::check_samples_per_ray(volume.dims, params.march[0])?;
        let sampler = volume.sampler_for(filter)?;
        let kernel = self.kernel_for(structure.accel, filter, variant)?;
        let groups = kernel.groups("frame", [target.width, target.height, 1])?;
        let n = crate::tf::LUT_SIZE as u32;
        let lut_groups = self.opacity.groups("frame LUT", [n, 1, 1])?;
        let lut_push = OpacityPush { dt: params.march[0], n };
        let device = self.ctx.device();
        // Earlier frames on this target: their parameter reads and frame
        // readback must finish before this frame overwrites them.
        record::barrier(device, cmd, Access::COMPUTE_READ_WRITE, Access::TRANSFER_WRITE);
        record::barrier(device, cmd, Access::TRANSFER_READ, Access::COMPUTE_WRITE);
        unsafe { device.cmd_update_buffer(cmd, target.params.raw, 0, bytemuck::bytes_of(params)) };
        record::barrier(device, cmd, Access::TRANSFER_WRITE, Access::COMPUTE_READ_WRITE);
        let mut bindings = vec![
            Binding::Storage(&target.params),
            Binding::Sampled(volume.image.view, sampler),
            Binding::TexelBuffer(target.lut.view()),
            output,
        ];
        bindings.extend(structure.built.bindings());
        let push = structure.built.push();
        let mut timer = timer;
        let pass = timer.begin(cmd, "march")?;
        if let Some(d) = depth {
            let limits = [
                Binding::Storage(&target.params),
                Binding::SampledIn(d.view, self.depth_sampler, d.layout),
            ];
            let depth_groups = self
                .depth_limit
                .groups("depth limits", [target.width, target.height, 1])?;
            self.depth_limit.dispatch(cmd, &limits, &[], depth_groups)?;
        }
        // An earlier frame's march reads the LUT this one rewrites.
        record::barrier(device, cmd, Access::COMPUTE_READ_WRITE, Access::COMPUTE_WRITE);
        self.opacity.dispatch(
            cmd,
            &[Binding::Storage(&tf.lut), Binding::Storage(target.lut.buffer())],
            bytemuck::bytes_of(&lut_push),
            lut_groups,
        )?;
        // The LUT and the depth limits, written above, are read by the march.
        record::barrier(device, cmd, Access::COMPUTE_WRITE, Access::COMPUTE_READ);
        // A band: workgroup rows [first, first + count).
        let [first, count] = band.unwrap_or([0, groups[1]]);
        let rows = count.min(groups[1].saturating_sub(first));
        kernel.dispatch_base(cmd, &bindings, &push, [0, first, 0], [groups[0], rows, 1])?;
        timer.end(cmd, pass);
        Ok(())
    }

    /// Records the copy of the frame buffer to the target's host-visible
    /// readback buffer, with the barriers before (compute write -> transfer
    /// read) and after (transfer write -> host read). A target without a
    /// readback buffer is an error.
    pub fn record_readback(&self, cmd: vk::CommandBuffer, target: &RenderTarget) -> Result<()> {
        let (frame, readback) = (target.frame_buffer()?, target.readback_buffer()?);
        let device = self.ctx.device();
        record::barrier(device, cmd, Access::COMPUTE_WRITE, Access::TRANSFER_READ);
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: frame.size(),
        }];
        unsafe { device.cmd_copy_buffer(cmd, frame.raw, readback.raw, &region) };
        record::barrier(device, cmd, Access::TRANSFER_WRITE, Access::HOST_READ);
        Ok(())
    }

    /// Renders one frame: records, submits, waits, reads back. Returns the
    /// frame and the GPU time of each pass ("march", "readback").
    pub fn render(
        &self,
        structure: &Structure,
        volume: &GpuVolume,
        tf: &GpuTransferFunction,
        settings: &RenderSettings,
    ) -> Result<(Frame, Timings)> {
        let params = settings.params(volume.dims, volume.spacing, volume.norm)?;
        self.render_params(structure, volume, tf, &params, settings.filter)
    }

    /// As `render`, with a `View` (a host's camera matrices, say).
    pub fn render_view(&self, scene: Scene, view: &View) -> Result<(Frame, Timings)> {
        self.render_params(
            scene.structure,
            scene.volume,
            scene.tf,
            view.params(),
            view.sample_filter(),
        )
    }

    /// As `render`, with explicit shader parameters (see `record_params`).
    pub fn render_params(
        &self,
        structure: &Structure,
        volume: &GpuVolume,
        tf: &GpuTransferFunction,
        params: &RenderParams,
        filter: Filter,
    ) -> Result<(Frame, Timings)> {
        let (frame, timings, _) = self.render_in_bands(
            structure,
            volume,
            tf,
            params,
            filter,
            crate::limits::MAX_SAMPLES_PER_SUBMIT,
        )?;
        Ok((frame, timings))
    }

    /// As `render_params`, in bands of rows of at most `max_samples` samples
    /// (rays x the longest ray's samples), one submission each; phases are
    /// summed over the bands, which are counted.
    pub fn render_in_bands(
        &self,
        structure: &Structure,
        volume: &GpuVolume,
        tf: &GpuTransferFunction,
        params: &RenderParams,
        filter: Filter,
        max_samples: u64,
    ) -> Result<(Frame, Timings, u32)> {
        let target = RenderTarget::new(&self.ctx, params.image[0], params.image[1])?;
        let per_ray = crate::limits::check_samples_per_ray(volume.dims, params.march[0])?;
        let kernel = self.kernel_for(structure.accel, filter, None)?;
        let groups = kernel.groups("frame", [target.width, target.height, 1])?;
        // Rays in one row of workgroups; at least one row per band.
        let row_rays = target.width as u64 * kernel.local_size()[1] as u64;
        let rows_per_band = (max_samples / per_ray.max(1) / row_rays.max(1)).clamp(1, groups[1] as u64) as u32;
        let mut timings = Timings::default();
        let mut first = 0;
        let mut bands = 0u32;
        while first < groups[1] {
            let last = first + rows_per_band >= groups[1];
            let mut timer = Timer::new(&self.ctx, 4)?;
            self.ctx.submit_and_wait(|cmd| {
                timer.reset(cmd);
                let scene = Scene { structure, volume, tf };
                let band = Some([first, rows_per_band]);
                self.record_band(cmd, Some(&mut timer), &target, scene, params, filter, band)?;
                if last {
                    let pass = timer.begin(cmd, "readback")?;
                    self.record_readback(cmd, &target)?;
                    timer.end(cmd, pass);
                }
                Ok(())
            })?;
            for (name, ms) in timer.results()?.phases {
                match timings.phases.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, sum)) => *sum += ms,
                    None => timings.push(name, ms),
                }
            }
            first += rows_per_band;
            bands += 1;
        }
        Ok((target.read()?, timings, bands))
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        unsafe { self.ctx.device().destroy_sampler(self.depth_sampler, None) };
    }
}
