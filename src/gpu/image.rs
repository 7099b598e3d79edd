//! Sampled 3D images (the volume, its gradient, brick pools) backed by
//! `gpu-allocator`, uploaded through staging in z-slabs.

use super::memory::{copy_to_mapped, Buffer, Staging, STAGING_CHUNK};
use super::record::Recording;
use super::record::{self, Access};
use super::retire::Retired;
use super::{Context, DeviceInfo};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

/// A sampled 3D image (one channel) with its view.
pub struct Image3d {
    ctx: Context,
    pub(crate) raw: vk::Image,
    pub(crate) view: vk::ImageView,
    allocation: Option<Allocation>,
    pub(crate) format: vk::Format,
    pub(crate) extent: [u32; 3],
    /// Bytes a texel of `format` takes in the uploads' data.
    texel_bytes: u64,
}

/// Checks a 3D image of `extent` texels of `texel_bytes` against
/// `maxImageDimension3D`, `maxMemoryAllocationSize` and the device-local
/// heap; returns its bytes. Loaders call it from a header, before reading voxels.
pub fn check_image3d(info: &DeviceInfo, extent: [u32; 3], texel_bytes: u64) -> Result<u64> {
    check_image3d_of(info, "volume", extent, texel_bytes)
}

/// Bytes per texel of the 3D image formats lacuna makes (None: another).
fn format_texel_bytes(format: vk::Format) -> Option<u64> {
    use vk::Format as F;
    Some(match format {
        F::R8_UNORM => 1,
        F::R8G8_UNORM | F::R16_UNORM | F::R16_SFLOAT => 2,
        F::R8G8B8A8_UNORM | F::R16G16_UNORM | F::R16G16_SFLOAT | F::R32_SFLOAT | F::R32_UINT => 4,
        F::R16G16B16A16_UNORM | F::R16G16B16A16_SFLOAT | F::R32G32_SFLOAT | F::R32G32_UINT => 8,
        F::R32G32B32A32_SFLOAT | F::R32G32B32A32_UINT => 16,
        _ => return None,
    })
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
        image.upload(data)?;
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
                image.record_copy(cmd, &staging, z, n, z == 0, z + n == d)?;
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
        cmd: Recording<'_>,
        name: &str,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u64,
        data: &[u8],
    ) -> Result<(Self, Staging)> {
        let ctx = cmd.context();
        let image = Self::create(ctx, name, format, extent, texel_bytes, data)?;
        let staging = Buffer::staging(ctx, "staging volume", data)?;
        image.record_copy(cmd, &staging, 0, extent[2], true, true)?;
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
        if extent.contains(&0) {
            return Err(Error::invalid("image extent", dims, "every side needs a texel"));
        }
        if format_texel_bytes(format) != Some(texel_bytes) {
            return Err(Error::invalid(
                "image texels",
                format!("{texel_bytes} bytes of {format:?}"),
                "must be the format's texel size (R, RG or RGBA of 8/16-bit unorm, 16/32-bit float, 32-bit uint)",
            ));
        }
        let bytes = check_image3d(info, extent, texel_bytes)?;
        // Sampling 16-bit unorm formats, for one, is optional in Vulkan.
        let needed = vk::FormatFeatureFlags::SAMPLED_IMAGE | vk::FormatFeatureFlags::TRANSFER_DST;
        if !ctx.format_properties(format).optimal_tiling_features.contains(needed) {
            return Err(Error::Unsupported(format!(
                "{dims}: this device cannot sample images of format {format:?} (no SAMPLED_IMAGE and TRANSFER_DST in its optimal-tiling features)"
            )));
        }
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
            texel_bytes,
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

    /// Writes `data` (texels of the size the image was made with) over
    /// every texel (as `with_data`) and waits. Compute-shader reads before
    /// are ordered first; none may be pending.
    pub(crate) fn upload(&self, data: &[u8]) -> Result<()> {
        self.upload_through(data, &mut None)
    }

    /// As `upload`, through `staging`: a host-visible buffer kept by the
    /// caller from an earlier upload, made (or made larger) here where it
    /// is None or smaller than a chunk of `data`. A series' steps then
    /// write into memory already faulted in: a new 16 MB staging buffer
    /// cost nbody:256's step 8 to 12 ms on lavapipe, most of it the first
    /// touch of its pages.
    pub(crate) fn upload_through(&self, data: &[u8], staging: &mut Option<Buffer>) -> Result<()> {
        let [w, h, d] = self.extent;
        let texel_bytes = self.texel_bytes;
        if w as u64 * h as u64 * d as u64 * texel_bytes != data.len() as u64 {
            return Err(Error::Interface(format!(
                "{} bytes for image {w}x{h}x{d} of {texel_bytes}-byte texels",
                data.len()
            )));
        }
        let slice_bytes = (w as u64 * h as u64 * texel_bytes).max(1);
        let slices_per_chunk = (STAGING_CHUNK / slice_bytes).max(1) as u32;
        let chunk = slices_per_chunk.min(d) as u64 * slice_bytes;
        let buffer = staging_of(&self.ctx, staging, chunk)?;
        let mut z = 0u32;
        while z < d {
            let n = slices_per_chunk.min(d - z);
            let start = (z as u64 * slice_bytes) as usize;
            let len = (n as u64 * slice_bytes) as usize;
            copy_to_mapped(&mut buffer.host_mut()?[..len], &data[start..start + len]);
            self.ctx
                .submit_and_wait(|cmd| self.record_copy(cmd, buffer, z, n, z == 0, z + n == d))?;
            z += n;
        }
        Ok(())
    }
}

