//! Buffers and 3D images backed by `gpu-allocator`, with staging upload and
//! readback. Each object keeps its `Context` and frees itself on drop.

use super::record::{self, Access};
use super::{Context, DeviceInfo};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

/// Largest staging chunk for uploads and readbacks, so big volumes stream
/// through a bounded amount of host-visible memory.
const STAGING_CHUNK: u64 = 64 << 20;

pub struct Buffer {
    ctx: Context,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    name: String,
}

impl Buffer {
    /// A buffer of `size` bytes (at least 4: Vulkan has no empty buffers).
    pub fn new(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        let info = ctx.info();
        info.check(
            format!("buffer '{name}' of {size} bytes"),
            "maxMemoryAllocationSize",
            size,
            info.max_memory_allocation_size,
        )?;
        let device = ctx.device();
        let create = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.create_buffer(&create, None) }.vk("vkCreateBuffer")?;
        ctx.name_object(raw, name);
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_buffer(raw, None) };
                return Err(Error::Memory {
                    what: format!("buffer '{name}' ({size} bytes)"),
                    message: e.to_string(),
                });
            }
        };
        if let Err(result) = unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            let _ = ctx.allocator().free(allocation);
            unsafe { device.destroy_buffer(raw, None) };
            return Err(Error::Vulkan {
                call: "vkBindBufferMemory",
                result,
            });
        }
        Ok(Buffer {
            ctx: ctx.clone(),
            raw,
            allocation: Some(allocation),
            size,
            name: name.to_string(),
        })
    }

    /// A host-visible staging buffer holding `data`.
    fn staging(ctx: &Context, name: &str, data: &[u8]) -> Result<Buffer> {
        let mut staging = Buffer::new(
            ctx,
            name,
            data.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.host_mut()?[..data.len()].copy_from_slice(data);
        Ok(staging)
    }

    /// As `with_data`, recorded into `cmd` instead of submitted: the copy
    /// from a staging buffer, then a barrier making it visible to
    /// compute-shader reads (`Access::TRANSFER_WRITE -> COMPUTE_READ`).
    /// Keep the returned `Staging` until the submission completed.
    pub fn record_with_data(
        ctx: &Context,
        cmd: vk::CommandBuffer,
        name: &str,
        data: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<(Self, Staging)> {
        let buffer = Buffer::upload_target(ctx, name, data.len() as u64, usage)?;
        let staging = Buffer::staging(ctx, "staging upload", data)?;
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: data.len() as u64,
        }];
        let device = ctx.device();
        unsafe { device.cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region) };
        record::barrier(device, cmd, Access::TRANSFER_WRITE, Access::COMPUTE_READ);
        Ok((buffer, Staging(vec![staging])))
    }

    /// A device-local buffer of `usage` that copies can write.
    pub fn upload_target(ctx: &Context, name: &str, size: u64, usage: vk::BufferUsageFlags) -> Result<Self> {
        Buffer::new(
            ctx,
            name,
            size,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )
    }

    /// A device-local storage buffer filled from `data` through staging.
    pub fn with_data(ctx: &Context, name: &str, data: &[u8], usage: vk::BufferUsageFlags) -> Result<Self> {
        let buffer = Buffer::upload_target(ctx, name, data.len() as u64, usage)?;
        buffer.upload(0, data)?;
        Ok(buffer)
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice()
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut()?.mapped_slice_mut()
    }

    /// As `mapped`, an error naming the buffer when it is not host visible.
    pub fn host(&self) -> Result<&[u8]> {
        let name = &self.name;
        self.mapped()
            .ok_or_else(|| Error::Interface(format!("buffer '{name}' is not host visible")))
    }

    /// As `mapped_mut`, an error naming the buffer when it is not host visible.
    pub fn host_mut(&mut self) -> Result<&mut [u8]> {
        let name = self.name.clone();
        self.mapped_mut()
            .ok_or_else(|| Error::Interface(format!("buffer '{name}' is not host visible")))
    }

    /// Copies `data` to byte `offset` through a staging buffer and waits.
    pub fn upload(&self, offset: u64, data: &[u8]) -> Result<()> {
        let mut done = 0u64;
        while done < data.len() as u64 {
            let n = (data.len() as u64 - done).min(STAGING_CHUNK);
            let staging = Buffer::staging(&self.ctx, "staging upload", &data[done as usize..(done + n) as usize])?;
            self.ctx.submit_and_wait(|cmd| {
                let region = [vk::BufferCopy {
                    src_offset: 0,
                    dst_offset: offset + done,
                    size: n,
                }];
                unsafe { self.ctx.device().cmd_copy_buffer(cmd, staging.raw, self.raw, &region) };
                Ok(())
            })?;
            done += n;
        }
        Ok(())
    }

    /// Reads `len` bytes from byte `offset` back to the host and waits.
    /// Assumes prior GPU writes were made visible to transfer reads (a
    /// submission boundary with `submit_and_wait` does that).
    pub fn download(&self, offset: u64, len: u64) -> Result<Vec<u8>> {
        let mut out = Vec::with_capacity(len as usize);
        while (out.len() as u64) < len {
            let done = out.len() as u64;
            let n = (len - done).min(STAGING_CHUNK);
            let staging = Buffer::new(
                &self.ctx,
                "staging readback",
                n,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;
            self.ctx.submit_and_wait(|cmd| {
                let region = [vk::BufferCopy {
                    src_offset: offset + done,
                    dst_offset: 0,
                    size: n,
                }];
                let device = self.ctx.device();
                unsafe { device.cmd_copy_buffer(cmd, self.raw, staging.raw, &region) };
                record::barrier(device, cmd, Access::TRANSFER_WRITE, Access::HOST_READ);
                Ok(())
            })?;
            out.extend_from_slice(&staging.host()?[..n as usize]);
        }
        Ok(out)
    }

    /// A whole-buffer descriptor range.
    pub fn descriptor(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo {
            buffer: self.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
        unsafe { self.ctx.device().destroy_buffer(self.raw, None) };
    }
}

/// A buffer that shaders read as an array of `format` texels
/// (`samplerBuffer` in GLSL), with its view. The march kernels read the LUT
/// this way because lavapipe fetches every lane's texel with vector loads,
/// where it reads a storage buffer one lane at a time.
pub struct TexelBuffer {
    buffer: Buffer,
    view: vk::BufferView,
}

/// Bytes per texel of the formats lacuna reads as texel buffers.
fn texel_bytes(format: vk::Format) -> Option<u64> {
    match format {
        vk::Format::R32_UINT | vk::Format::R32_SFLOAT => Some(4),
        vk::Format::R32G32_UINT => Some(8),
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => Some(16),
        _ => None,
    }
}

impl TexelBuffer {
    /// Views all of `buffer`, created with `UNIFORM_TEXEL_BUFFER` usage, as
    /// texels of `format` (32-bit RGBA or single-channel formats); its size
    /// must be a whole, non-zero number of texels.
    pub fn new(ctx: &Context, buffer: Buffer, format: vk::Format) -> Result<Self> {
        let what = format!("buffer '{}' as texels of {format:?}", buffer.name);
        let bytes = texel_bytes(format)
            .ok_or_else(|| Error::Unsupported(format!("{what}: not a texel buffer format lacuna reads")))?;
        if buffer.size == 0 || !buffer.size.is_multiple_of(bytes) {
            return Err(Error::Interface(format!(
                "{what}: {} bytes is not a whole number of {bytes}-byte texels",
                buffer.size
            )));
        }
        if !ctx.reads_texel_buffers(format) {
            return Err(Error::Unsupported(format!(
                "{what}: the device cannot read {format:?} uniform texel buffers"
            )));
        }
        let texels = buffer.size / bytes;
        let info = ctx.info();
        info.check(
            what,
            "maxTexelBufferElements",
            texels,
            info.max_texel_buffer_elements as u64,
        )?;
        let create = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw)
            .format(format)
            .offset(0)
            .range(buffer.size);
        let view = unsafe { ctx.device().create_buffer_view(&create, None) }.vk("vkCreateBufferView")?;
        Ok(TexelBuffer { buffer, view })
    }

    /// The buffer (for writes as a storage buffer, copies, readback).
    pub fn buffer(&self) -> &Buffer {
        &self.buffer
    }

    /// The view a `samplerBuffer` binding takes.
    pub fn view(&self) -> vk::BufferView {
        self.view
    }
}

