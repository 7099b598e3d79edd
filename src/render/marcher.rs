//! Marcher dispatch: one kernel per traversal style, a render target, and the
//! `record_*` functions that only record into a caller's command buffer.

use super::params::RenderParams;
use super::settings::RenderSettings;
use crate::accel::{Accel, Structure};
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::gpu::record::{self, Access};
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation, Timer};
use crate::tf::GpuTransferFunction;
use crate::timings::Timings;
use crate::volume::{Filter, GpuVolume, FILTER_CONSTANT_ID};
use bytemuck::{Pod, Zeroable};

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A march kernel: shader name, the structure's specialization constants,
/// and the sample filter.
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

/// Where a frame goes: the RGBA f32 frame buffer, its parameter block, the
/// frame's LUT (corrected for its step, then raw: `glsl/common/tf.glsl`), and
/// a host-visible copy for readback.
pub struct RenderTarget {
    pub width: u32,
    pub height: u32,
    pub frame: Buffer,
    pub params: Buffer,
    pub lut: Buffer,
    readback: Buffer,
}

impl RenderTarget {
    /// Checks the frame against `maxStorageBufferRange` and the dispatch limits.
    pub fn new(ctx: &Context, width: u32, height: u32) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "size",
                format!("{width}x{height}"),
                "width and height must be > 0",
            ));
        }
        let info = ctx.info();
        let bytes = width as u64 * height as u64 * 16;
        info.check(
            format!("frame {width}x{height} ({bytes} bytes)"),
            "maxStorageBufferRange",
            bytes,
            info.max_storage_buffer_range,
        )?;
        let local = crate::gpu::shaders::MARCH_NAIVE.local_size_with(&[]);
        record::groups_for(info, "frame", [width, height, 1], local)?;
        let frame = Buffer::new(
            ctx,
            "frame",
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let params = Buffer::new(
            ctx,
            "render params",
            std::mem::size_of::<RenderParams>() as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let lut = Buffer::new(
            ctx,
            "frame LUT",
            (2 * crate::tf::LUT_SIZE * 16) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let readback = Buffer::new(
            ctx,
            "frame readback",
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        Ok(RenderTarget {
            width,
            height,
            frame,
            params,
            lut,
            readback,
        })
    }

    /// Reads the frame recorded by `Renderer::record_readback`, after the
    /// submission completed.
    pub fn read(&self) -> Frame {
        // `new` allocates the readback buffer GpuToCpu, which gpu-allocator maps.
        #[allow(clippy::expect_used)]
        let bytes = self.readback.mapped().expect("readback buffer is host visible");
        let n = self.width as usize * self.height as usize;
        let pixels: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..n * 16]);
        Frame::new(self.width, self.height, pixels)
    }
}

/// The march kernels, created once per context and filter when a structure
/// first needs them (each structure names its kernel: `Method::march`), and
/// the kernel that writes each frame's LUT.
pub struct Renderer {
    ctx: Context,
    kernels: Mutex<HashMap<KernelKey, Arc<Kernel>>>,
    opacity: Kernel,
}

