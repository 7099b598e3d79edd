//! Buffers and 3D images backed by `gpu-allocator`, with staging upload and
//! readback. Each object keeps its `Context` and frees itself on drop.

use super::host_read::{lock, HostAccess, HostRead};
use super::record::{Access, Recording};
use super::retire::Retired;
use super::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Mutex;

/// Largest staging chunk for uploads and readbacks, so big volumes stream
/// through a bounded amount of host-visible memory.
pub(super) const STAGING_CHUNK: u64 = 64 << 20;

/// Copies at or above this size are split across the host's threads.
const PARALLEL_COPY: usize = 4 << 20;

/// `dst.copy_from_slice(src)`, split over the host's threads for large
/// copies: one thread fills mapped memory well below what the memory
/// system takes (a volume step into staging, each step of a series). Own
/// scoped threads rather than rayon's pool, where a series' next step may
/// be generating while this one uploads (`view`).
pub(crate) fn copy_to_mapped(dst: &mut [u8], src: &[u8]) {
    assert_eq!(dst.len(), src.len(), "copy_to_mapped: lengths differ");
    // At most 16 threads, each at least 1 MiB: the split that took a 16 MiB
    // step from 3.7 to 2.5 ms on a 16-core host (docs/results/h100.md).
    let host = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = host.min(16).min(src.len() >> 20);
    if src.len() < PARALLEL_COPY || threads < 2 {
        dst.copy_from_slice(src);
        return;
    }
    let part = src.len().div_ceil(threads);
    std::thread::scope(|scope| {
        for (d, s) in dst.chunks_mut(part).zip(src.chunks(part)) {
            scope.spawn(move || d.copy_from_slice(s));
        }
    });
}