impl Drop for TexelBuffer {
    fn drop(&mut self) {
        // Before the buffer, which drops after this.
        unsafe { self.buffer.ctx.device().destroy_buffer_view(self.view, None) };
    }
}

/// Host-visible staging buffers a recorded upload copies from: keep them
/// until the submission that executes the copy completed (dropping them
/// earlier frees memory the GPU still reads).
#[must_use = "keep the staging until the submission that reads it completed"]
pub struct Staging(Vec<Buffer>);

impl Staging {
    /// Joins the staging of several recorded uploads.
    pub fn join(mut self, other: Staging) -> Staging {
        self.0.extend(other.0);
        self
    }
}

/// A sampled 3D image (one channel) with its view.
pub struct Image3d {
    ctx: Context,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    allocation: Option<Allocation>,
    pub format: vk::Format,
    pub extent: [u32; 3],
}

/// Checks a 3D image of `extent` texels of `texel_bytes` against
/// `maxImageDimension3D`, `maxMemoryAllocationSize` and the device-local
/// heap; returns its bytes. Loaders call it from a header, before reading voxels.
pub fn check_image3d(info: &DeviceInfo, extent: [u32; 3], texel_bytes: u64) -> Result<u64> {
    check_image3d_of(info, "volume", extent, texel_bytes)
}