impl Renderer {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Renderer {
            ctx: ctx.clone(),
            kernels: Mutex::new(HashMap::new()),
            opacity: Kernel::new::<OpacityPush>(ctx, &crate::gpu::shaders::BUILD_OPACITY_LUT)?,
        })
    }

    /// The march kernel of `accel` sampling with `filter`, created on first use.
    pub fn kernel(&self, accel: Accel, filter: Filter) -> Result<Arc<Kernel>> {
        let march = accel.method().march();
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

    /// Records one frame into `cmd`: parameter update, then the march pass
    /// (timed as "march" when `timer` is given): the frame's LUT corrected
    /// for its step, then `structure`'s kernel sampling with `settings.filter`.
    ///
    /// Barriers. Before: the volume image is in SHADER_READ_ONLY_OPTIMAL and
    /// its upload and the TF buffer's are visible to compute reads (true after
    /// `GpuVolume::upload` / `TransferFunction::upload`, which wait), and the
    /// structure's buffers are visible to compute reads (true after
    /// `Builder::build`; after `record_*` builds, a barrier from
    /// `Access::COMPUTE_WRITE` to `Access::COMPUTE_READ`). Recorded
    /// here: earlier uses of `target` in the same command buffer (compute
    /// reads of the parameters and LUT, transfer reads of the frame) are
    /// ordered before this frame's writes. After: the frame buffer is written in the
    /// compute stage; read it only after a barrier from `Access::COMPUTE_WRITE`
    /// (`record_readback` records one).
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
        if (settings.width, settings.height) != (target.width, target.height) {
            return Err(Error::invalid(
                "size",
                format!("{}x{}", settings.width, settings.height),
                format!("render target is {}x{}", target.width, target.height),
            ));
        }
        let params = settings.params(volume.dims, volume.spacing, volume.norm)?;
        self.record_params(cmd, timer, structure, target, volume, tf, &params, settings.filter)
    }

    /// As `record`, with explicit shader parameters: a camera of your own
    /// (any ray origins and directions in voxel space). `params.image` must
    /// match the target and `params.dims` the volume; hardware `filter`
    /// needs a volume format the device filters linearly.
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
        if [params.image[0], params.image[1]] != [target.width, target.height] {
            return Err(Error::invalid(
                "render params",
                format!("{}x{}", params.image[0], params.image[1]),
                format!("render target is {}x{}", target.width, target.height),
            ));
        }
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
        let kernel = self.kernel(structure.accel, filter)?;
        let groups = kernel.groups("frame", [target.width, target.height, 1])?;
        let n = crate::tf::LUT_SIZE as u32;
        let lut_groups = self.opacity.groups("frame LUT", [n, 1, 1])?;
        let lut_push = OpacityPush { dt: params.march[0], n };
        let device = self.ctx.device();
        // Earlier frames on this target: their parameter reads and frame
        // readback must finish before this frame overwrites them.
        record::barrier(device, cmd, Access::COMPUTE_READ, Access::TRANSFER_WRITE);
        record::barrier(device, cmd, Access::TRANSFER_READ, Access::COMPUTE_WRITE);
        unsafe { device.cmd_update_buffer(cmd, target.params.raw, 0, bytemuck::bytes_of(params)) };
        record::barrier(device, cmd, Access::TRANSFER_WRITE, Access::COMPUTE_READ);
        let mut bindings = vec![
            Binding::Storage(&target.params),
            Binding::Sampled(volume.image.view, sampler),
            Binding::Storage(&target.lut),
            Binding::Storage(&target.frame),
        ];
        bindings.extend(structure.built.bindings());
        let push = structure.built.push();
        let pass = match timer {
            Some(timer) => Some((timer.begin(cmd, "march")?, timer)),
            None => None,
        };
        // An earlier frame's march reads the LUT this one rewrites.
        record::barrier(device, cmd, Access::COMPUTE_READ_WRITE, Access::COMPUTE_WRITE);
        self.opacity.dispatch(
            cmd,
            &[Binding::Storage(&tf.lut), Binding::Storage(&target.lut)],
            bytemuck::bytes_of(&lut_push),
            lut_groups,
        )?;
        record::barrier(device, cmd, Access::COMPUTE_WRITE, Access::COMPUTE_READ);
        kernel.dispatch(cmd, &bindings, &push, groups)?;
        if let Some((pass, timer)) = pass {
            timer.end(cmd, pass);
        }
        Ok(())
    }

    /// Records the copy of the frame to the host-visible readback buffer,
    /// with the barriers before (compute write -> transfer read) and after
    /// (transfer write -> host read).
    pub fn record_readback(&self, cmd: vk::CommandBuffer, target: &RenderTarget) {
        let device = self.ctx.device();
        record::barrier(device, cmd, Access::COMPUTE_WRITE, Access::TRANSFER_READ);
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: target.frame.size(),
        }];
        unsafe { device.cmd_copy_buffer(cmd, target.frame.raw, target.readback.raw, &region) };
        record::barrier(device, cmd, Access::TRANSFER_WRITE, Access::HOST_READ);
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

    /// As `render`, with explicit shader parameters (see `record_params`).
    pub fn render_params(
        &self,
        structure: &Structure,
        volume: &GpuVolume,
        tf: &GpuTransferFunction,
        params: &RenderParams,
        filter: Filter,
    ) -> Result<(Frame, Timings)> {
        let target = RenderTarget::new(&self.ctx, params.image[0], params.image[1])?;
        let mut timer = Timer::new(&self.ctx, 4)?;
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            self.record_params(cmd, Some(&mut timer), structure, &target, volume, tf, params, filter)?;
            let pass = timer.begin(cmd, "readback")?;
            self.record_readback(cmd, &target);
            timer.end(cmd, pass);
            Ok(())
        })?;
        Ok((target.read(), timer.results()?))
    }
}
