//! Where a frame goes: lacuna's per-size buffers (`RenderTarget`), and the
//! host's images a frame can be written to (`HostImage`).

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::gpu::record;
use crate::gpu::shaders::blocks::RenderParams;
use crate::gpu::{vk, Buffer, Context, MemoryLocation, TexelBuffer};

/// The per-frame-size buffers of a frame: its parameter block (with the
/// per-pixel depth limits after it), the frame's LUT (corrected for its
/// step, then raw: `glsl/common/tf.glsl`), and, when the frame goes to a
/// buffer, the RGBA f32 frame buffer and optionally a host-visible readback.
pub struct RenderTarget {
    pub width: u32,
    pub height: u32,
    /// RGBA f32 premultiplied, row-major; None for a target of host images.
    pub frame: Option<Buffer>,
    pub params: Buffer,
    pub lut: TexelBuffer,
    readback: Option<Buffer>,
}

/// A host's 2D storage image a frame is written to: premultiplied RGBA,
/// `R8G8B8A8_UNORM`, `R16G16B16A16_SFLOAT` or `R32G32B32A32_SFLOAT`, created
/// with `STORAGE` usage, in `layout` (GENERAL, the layout storage writes need)
/// when the frame's commands execute.
#[derive(Clone, Copy, Debug)]
pub struct HostImage {
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub layout: vk::ImageLayout,
    pub width: u32,
    pub height: u32,
}

/// The frame's destination.
#[derive(Clone, Copy, Debug)]
pub enum Output {
    /// The target's own frame buffer.
    Buffer,
    Image(HostImage),
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

    fn create(ctx: &Context, width: u32, height: u32, frame: bool, readback: bool) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "size",
                format!("{width}x{height}"),
                "width and height must be > 0",
            ));
        }
        let info = ctx.info();
        let pixels = width as u64 * height as u64;
        let bytes = pixels * 16;
        info.check(
            format!("frame {width}x{height} ({bytes} bytes)"),
            "maxStorageBufferRange",
            bytes,
            info.max_storage_buffer_range,
        )?;
        let local = crate::gpu::shaders::MARCH_NAIVE.local_size_with(&[]);
        record::groups_for(info, "frame", [width, height, 1], local)?;
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
        let params = buffer(
            "render params",
            std::mem::size_of::<RenderParams>() as u64 + pixels * 4,
            storage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let lut = buffer(
            "frame LUT",
            (2 * crate::tf::LUT_SIZE * 16) as u64,
            storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let lut = TexelBuffer::new(ctx, lut, vk::Format::R32G32B32A32_SFLOAT)?;
        let readback = match readback {
            true => Some(buffer(
                "frame readback",
                bytes,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?),
            false => None,
        };
        Ok(RenderTarget {
            width,
            height,
            frame,
            params,
            lut,
            readback,
        })
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
        let bytes = self.readback_buffer()?.host()?;
        let n = self.width as usize * self.height as usize;
        let pixels: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..n * 16]);
        Ok(Frame::new(self.width, self.height, pixels))
    }
}