/// As `check_image3d`, for an image the errors call `what` (e.g. `brick pool of ch2.nii`).
pub fn check_image3d_of(info: &DeviceInfo, what: &str, extent: [u32; 3], texel_bytes: u64) -> Result<u64> {
    let dims = format!("{what} {}x{}x{}", extent[0], extent[1], extent[2]);
    let largest = extent.iter().copied().max().unwrap_or(0) as u64;
    info.check(
        dims.clone(),
        "maxImageDimension3D",
        largest,
        info.max_image_dimension_3d as u64,
    )?;
    let bytes = extent.iter().fold(texel_bytes, |acc, &e| acc.saturating_mul(e as u64));
    info.check(
        format!("{dims} ({bytes} bytes)"),
        "maxMemoryAllocationSize",
        bytes,
        info.max_memory_allocation_size,
    )?;
    if info.device_local_bytes > 0 {
        info.check(
            format!("{dims} ({bytes} bytes)"),
            "device-local heap size",
            bytes,
            info.device_local_bytes,
        )?;
    }
    Ok(bytes)
}

impl Image3d {
    /// Creates the image and uploads `data` (tightly packed, x fastest) in
    /// z-slabs; leaves it in `SHADER_READ_ONLY_OPTIMAL`, visible to compute.
    pub fn with_data(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u64,
        data: &[u8],
    ) -> Result<Self> {
        let image = Self::create(ctx, name, format, extent, texel_bytes, data)?;
        image.upload(texel_bytes, data)?;
        Ok(image)
    }

