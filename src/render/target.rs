//! Where a frame goes: lacuna's per-size buffers (`RenderTarget`), and the
//! host's images a frame can be written to (`HostImage`).

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::gpu::record;
use crate::gpu::shaders::blocks::RenderParams;
use crate::gpu::{vk, Buffer, Context, DeviceInfo, MemoryLocation, TexelBuffer};

/// The per-frame-size buffers of a frame: its parameter block (with the
/// per-pixel depth limits after it), the frame's LUT (corrected for its
/// step, then raw: `glsl/common/tf.glsl`), and, when the frame goes to a
/// buffer, the RGBA f32 frame buffer and optionally a host-visible readback.
///
/// Its fields are read through methods: the march writes what they say,
/// so they do not change after it is made.
pub struct RenderTarget {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// RGBA f32 premultiplied, row-major; None for a target of host images.
    pub(crate) frame: Option<Buffer>,
    /// An iso frame's depth, f32 per pixel (`HostDepthOut` says what it
    /// holds); 16 bytes, never written, for a target of host images.
    pub(crate) depth: Buffer,
    pub(crate) params: Buffer,
    pub(crate) lut: TexelBuffer,
    /// The SIMD groups of the last frame whose march a driver's loop cap
    /// may have cut short (`cut_groups`); host-visible.
    status: Buffer,
    readback: Option<Buffer>,
}

/// A host's 2D storage image a frame is written to: premultiplied RGBA,
/// `R8G8B8A8_UNORM`, `R16G16B16A16_SFLOAT` or `R32G32B32A32_SFLOAT`, created
/// with `STORAGE` usage, in `layout` (GENERAL, the layout storage writes need)
/// when the frame's commands execute.
#[derive(Clone, Copy, Debug)]
pub struct HostImage {
    pub(crate) view: vk::ImageView,
    pub(crate) format: vk::Format,
    pub(crate) layout: vk::ImageLayout,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl HostImage {
    /// The host's image `view`, `width` x `height` texels of `format`.
    /// Format, size and layout are checked where a frame is recorded.
    ///
    /// # Safety
    /// Whenever a frame recorded to it executes, `view` is a live 2D colour
    /// view (one level and layer) of `format` and at least `width` x
    /// `height` texels, of an image of the renderer's device created with
    /// `STORAGE` usage, in `layout`.
    pub unsafe fn new(
        view: vk::ImageView,
        format: vk::Format,
        layout: vk::ImageLayout,
        width: u32,
        height: u32,
    ) -> Self {
        HostImage {
            view,
            format,
            layout,
            width,
            height,
        }
    }

    /// Its width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Its height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }
}

/// A host's storage buffer a frame writes its depth to: one f32 per pixel,
/// row-major, `size` bytes from `offset` (at least width x height x 4; the
/// offset a multiple of `minStorageBufferOffsetAlignment`). Iso frames write
/// each surface's depth there, every other frame (and a ray that hits no
/// surface) the far depth: with host camera matrices NDC depth in the
/// host's convention (`CameraMatrices`; the far plane's depth where nothing
/// is hit), else the distance from the ray's origin in physical units
/// (infinity where nothing is hit). A host copies it into its depth
/// attachment with `vkCmdCopyBufferToImage` (D32_SFLOAT) to depth-test what
/// it draws after.
#[derive(Clone, Copy, Debug)]
pub struct HostDepthOut {
    pub(crate) buffer: vk::Buffer,
    pub(crate) offset: u64,
    pub(crate) size: u64,
}

/// The frame's destination.
#[derive(Clone, Copy, Debug)]
pub enum Output {
    /// The target's own frame buffer (and, for iso frames, its depth
    /// buffer, which the readback carries: `Frame::depth`).
    Buffer,
    Image(HostImage),
    /// A host image and a host depth buffer.
    ImageAndDepth(HostImage, HostDepthOut),
}

impl HostDepthOut {
    /// `size` bytes of the host's `buffer` from `offset` (checked against
    /// the frame and the device's alignment where a frame is recorded).
    ///
    /// # Safety
    /// Whenever a frame recorded to it executes, `buffer` is a live buffer
    /// of the context's device created with `STORAGE_BUFFER` usage, at least
    /// `offset + size` bytes long, and nothing reads or writes those bytes
    /// on the host meanwhile (where it is a lacuna `Buffer`'s handle: no
    /// `Buffer::host` or `host_mut` until the submission completed; lacuna
    /// does not see the write through a raw handle).
    pub unsafe fn new(buffer: vk::Buffer, offset: u64, size: u64) -> Self {
        HostDepthOut { buffer, offset, size }
    }