/// A Vulkan buffer and its memory, freed on drop.
pub struct Buffer {
    ctx: Context,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    usage: vk::BufferUsageFlags,
    name: String,
    /// Who holds its mapped bytes: the host's readers, and lacuna's
    /// submissions that record device writes into it. Never both.
    host_access: Mutex<HostAccess>,
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
        // Only what lacuna binds and copies: no feature-gated usage.
        let known = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::UNIFORM_BUFFER
            | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
            | vk::BufferUsageFlags::STORAGE_TEXEL_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        if usage.is_empty() || !known.contains(usage) {
            return Err(Error::invalid(
                "buffer usage",
                format!("{usage:?}"),
                format!("buffer '{name}': storage, uniform, texel or transfer usage, at least one"),
            ));
        }
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
            usage,
            name: name.to_string(),
            host_access: Mutex::default(),
        })
    }

    /// A host-visible staging buffer holding `data`.
    pub(super) fn staging(ctx: &Context, name: &str, data: &[u8]) -> Result<Buffer> {
        Buffer::host_written(ctx, name, data, vk::BufferUsageFlags::TRANSFER_SRC)
    }

    /// A host-visible (and coherent) buffer of `usage` holding `data`,
    /// written through its mapping: nothing is recorded or submitted, and a
    /// later submission sees the write. For small buffers the device reads
    /// little of; others belong in device memory (`with_data`).
    pub fn host_written(ctx: &Context, name: &str, data: &[u8], usage: vk::BufferUsageFlags) -> Result<Buffer> {
        let mut buffer = Buffer::new(ctx, name, data.len() as u64, usage, MemoryLocation::CpuToGpu)?;
        copy_to_mapped(&mut buffer.host_mut()?[..data.len()], data);
        Ok(buffer)
    }

    /// As `with_data`, recorded into `cmd` instead of submitted: the copy
    /// from a staging buffer, then a barrier making it visible to
    /// compute-shader reads (`Access::TRANSFER_WRITE -> COMPUTE_READ`).
    /// Keep the returned `Staging` until the submission completed.
    pub fn record_with_data(
        cmd: Recording<'_>,
        name: &str,
        data: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<(Self, Staging)> {
        let ctx = cmd.context();
        let buffer = Buffer::upload_target(ctx, name, data.len() as u64, usage)?;
        let staging = Buffer::staging(ctx, "staging upload", data)?;
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: data.len() as u64,
        }];
        cmd.copy_buffer(&staging, &buffer, &region)?;
        cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ);
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

    /// The handle, to bind or barrier in the caller's own commands; the
    /// buffer still owns it.
    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// The context it was made on.
    pub fn context(&self) -> &Context {
        &self.ctx
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Whether the host sees its memory, coherently: the device's writes,
    /// once a barrier to host reads and a wait made them available, read
    /// with no invalidate.
    pub fn is_host_coherent(&self) -> bool {
        self.allocation.as_ref().is_some_and(|a| {
            a.mapped_ptr().is_some() && a.memory_properties().contains(vk::MemoryPropertyFlags::HOST_COHERENT)
        })
    }

    /// Its mapped bytes, read on the host. An error naming the buffer when
    /// it is not host visible, or while one of lacuna's submissions that
    /// writes it is recorded or running (read after `submit_and_wait`
    /// returns); while the `HostRead` lives, recording a device write into
    /// it is an error. A submission whose wait failed (a lost device) never
    /// settles: what it wrote stays refused.
    pub fn host(&self) -> Result<HostRead<'_>> {
        let bytes = self.mapped_bytes()?;
        if !lock(&self.host_access).start_read() {
            return Err(self.in_flight("read on the host", "writes"));
        }
        Ok(HostRead::counted(bytes, &self.host_access))
    }

    /// Its mapped bytes, to write on the host: an error naming the buffer
    /// when it is not host visible, or while one of lacuna's submissions
    /// that reads or writes it is recorded or running.
    pub fn host_mut(&mut self) -> Result<&mut [u8]> {
        if !self
            .host_access
            .get_mut()
            .unwrap_or_else(|p| p.into_inner())
            .start_write()
        {
            return Err(self.in_flight("written on the host", "reads or writes"));
        }
        let name = &self.name;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::Interface(format!("buffer '{name}' is not host visible")))
    }

    fn mapped_bytes(&self) -> Result<&[u8]> {
        let name = &self.name;
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| Error::Interface(format!("buffer '{name}' is not host visible")))
    }

    fn in_flight(&self, what: &str, uses: &str) -> Error {
        Error::invalid(
            "host access",
            format!("buffer '{}' {what}", self.name),
            format!("a submission that {uses} it has not completed: access it after submit_and_wait returns"),
        )
    }

    /// Notes that `cmd` records a device write into it: an error while a
    /// `HostRead` of it lives; until lacuna's submission settles, host
    /// reads and writes are errors. (A host's adopted command buffer is the
    /// host's to wait for: `Recording::adopt`.) Memory the host cannot map
    /// needs no note.
    pub(crate) fn written_by(&self, cmd: Recording<'_>) -> Result<()> {
        self.note_use(cmd, true)
    }

    /// Notes that `cmd` records a device read of it: until lacuna's
    /// submission settles, host writes are errors.
    pub(crate) fn used_by(&self, cmd: Recording<'_>) -> Result<()> {
        self.note_use(cmd, false)
    }

    fn note_use(&self, cmd: Recording<'_>, writes: bool) -> Result<()> {
        if self.allocation.as_ref().is_none_or(|a| a.mapped_ptr().is_none()) {
            return Ok(());
        }
        match lock(&self.host_access).note(cmd.completion(), writes) {
            true => Ok(()),
            false => Err(Error::invalid(
                "device write",
                format!("into buffer '{}'", self.name),
                "the host is reading it (a HostRead is alive): drop that first",
            )),
        }
    }

    /// Bytes `[offset, offset + len)`, or an error naming the buffer when
    /// it does not hold them.
    fn check_range(&self, offset: u64, len: u64) -> Result<()> {
        match self.holds(offset, len) {
            true => Ok(()),
            false => Err(Error::invalid(
                "buffer range",
                format!("{len} bytes at {offset}"),
                format!("buffer '{}' holds {} bytes", self.name, self.size),
            )),
        }
    }

    /// Copies `data` to byte `offset` through a staging buffer and waits.
    pub fn upload(&self, offset: u64, data: &[u8]) -> Result<()> {
        self.check_range(offset, data.len() as u64)?;
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
                cmd.copy_buffer(&staging, self, &region)
            })?;
            done += n;
        }
        Ok(())
    }

    /// Reads `len` bytes from byte `offset` back to the host and waits.
    /// Assumes prior GPU writes were made visible to transfer reads (a
    /// submission boundary with `submit_and_wait` does that).
    pub fn download(&self, offset: u64, len: u64) -> Result<Vec<u8>> {
        // Within the buffer: no larger than memory the device holds.
        self.check_range(offset, len)?;
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
                cmd.copy_buffer(self, &staging, &region)?;
                cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
                Ok(())
            })?;
            out.extend_from_slice(&staging.host()?[..n as usize]);
        }
        Ok(out)
    }

    /// Whether `len` bytes from `offset` lie within it.
    pub(crate) fn holds(&self, offset: u64, len: u64) -> bool {
        offset.checked_add(len).is_some_and(|end| end <= self.size)
    }

    /// The usage it was made with.
    pub fn usage(&self) -> vk::BufferUsageFlags {
        self.usage
    }

    /// An error unless it was made with `usage` (to be `what`).
    pub(crate) fn check_usage(&self, usage: vk::BufferUsageFlags, what: &str) -> Result<()> {
        match self.usage.contains(usage) {
            true => Ok(()),
            false => Err(Error::Interface(format!(
                "buffer '{}' {what}: it was made without {usage:?} usage",
                self.name
            ))),
        }
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
        self.ctx.retire([Retired::Buffer(self.raw, self.allocation.take())]);
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
        ctx.check_is(&buffer.ctx, "texel buffer's buffer")?;
        if !buffer.usage.contains(vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER) {
            return Err(Error::Interface(format!(
                "{what}: it was made without UNIFORM_TEXEL_BUFFER usage"
            )));
        }
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

    /// The mapped bytes of a host-visible buffer, to write in place.
    pub fn host_mut(&mut self) -> Result<&mut [u8]> {
        self.buffer.host_mut()
    }

    /// The view a `samplerBuffer` binding takes.
    pub fn view(&self) -> vk::BufferView {
        self.view
    }
}

