//! The host engine's own Vulkan objects (not lacuna's): 2D images with their
//! memory and views, layout transitions, and image readback. Raw `ash`, as an
//! engine has it; `tests/integration/embed.rs` and `tests/integration/host_render.rs` use it too.
#![allow(dead_code)]

use lacuna::ash::{self, vk};

/// A 2D image with its own memory and a view of `aspect`.
pub struct Image2d {
    pub image: vk::Image,
    pub memory: vk::DeviceMemory,
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub aspect: vk::ImageAspectFlags,
    pub width: u32,
    pub height: u32,
}

/// A memory type of `bits` with `flags`.
pub fn memory_type(instance: &ash::Instance, pd: vk::PhysicalDevice, bits: u32, flags: vk::MemoryPropertyFlags) -> u32 {
    let props = unsafe { instance.get_physical_device_memory_properties(pd) };
    (0..props.memory_type_count)
        .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(flags))
        .expect("a matching memory type")
}

impl Image2d {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        instance: &ash::Instance,
        pd: vk::PhysicalDevice,
        device: &ash::Device,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
        width: u32,
        height: u32,
    ) -> Image2d {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        unsafe {
            let image = device.create_image(&info, None).unwrap();
            let req = device.get_image_memory_requirements(image);
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(memory_type(
                    instance,
                    pd,
                    req.memory_type_bits,
                    vk::MemoryPropertyFlags::DEVICE_LOCAL,
                ));
            let memory = device.allocate_memory(&alloc, None).unwrap();
            device.bind_image_memory(image, memory, 0).unwrap();
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(range(aspect));
            let view = device.create_image_view(&view_info, None).unwrap();
            Image2d {
                image,
                memory,
                view,
                format,
                aspect,
                width,
                height,
            }
        }
    }

    pub fn destroy(&self, device: &ash::Device) {
        unsafe {
            device.destroy_image_view(self.view, None);
            device.destroy_image(self.image, None);
            device.free_memory(self.memory, None);
        }
    }

    /// Records a layout transition with its memory dependency.
    #[allow(clippy::too_many_arguments)]
    pub fn transition(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        old: vk::ImageLayout,
        new: vk::ImageLayout,
        src: (vk::PipelineStageFlags2, vk::AccessFlags2),
        dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
    ) {
        let barrier = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(src.0)
            .src_access_mask(src.1)
            .dst_stage_mask(dst.0)
            .dst_access_mask(dst.1)
            .old_layout(old)
            .new_layout(new)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(self.image)
            .subresource_range(range(self.aspect))];
        let info = vk::DependencyInfo::default().image_memory_barriers(&barrier);
        unsafe { device.cmd_pipeline_barrier2(cmd, &info) };
    }

    /// Records the copy of the image (in TRANSFER_SRC_OPTIMAL) into `buffer`,
    /// tightly packed, and the barrier that makes it host-readable.
    pub fn record_copy_out(&self, device: &ash::Device, cmd: vk::CommandBuffer, buffer: vk::Buffer) {
        let region = [vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: self.aspect,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: self.width,
                height: self.height,
                depth: 1,
            })];
        unsafe {
            device.cmd_copy_image_to_buffer(cmd, self.image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer, &region);
            let barrier = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ)];
            device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier));
        }
    }
}

pub fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// A host-visible, coherent buffer with its memory, mapped.
pub struct HostBuffer {
    pub buffer: vk::Buffer,
    pub memory: vk::DeviceMemory,
    pub size: u64,
    ptr: *mut u8,
}

impl HostBuffer {
    pub fn new(
        instance: &ash::Instance,
        pd: vk::PhysicalDevice,
        device: &ash::Device,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> HostBuffer {
        unsafe {
            let buffer = device
                .create_buffer(&vk::BufferCreateInfo::default().size(size).usage(usage), None)
                .unwrap();
            let req = device.get_buffer_memory_requirements(buffer);
            let flags = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(memory_type(instance, pd, req.memory_type_bits, flags));
            let memory = device.allocate_memory(&alloc, None).unwrap();
            device.bind_buffer_memory(buffer, memory, 0).unwrap();
            let ptr = device.map_memory(memory, 0, size, vk::MemoryMapFlags::empty()).unwrap() as *mut u8;
            HostBuffer {
                buffer,
                memory,
                size,
                ptr,
            }
        }
    }

    pub fn bytes(&self) -> &[u8] {
        // SAFETY: mapped for `size` bytes until destroy; read after the GPU finished.
        unsafe { std::slice::from_raw_parts(self.ptr, self.size as usize) }
    }

    pub fn bytes_mut(&mut self) -> &mut [u8] {
        // SAFETY: as `bytes`; written before the GPU reads it.
        unsafe { std::slice::from_raw_parts_mut(self.ptr, self.size as usize) }
    }

    pub fn destroy(&self, device: &ash::Device) {
        unsafe {
            device.destroy_buffer(self.buffer, None);
            device.free_memory(self.memory, None);
        }
    }
}