    pub(crate) fn check(&self, ctx: &Context, width: u32, height: u32) -> Result<()> {
        let need = width as u64 * height as u64 * 4;
        if self.size < need {
            return Err(Error::invalid(
                "host depth output",
                format!("{} bytes", self.size),
                format!("a {width}x{height} frame needs {need} (one f32 per pixel)"),
            ));
        }
        let align = ctx.info().min_storage_buffer_offset_alignment;
        if !self.offset.is_multiple_of(align.max(1)) {
            return Err(Error::invalid(
                "host depth output offset",
                self.offset.to_string(),
                format!("must be a multiple of minStorageBufferOffsetAlignment ({align})"),
            ));
        }
        Ok(())
    }
}

impl HostImage {
    /// The shader variant suffix for the format (`glsl/common/frame_out.glsl`).
    pub(crate) fn variant(&self) -> Result<&'static str> {
        match self.format {
            vk::Format::R8G8B8A8_UNORM => Ok("rgba8"),
            vk::Format::R16G16B16A16_SFLOAT => Ok("rgba16f"),
            vk::Format::R32G32B32A32_SFLOAT => Ok("rgba32f"),
            f => Err(Error::invalid(
                "host image format",
                format!("{f:?}"),
                "must be R8G8B8A8_UNORM, R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT",
            )),
        }
    }

    pub(crate) fn check(&self, width: u32, height: u32) -> Result<()> {
        self.variant()?;
        if self.layout != vk::ImageLayout::GENERAL {
            return Err(Error::invalid(
                "host image layout",
                format!("{:?}", self.layout),
                "storage images are written in GENERAL",
            ));
        }
        if (self.width, self.height) != (width, height) {
            return Err(Error::invalid(
                "host image",
                format!("{}x{}", self.width, self.height),
                format!("the frame is {width}x{height}"),
            ));
        }
        Ok(())
    }
}

impl RenderTarget {
    /// The frame size it was made for.
    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The RGBA f32 frame buffer (premultiplied, row-major); None for a
    /// target of host images.
    pub fn frame(&self) -> Option<&Buffer> {
        self.frame.as_ref()
    }

    /// The depth buffer (one f32 per pixel; see `HostDepthOut`).
    pub fn depth(&self) -> &Buffer {
        &self.depth
    }

    /// The frame's LUT as the last recorded frame wrote it (corrected for
    /// its step, then raw).
    pub fn lut(&self) -> &TexelBuffer {
        &self.lut
    }

    /// A target writing its own frame buffer, with a host-visible readback
    /// (`Renderer::record_readback`, `read`). Checks the frame against
    /// `maxStorageBufferRange` and the dispatch limits.
    pub fn new(ctx: &Context, width: u32, height: u32) -> Result<Self> {
        Self::create(ctx, width, height, true, true)
    }

    /// A target writing its own frame buffer, without a readback buffer.
    pub fn without_readback(ctx: &Context, width: u32, height: u32) -> Result<Self> {
        Self::create(ctx, width, height, true, false)
    }

    /// A target for frames that go to host images (`Output::Image`): no
    /// frame buffer, no readback.
    pub fn for_images(ctx: &Context, width: u32, height: u32) -> Result<Self> {
        Self::create(ctx, width, height, false, false)
    }

    /// Checks a frame of `width` x `height` against the device's limits, as
    /// creating a target does: callers check it before work that comes
    /// first (loading a volume, auto's probes).
    pub fn check_size(info: &DeviceInfo, width: u32, height: u32) -> Result<()> {
        Self::check_size_for(info, width, height, true)
    }