/// The staging buffer `kept`, made (or made larger) where it is None or
/// smaller than `bytes`.
fn staging_of<'a>(ctx: &Context, kept: &'a mut Option<Buffer>, bytes: u64) -> Result<&'a mut Buffer> {
    Ok(match kept.take() {
        Some(k) if k.size() >= bytes => kept.insert(k),
        small => {
            // Freed before the larger one is made.
            drop(small);
            kept.insert(Buffer::new(
                ctx,
                "staging volume",
                bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?)
        }
    })
}

/// A box of texels: its low corner and extent.
pub type TexelBox = ([u32; 3], [u32; 3]);

/// The copy of texel box `b` of the image's colour from `offset` in a
/// buffer, its rows tightly packed.
fn copy_region(offset: u64, ([x, y, z], [w, h, d]): TexelBox) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_offset(vk::Offset3D {
            x: x as i32,
            y: y as i32,
            z: z as i32,
        })
        .image_extent(vk::Extent3D {
            width: w,
            height: h,
            depth: d,
        })
}

impl Image3d {
    /// The image, to bind or barrier in the caller's own commands; the
    /// `Image3d` still owns it.
    pub fn raw(&self) -> vk::Image {
        self.raw
    }

    /// Its view of the whole image.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }

    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Texels along x, y and z.
    pub fn extent(&self) -> [u32; 3] {
        self.extent
    }

    /// Whether the image's texels fit one staging buffer, as
    /// `upload_mirrored` takes them.
    pub(crate) fn mirrorable(&self) -> bool {
        self.extent.iter().map(|&n| n as u64).product::<u64>() * self.texel_bytes <= STAGING_CHUNK
    }

    /// Writes `data` (every texel, as `upload`) through `mirror`: a
    /// host-visible buffer that holds every texel as the last upload
    /// through it left them (None: made here). Where `update` is given and
    /// the mirror was there, `update` rewrites in the mapped texels only
    /// what changed since (the caller vouches for it); else all of `data`
    /// is copied in. The image's copy from the mirror is then submitted,
    /// `meanwhile` runs on the host while the device copies (a series
    /// step's cells copy), and the call waits. The image must fit one
    /// staging buffer (`mirrorable`), and no submission reading it may be
    /// pending; it is written whole (its texels before are not read).
    pub(crate) fn upload_mirrored<T>(
        &self,
        data: &[u8],
        mirror: &mut Option<Buffer>,
        update: Option<impl FnOnce(&mut [u8])>,
        meanwhile: impl FnOnce() -> Result<T>,
    ) -> Result<T> {
        let [w, h, d] = self.extent;
        let bytes = w as u64 * h as u64 * d as u64 * self.texel_bytes;
        if bytes != data.len() as u64 || !self.mirrorable() {
            return Err(Error::Interface(format!(
                "{} bytes for image {w}x{h}x{d} of {}-byte texels, mirrored in one staging buffer",
                data.len(),
                self.texel_bytes
            )));
        }
        // Out of `mirror` until the copy is done: after an error it is
        // None, never a buffer holding other texels than the image's.
        let mut taken = mirror.take();
        let kept = taken.as_ref().is_some_and(|m| m.size() >= bytes);
        let buffer = staging_of(&self.ctx, &mut taken, bytes)?;
        let mapped = &mut buffer.host_mut()?[..bytes as usize];
        match update {
            Some(update) if kept => update(mapped),
            _ => copy_to_mapped(mapped, data),
        }
        let buffer = &*buffer;
        // The whole image from the mirror: from UNDEFINED, as every texel
        // is written.
        let record = |cmd: Recording<'_>| self.record_copy(cmd, buffer, 0, d, true, true);
        let ((), value) = self.ctx.submit_while(record, meanwhile)?;
        *mirror = taken;
        Ok(value)
    }