impl Drop for TexelBuffer {
    fn drop(&mut self) {
        // Before the buffer, which drops after this.
        self.buffer.ctx.retire([Retired::BufferView(self.view)]);
    }
}

/// Host-visible staging buffers a recorded upload copies from: keep them
/// until the submission that executes the copy completed (dropping them
/// earlier frees memory the GPU still reads).
#[must_use = "keep the staging until the submission that reads it completed"]
pub struct Staging(pub(super) Vec<Buffer>);

impl Staging {
    /// Joins the staging of several recorded uploads.
    pub fn join(mut self, other: Staging) -> Staging {
        self.0.extend(other.0);
        self
    }
}

/// Copies and fills of lacuna's buffers, checked before they are recorded.
impl Recording<'_> {
    /// Records copies between two buffers of this context (TRANSFER_SRC
    /// and TRANSFER_DST usage), each region non-empty and within both, and
    /// not overlapping itself within one buffer (an error names the first
    /// that is not).
    pub fn copy_buffer(self, src: &Buffer, dst: &Buffer, regions: &[vk::BufferCopy]) -> Result<()> {
        self.context().check_is(src.context(), "copied buffer")?;
        self.context().check_is(dst.context(), "copied-to buffer")?;
        src.check_usage(vk::BufferUsageFlags::TRANSFER_SRC, "copied from")?;
        dst.check_usage(vk::BufferUsageFlags::TRANSFER_DST, "copied to")?;
        for r in regions {
            let overlaps = src.raw == dst.raw
                && r.src_offset < r.dst_offset.saturating_add(r.size)
                && r.dst_offset < r.src_offset.saturating_add(r.size);
            if r.size == 0 || !src.holds(r.src_offset, r.size) || !dst.holds(r.dst_offset, r.size) || overlaps {
                return Err(Error::invalid(
                    "buffer copy",
                    format!("{} bytes from {} to {}", r.size, r.src_offset, r.dst_offset),
                    format!("the buffers hold {} and {} bytes", src.size(), dst.size()),
                ));
            }
        }
        src.used_by(self)?;
        dst.written_by(self)?;
        // SAFETY: both buffers are this device's and alive for the call; the
        // regions lie within them.
        unsafe {
            self.context()
                .device()
                .cmd_copy_buffer(self.raw(), src.raw, dst.raw, regions)
        };
        Ok(())
    }

    /// Records a fill of `buffer` (of this context, TRANSFER_DST usage)
    /// from `offset` on with `value` (`vk::WHOLE_SIZE`: to its end),
    /// checked to be whole words within it.
    pub fn fill_buffer(self, buffer: &Buffer, offset: u64, size: u64, value: u32) -> Result<()> {
        self.context().check_is(buffer.context(), "filled buffer")?;
        buffer.check_usage(vk::BufferUsageFlags::TRANSFER_DST, "filled")?;
        let within = size == vk::WHOLE_SIZE || (size > 0 && size.is_multiple_of(4) && buffer.holds(offset, size));
        if !within || offset >= buffer.size() || !offset.is_multiple_of(4) {
            return Err(Error::invalid(
                "buffer fill",
                format!("{size} bytes from {offset}"),
                format!("the buffer holds {} bytes", buffer.size()),
            ));
        }
        buffer.written_by(self)?;
        // SAFETY: the buffer is this device's and alive for the call; the
        // range lies within it.
        unsafe {
            self.context()
                .device()
                .cmd_fill_buffer(self.raw(), buffer.raw, offset, size, value)
        };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parallel_copy_lands_every_byte_in_place() {
        // Above the parallel threshold, with a last piece shorter than the rest.
        let n = PARALLEL_COPY + (3 << 20) + 12345;
        let src: Vec<u8> = (0..n).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
        let mut dst = vec![0u8; n];
        copy_to_mapped(&mut dst, &src);
        assert!(dst == src, "a byte of the parallel copy differs");
        let mut small = vec![0u8; 100];
        copy_to_mapped(&mut small, &src[..100]);
        assert_eq!(small, src[..100]);
    }
}