    /// As `with_data`, the texels of slices `z .. z + n` written by
    /// `fill(z, n, out)` straight into each staging chunk: the host never
    /// holds the whole image (a brick pool made from its bricks).
    pub fn with_slices(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u64,
        fill: impl Fn(u32, u32, &mut [u8]),
    ) -> Result<Self> {
        let image = Self::create_empty(ctx, name, format, extent, texel_bytes)?;
        let [w, h, d] = extent;
        let slice_bytes = (w as u64 * h as u64 * texel_bytes).max(1);
        let slices_per_chunk = (STAGING_CHUNK / slice_bytes).max(1) as u32;
        let mut z = 0u32;
        while z < d {
            let n = slices_per_chunk.min(d - z);
            let mut staging = Buffer::new(
                ctx,
                "staging volume",
                n as u64 * slice_bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?;
            fill(z, n, &mut staging.host_mut()?[..(n as u64 * slice_bytes) as usize]);
            ctx.submit_and_wait(|cmd| {
                image.record_copy(cmd, &staging, z, n, z == 0, z + n == d);
                Ok(())
            })?;
            z += n;
        }
        Ok(image)
    }

    /// As `with_data`, recorded into `cmd` instead of submitted: one copy from
    /// a staging buffer, leaving the image in `SHADER_READ_ONLY_OPTIMAL` with
    /// a barrier to compute-shader reads. Keep the returned `Staging` until
    /// the submission completed.
    pub fn record_with_data(
        ctx: &Context,
        cmd: vk::CommandBuffer,
        name: &str,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u64,
        data: &[u8],
    ) -> Result<(Self, Staging)> {
        let image = Self::create(ctx, name, format, extent, texel_bytes, data)?;
        let staging = Buffer::staging(ctx, "staging volume", data)?;
        image.record_copy(cmd, &staging, 0, extent[2], true, true);
        Ok((image, Staging(vec![staging])))
    }

    /// The image and its view, after the limit checks; no contents yet.
    fn create(
        ctx: &Context,
        name: &str,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u64,
        data: &[u8],
    ) -> Result<Self> {
        let bytes = check_image3d(ctx.info(), extent, texel_bytes)?;
        if bytes != data.len() as u64 {
            return Err(Error::invalid(
                "image data",
                format!("{} bytes", data.len()),
                format!(
                    "volume {}x{}x{} of {texel_bytes}-byte texels needs {bytes}",
                    extent[0], extent[1], extent[2]
                ),
            ));
        }
        Self::create_empty(ctx, name, format, extent, texel_bytes)
    }

    /// The image and its view, after the limit checks; no contents yet.
    fn create_empty(ctx: &Context, name: &str, format: vk::Format, extent: [u32; 3], texel_bytes: u64) -> Result<Self> {
        let info = ctx.info();
        let dims = format!("volume {}x{}x{}", extent[0], extent[1], extent[2]);
        let bytes = check_image3d(info, extent, texel_bytes)?;
        let device = ctx.device();
        let create = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_3D)
            .format(format)
            .extent(vk::Extent3D {
                width: extent[0],
                height: extent[1],
                depth: extent[2],
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { device.create_image(&create, None) }.vk("vkCreateImage")?;
        ctx.name_object(raw, name);
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = match ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_image(raw, None) };
                return Err(Error::Memory {
                    what: format!("{dims} ({bytes} bytes)"),
                    message: e.to_string(),
                });
            }
        };
        let mut image = Image3d {
            ctx: ctx.clone(),
            raw,
            view: vk::ImageView::null(),
            allocation: Some(allocation),
            format,
            extent,
        };
        if let Some(a) = image.allocation.as_ref() {
            unsafe { device.bind_image_memory(raw, a.memory(), a.offset()) }.vk("vkBindImageMemory")?;
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_3D)
            .format(format)
            .subresource_range(record::COLOR_RANGE);
        image.view = unsafe { device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
        Ok(image)
    }

    fn upload(&self, texel_bytes: u64, data: &[u8]) -> Result<()> {
        let [w, h, d] = self.extent;
        let slice_bytes = (w as u64 * h as u64 * texel_bytes).max(1);
        let slices_per_chunk = (STAGING_CHUNK / slice_bytes).max(1) as u32;
        let mut z = 0u32;
        while z < d {
            let n = slices_per_chunk.min(d - z);
            let start = (z as u64 * slice_bytes) as usize;
            let len = (n as u64 * slice_bytes) as usize;
            let staging = Buffer::staging(&self.ctx, "staging volume", &data[start..start + len])?;
            self.ctx.submit_and_wait(|cmd| {
                self.record_copy(cmd, &staging, z, n, z == 0, z + n == d);
                Ok(())
            })?;
            z += n;
        }
        Ok(())
    }
}

impl Image3d {
    /// Records the copy of slices `z .. z + n` from `staging`: the transition
    /// to TRANSFER_DST first (from UNDEFINED when `first`), and to
    /// SHADER_READ_ONLY_OPTIMAL for compute reads after the `last`.
    fn record_copy(&self, cmd: vk::CommandBuffer, staging: &Buffer, z: u32, n: u32, first: bool, last: bool) {
        let device = self.ctx.device();
        let [w, h, _] = self.extent;
        let (old, src) = if first {
            (vk::ImageLayout::UNDEFINED, Access::NONE)
        } else {
            (vk::ImageLayout::TRANSFER_DST_OPTIMAL, Access::TRANSFER_WRITE)
        };
        let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
        record::image_barrier(device, cmd, self.raw, old, dst, src, Access::TRANSFER_WRITE);
        let region = [vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_offset(vk::Offset3D {
                x: 0,
                y: 0,
                z: z as i32,
            })
            .image_extent(vk::Extent3D {
                width: w,
                height: h,
                depth: n,
            })];
        unsafe { device.cmd_copy_buffer_to_image(cmd, staging.raw, self.raw, dst, &region) };
        if last {
            let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
            record::image_barrier(
                device,
                cmd,
                self.raw,
                dst,
                read,
                Access::TRANSFER_WRITE,
                Access::COMPUTE_READ,
            );
        }
    }
}

impl Drop for Image3d {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe { device.destroy_image_view(self.view, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
        unsafe { device.destroy_image(self.raw, None) };
    }
}