    /// Writes the texels of `boxes` from `data` (every texel of the image,
    /// x fastest, as `upload` takes them) and leaves the others as they
    /// are, through `staging` (as `upload_through`), and waits: a series
    /// step that changed in places. The image must hold texels already
    /// (an upload before), and no submission reading it may be pending.
    pub(crate) fn upload_boxes_through(
        &self,
        data: &[u8],
        boxes: &[TexelBox],
        staging: &mut Option<Buffer>,
    ) -> Result<()> {
        let [w, h, d] = self.extent.map(|n| n as usize);
        let tb = self.texel_bytes as usize;
        if w * h * d * tb != data.len()
            || boxes
                .iter()
                .any(|(lo, n)| (0..3).any(|a| lo[a] + n[a] > self.extent[a]))
        {
            return Err(Error::Interface(format!(
                "{} bytes or boxes past image {w}x{h}x{d} of {tb}-byte texels",
                data.len()
            )));
        }
        // Offsets kept at multiples of 16 bytes (any texel size divides it).
        let box_bytes =
            |(_, n): &TexelBox| (n.iter().map(|&k| k as u64).product::<u64>() * tb as u64).next_multiple_of(16);
        let mut at = 0;
        while at < boxes.len() {
            // As many boxes as fit a chunk (one at least).
            let mut end = at;
            let mut bytes = 0;
            while end < boxes.len() && (end == at || bytes + box_bytes(&boxes[end]) <= STAGING_CHUNK) {
                bytes += box_bytes(&boxes[end]);
                end += 1;
            }
            let buffer = staging_of(&self.ctx, staging, bytes)?;
            let mapped = buffer.host_mut()?;
            let mut regions = Vec::with_capacity(end - at);
            let mut offset = 0usize;
            for b in &boxes[at..end] {
                let ([x, y, z], [nx, ny, nz]) = (b.0.map(|k| k as usize), b.1.map(|k| k as usize));
                let row = nx * tb;
                for k in 0..nz {
                    for j in 0..ny {
                        let src = ((x + w * (y + j + h * (z + k))) * tb)..;
                        let dst = offset + (j + ny * k) * row;
                        copy_to_mapped(&mut mapped[dst..dst + row], &data[src][..row]);
                    }
                }
                regions.push(copy_region(offset as u64, *b));
                offset += box_bytes(b) as usize;
            }
            let (read, dst) = (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            );
            self.ctx.submit_and_wait(|cmd| {
                self.transition(cmd, read, dst, Access::COMPUTE_READ, Access::TRANSFER_WRITE);
                self.record_from(cmd, buffer, &regions)?;
                self.record_readable(cmd);
                Ok(())
            })?;
            at = end;
        }
        Ok(())
    }

    /// Records the copy of slices `z .. z + n` from `staging`: the transition
    /// to TRANSFER_DST first (from UNDEFINED when `first`), and to
    /// SHADER_READ_ONLY_OPTIMAL for compute reads after the `last`.
    fn record_copy(&self, cmd: Recording<'_>, staging: &Buffer, z: u32, n: u32, first: bool, last: bool) -> Result<()> {
        let [w, h, _] = self.extent;
        let (old, src) = if first {
            (vk::ImageLayout::UNDEFINED, Access::COMPUTE_READ)
        } else {
            (vk::ImageLayout::TRANSFER_DST_OPTIMAL, Access::TRANSFER_WRITE)
        };
        let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
        self.transition(cmd, old, dst, src, Access::TRANSFER_WRITE);
        self.record_from(cmd, staging, &[copy_region(0, ([0, 0, z], [w, h, n]))])?;
        if last {
            self.record_readable(cmd);
        }
        Ok(())
    }

    /// Records copies of `regions` from `buffer` (noted as read: the host
    /// may not write it until the submission settles) into this image, in
    /// TRANSFER_DST_OPTIMAL.
    fn record_from(&self, cmd: Recording<'_>, buffer: &Buffer, regions: &[vk::BufferImageCopy]) -> Result<()> {
        buffer.used_by(cmd)?;
        let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
        // SAFETY: the buffer and image are this device's and alive for the
        // call; callers keep the regions within both.
        unsafe {
            self.ctx
                .device()
                .cmd_copy_buffer_to_image(cmd.raw(), buffer.raw, self.raw, dst, regions)
        };
        Ok(())
    }

    /// Records a layout transition of this image.
    fn transition(&self, cmd: Recording<'_>, old: vk::ImageLayout, new: vk::ImageLayout, src: Access, dst: Access) {
        // SAFETY: the image is this context's, alive while `self` is, with
        // one level and layer; callers name the layout it is in.
        unsafe { cmd.image_barrier(self.raw, old, new, src, dst) };
    }

    /// Records the transition from the copies' TRANSFER_DST_OPTIMAL to
    /// SHADER_READ_ONLY_OPTIMAL for compute reads.
    fn record_readable(&self, cmd: Recording<'_>) {
        let (dst, read) = (
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        );
        self.transition(cmd, dst, read, Access::TRANSFER_WRITE, Access::COMPUTE_READ);
    }
}

impl Drop for Image3d {
    fn drop(&mut self) {
        self.ctx
            .retire([Retired::Image(self.raw, self.view, self.allocation.take())]);
    }
}