    /// `check_size` for a target with its own frame buffer (`frame`) or one
    /// for host images, whose largest buffer is the per-pixel parameters.
    fn check_size_for(info: &DeviceInfo, width: u32, height: u32, frame: bool) -> Result<()> {
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "size",
                format!("{width}x{height}"),
                "width and height must be > 0",
            ));
        }
        let pixels = width as u64 * height as u64;
        let (what, bytes) = match frame {
            true => ("frame", pixels * 16),
            false => ("frame's ray parameters", params_bytes(pixels)),
        };
        info.check(
            format!("{what} {width}x{height} ({bytes} bytes)"),
            "maxStorageBufferRange",
            bytes,
            info.max_storage_buffer_range,
        )?;
        let local = crate::gpu::shaders::MARCH_NAIVE.local_size_with(&[]);
        record::groups_for(info, "frame", [width, height, 1], local)?;
        Ok(())
    }

    fn create(ctx: &Context, width: u32, height: u32, frame: bool, readback: bool) -> Result<Self> {
        let info = ctx.info();
        Self::check_size_for(info, width, height, frame)?;
        let pixels = width as u64 * height as u64;
        let bytes = pixels * 16;
        let buffer = |name: &str, size: u64, usage: vk::BufferUsageFlags, location: MemoryLocation| {
            Buffer::new(ctx, name, size, usage, location)
        };
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let frame = match frame {
            true => Some(buffer(
                "frame",
                bytes,
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )?),
            false => None,
        };
        let depth = buffer(
            "frame depth",
            if frame.is_some() { pixels * 4 } else { 16 },
            storage | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let params = buffer(
            "render params",
            params_bytes(pixels),
            storage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let lut = buffer(
            "frame LUT",
            (2 * crate::tf::LUT_SIZE * 16 * crate::volume::MAX_CHANNELS) as u64,
            storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let lut = TexelBuffer::new(ctx, lut, vk::Format::R32G32B32A32_SFLOAT)?;
        let status = buffer(
            "march status",
            16,
            storage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let readback = match readback {
            true => Some(buffer(
                "frame readback",
                bytes + pixels * 4,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?),
            false => None,
        };
        Ok(RenderTarget {
            width,
            height,
            frame,
            depth,
            params,
            lut,
            status,
            readback,
        })
    }

    pub(crate) fn status_buffer(&self) -> &Buffer {
        &self.status
    }

    /// How many SIMD groups of the last frame recorded on this target ran
    /// into the device's cap on a shader's loop passes, after its
    /// submission completed: 0 on a device without one
    /// (`DeviceInfo::loop_pass_limit`). More than 0 means those groups' rays
    /// may have stopped early, so the frame may not be the exact one:
    /// `Renderer::render` refuses it (`Error::LoopCap`).
    pub fn cut_groups(&self) -> Result<u32> {
        let bytes = self.status.host()?;
        Ok(bytemuck::pod_read_unaligned(&bytes[..4]))
    }

    pub(crate) fn frame_buffer(&self) -> Result<&Buffer> {
        self.frame.as_ref().ok_or_else(|| {
            Error::invalid(
                "render target",
                format!("{}x{}", self.width, self.height),
                "has no frame buffer (made by RenderTarget::for_images)",
            )
        })
    }

    pub(crate) fn readback_buffer(&self) -> Result<&Buffer> {
        self.readback.as_ref().ok_or_else(|| {
            Error::invalid(
                "render target",
                format!("{}x{}", self.width, self.height),
                "has no readback buffer (made without one)",
            )
        })
    }

    /// Reads the frame recorded by `Renderer::record_readback`, after the
    /// submission completed.
    pub fn read(&self) -> Result<Frame> {
        self.read_frame(false)
    }

    /// As `read`, with the iso frame's depth (`Frame::depth`).
    pub fn read_with_depth(&self) -> Result<Frame> {
        self.read_frame(true)
    }

    fn read_frame(&self, depth: bool) -> Result<Frame> {
        let bytes = self.readback_buffer()?.host()?;
        let n = self.width as usize * self.height as usize;
        let pixels: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..n * 16]);
        let mut frame = Frame::new(self.width, self.height, pixels);
        if depth {
            frame.depth = Some(bytemuck::pod_collect_to_vec(&bytes[n * 16..n * 20]));
        }
        Ok(frame)
    }
}

/// Bytes of a target's parameter buffer: the frame's block and a word per
/// pixel (its ray limit).
fn params_bytes(pixels: u64) -> u64 {
    std::mem::size_of::<RenderParams>() as u64 + pixels * 4
}
