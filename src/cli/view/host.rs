//! The viewer's own Vulkan, as a host engine has it: an instance with the
//! window system's surface extensions (and, with `--validate`, the
//! validation layer with synchronization validation), a device with what
//! `Context::adopt` requires plus `VK_KHR_swapchain`, one queue for graphics,
//! compute and present, a swapchain, and an RGBA32F canvas image that is
//! blitted (scaled and sRGB-encoded by the blit) into each swapchain image.
//! One frame in flight: each frame is waited for, so its timestamps and
//! readback are ready when `frame` returns.

use super::blit;
use lacuna::gpu::{required_features, vk, AdoptInfo, Context, EnabledFeatures, Recording};
use lacuna::{Error, Result};
use std::ffi::CStr;
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// The canvas's format: what lacuna's frame is (RGBA f32, linear, premultiplied).
pub const CANVAS_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

fn vk_err(call: &'static str) -> impl Fn(vk::Result) -> Error {
    move |result| Error::Vulkan { call, result }
}

/// The host's image the scene renders into each frame.
/// The device extensions the viewer enables: lacuna's and the swapchain.
const DEVICE_EXTENSIONS: [&CStr; 2] = [ash::khr::push_descriptor::NAME, ash::khr::swapchain::NAME];

pub struct Canvas {
    pub image: vk::Image,
    memory: vk::DeviceMemory,
    pub extent: vk::Extent2D,
}

/// What became of a frame.
pub struct Presented {
    /// The frame was rendered and submitted (its timestamps and readback are ready).
    pub drawn: bool,
    /// The swapchain no longer matches the window: `resize` before the next frame.
    pub stale: bool,
}

struct Swapchain {
    handle: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    /// Signalled by each image's frame, waited on by its present.
    rendered: Vec<vk::Semaphore>,
    extent: vk::Extent2D,
}

pub struct Host {
    entry: ash::Entry,
    instance: ash::Instance,
    surface_fn: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    physical_device: vk::PhysicalDevice,
    device: ash::Device,
    family: u32,
    queue: vk::Queue,
    swapchain_fn: ash::khr::swapchain::Device,
    swapchain: Option<Swapchain>,
    format: vk::SurfaceFormatKHR,
    canvas: Option<Canvas>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    acquired: vk::Semaphore,
    fence: vk::Fence,
}

impl Host {
    /// The instance, surface and device for `window`; then the swapchain.
    pub fn new(window: &Window, validate: bool) -> Result<Host> {
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| Error::NoDevice(format!("no Vulkan loader found ({e})")))?;
        let display = window
            .display_handle()
            .map_err(|e| Error::NoDevice(format!("no display handle: {e}")))?
            .as_raw();
        let window_handle = window
            .window_handle()
            .map_err(|e| Error::NoDevice(format!("no window handle: {e}")))?
            .as_raw();
        let mut extensions = ash_window::enumerate_required_extensions(display)
            .map_err(vk_err("vkEnumerateInstanceExtensionProperties (surface)"))?
            .to_vec();
        let mut layers = Vec::new();
        if validate {
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .map_err(vk_err("vkEnumerateInstanceLayerProperties"))?;
            if !available
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER))
            {
                return Err(Error::NoDevice(
                    "validation requested but VK_LAYER_KHRONOS_validation is not installed".into(),
                ));
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let app = vk::ApplicationInfo::default()
            .application_name(c"lacuna view")
            .api_version(vk::API_VERSION_1_3);
        let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validate {
            info = info.push_next(&mut features);
        }
        let instance = unsafe { entry.create_instance(&info, None) }.map_err(vk_err("vkCreateInstance"))?;
        let surface_fn = ash::khr::surface::Instance::new(&entry, &instance);
        let surface = match unsafe { ash_window::create_surface(&entry, &instance, display, window_handle, None) } {
            Ok(s) => s,
            Err(e) => {
                unsafe { instance.destroy_instance(None) };
                return Err(vk_err("vkCreate*SurfaceKHR")(e));
            }
        };
        let device = Self::create_device(&instance, &surface_fn, surface);
        let (physical_device, device, family) = match device {
            Ok(d) => d,
            Err(e) => {
                unsafe {
                    surface_fn.destroy_surface(surface, None);
                    instance.destroy_instance(None);
                }
                return Err(e);
            }
        };
        let queue = unsafe { device.get_device_queue(family, 0) };
        let swapchain_fn = ash::khr::swapchain::Device::new(&instance, &device);
        let mut host = Host {
            entry,
            instance,
            surface_fn,
            surface,
            physical_device,
            device,
            family,
            queue,
            swapchain_fn,
            swapchain: None,
            format: vk::SurfaceFormatKHR::default(),
            canvas: None,
            pool: vk::CommandPool::null(),
            cmd: vk::CommandBuffer::null(),
            acquired: vk::Semaphore::null(),
            fence: vk::Fence::null(),
        };
        // From here on, Drop cleans up whatever was made.
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        host.pool =
            unsafe { host.device.create_command_pool(&pool_info, None) }.map_err(vk_err("vkCreateCommandPool"))?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(host.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        host.cmd =
            unsafe { host.device.allocate_command_buffers(&alloc) }.map_err(vk_err("vkAllocateCommandBuffers"))?[0];
        host.acquired =
            unsafe { host.device.create_semaphore(&Default::default(), None) }.map_err(vk_err("vkCreateSemaphore"))?;
        host.fence = unsafe { host.device.create_fence(&Default::default(), None) }.map_err(vk_err("vkCreateFence"))?;
        host.format = host.choose_format()?;
        Ok(host)
    }

    /// lacuna's device choice (`LACUNA_DEVICE` honoured), one queue family
    /// with graphics (for the blit), compute and present, and the features
    /// `Context::adopt` documents.
    fn create_device(
        instance: &ash::Instance,
        surface_fn: &ash::khr::surface::Instance,
        surface: vk::SurfaceKHR,
    ) -> Result<(vk::PhysicalDevice, ash::Device, u32)> {
        let selector = std::env::var("LACUNA_DEVICE").ok();
        let pd = lacuna::gpu::select_device(instance, selector.as_deref())?;
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
        let family = (0..families.len() as u32)
            .find(|&i| {
                families[i as usize].queue_flags.contains(wanted)
                    && unsafe { surface_fn.get_physical_device_surface_support(pd, i, surface) }.unwrap_or(false)
            })
            .ok_or_else(|| {
                Error::NoDevice("no queue family with graphics, compute and present to this window".into())
            })?;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let extensions = DEVICE_EXTENSIONS.map(CStr::as_ptr);
        // Exactly what lacuna needs (and what adopt is told was enabled).
        let (mut v12, mut v13) = required_features();
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&extensions)
            .push_next(&mut v13)
            .push_next(&mut v12);
        let device = unsafe { instance.create_device(pd, &info, None) }.map_err(vk_err("vkCreateDevice"))?;
        Ok((pd, device, family))
    }

    /// What `create_device` enabled, for `Context::adopt` to check.
    fn enabled() -> EnabledFeatures {
        let (vulkan12, vulkan13) = required_features();
        EnabledFeatures {
            api_version: vk::API_VERSION_1_3,
            extensions: DEVICE_EXTENSIONS.iter().map(|&e| e.into()).collect(),
            vulkan12,
            vulkan13,
        }
    }

    /// lacuna on the host's device: it owns none of these handles. With
    /// validation, it collects the instance's messages (the host's too).
    pub fn adopt(&self, validate: bool) -> Result<Context> {
        unsafe {
            Context::adopt(AdoptInfo {
                entry: validate.then(|| self.entry.clone()),
                instance: self.instance.clone(),
                physical_device: self.physical_device,
                device: self.device.clone(),
                queue: self.queue,
                queue_family: self.family,
                enabled: Self::enabled(),
            })
        }
    }

    /// An sRGB swapchain format when there is one (the blit then encodes),
    /// which must take blits of the canvas.
    fn choose_format(&self) -> Result<vk::SurfaceFormatKHR> {
        let formats = unsafe {
            self.surface_fn
                .get_physical_device_surface_formats(self.physical_device, self.surface)
        }
        .map_err(vk_err("vkGetPhysicalDeviceSurfaceFormatsKHR"))?;
        let srgb = [vk::Format::B8G8R8A8_SRGB, vk::Format::R8G8B8A8_SRGB];
        let format = formats
            .iter()
            .find(|f| srgb.contains(&f.format))
            .or(formats.first())
            .copied()
            .ok_or_else(|| Error::NoDevice("the window's surface offers no format".into()))?;
        let features = |f: vk::Format| unsafe {
            self.instance
                .get_physical_device_format_properties(self.physical_device, f)
                .optimal_tiling_features
        };
        if !features(CANVAS_FORMAT).contains(vk::FormatFeatureFlags::BLIT_SRC) {
            return Err(Error::Unsupported("the device cannot blit from RGBA32F images".into()));
        }
        if !features(format.format).contains(vk::FormatFeatureFlags::BLIT_DST) {
            return Err(Error::Unsupported(format!(
                "the device cannot blit into the swapchain format {:?}",
                format.format
            )));
        }
        Ok(format)
    }

    /// (Re)creates the swapchain and the canvas for the window's `size`;
    /// returns the extent frames are rendered at.
    pub fn resize(&mut self, size: (u32, u32)) -> Result<vk::Extent2D> {
        unsafe { self.device.device_wait_idle() }.map_err(vk_err("vkDeviceWaitIdle"))?;
        let caps = unsafe {
            self.surface_fn
                .get_physical_device_surface_capabilities(self.physical_device, self.surface)
        }
        .map_err(vk_err("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?;
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            return Err(Error::Unsupported(
                "swapchain images cannot be transfer destinations".into(),
            ));
        }
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let modes = unsafe {
            self.surface_fn
                .get_physical_device_surface_present_modes(self.physical_device, self.surface)
        }
        .map_err(vk_err("vkGetPhysicalDeviceSurfacePresentModesKHR"))?;
        // Unthrottled where possible: the title's fps is the renderer's.
        let mode = [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
            .into_iter()
            .find(|m| modes.contains(m))
            .unwrap_or(vk::PresentModeKHR::FIFO);
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = [vk::CompositeAlphaFlagsKHR::OPAQUE, vk::CompositeAlphaFlagsKHR::INHERIT]
            .into_iter()
            .find(|a| caps.supported_composite_alpha.contains(*a))
            .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let old = self.swapchain.take();
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(self.format.format)
            .image_color_space(self.format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old.as_ref().map_or(vk::SwapchainKHR::null(), |s| s.handle));
        let created = unsafe { self.swapchain_fn.create_swapchain(&info, None) };
        if let Some(old) = old {
            self.destroy_swapchain(old);
        }
        let handle = created.map_err(vk_err("vkCreateSwapchainKHR"))?;
        let images = unsafe { self.swapchain_fn.get_swapchain_images(handle) };
        let mut swapchain = Swapchain {
            handle,
            images: Vec::new(),
            rendered: Vec::new(),
            extent,
        };
        let images = match images {
            Ok(i) => i,
            Err(e) => {
                self.destroy_swapchain(swapchain);
                return Err(vk_err("vkGetSwapchainImagesKHR")(e));
            }
        };
        for _ in &images {
            match unsafe { self.device.create_semaphore(&Default::default(), None) } {
                Ok(s) => swapchain.rendered.push(s),
                Err(e) => {
                    self.destroy_swapchain(swapchain);
                    return Err(vk_err("vkCreateSemaphore")(e));
                }
            }
        }
        swapchain.images = images;
        self.swapchain = Some(swapchain);
        if let Some(canvas) = self.canvas.take() {
            self.destroy_canvas(canvas);
        }
        self.canvas = Some(self.create_canvas(extent)?);
        Ok(extent)
    }

    fn create_canvas(&self, extent: vk::Extent2D) -> Result<Canvas> {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(CANVAS_FORMAT)
            .extent(vk::Extent3D {
                width: extent.width,
                height: extent.height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let image = unsafe { self.device.create_image(&info, None) }.map_err(vk_err("vkCreateImage"))?;
        let needs = unsafe { self.device.get_image_memory_requirements(image) };
        let memory = unsafe {
            self.instance
                .get_physical_device_memory_properties(self.physical_device)
        };
        let kind = (0..memory.memory_type_count).find(|&i| {
            needs.memory_type_bits & (1 << i) != 0
                && memory.memory_types[i as usize]
                    .property_flags
                    .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
        });
        let allocated = kind.ok_or(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY).and_then(|kind| {
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(needs.size)
                .memory_type_index(kind);
            unsafe { self.device.allocate_memory(&alloc, None) }
        });
        let bound = allocated.and_then(
            |memory| match unsafe { self.device.bind_image_memory(image, memory, 0) } {
                Ok(()) => Ok(memory),
                Err(e) => {
                    unsafe { self.device.free_memory(memory, None) };
                    Err(e)
                }
            },
        );
        match bound {
            Ok(memory) => Ok(Canvas { image, memory, extent }),
            Err(e) => {
                unsafe { self.device.destroy_image(image, None) };
                Err(Error::Memory {
                    what: format!("canvas {}x{}", extent.width, extent.height),
                    message: e.to_string(),
                })
            }
        }
    }

    fn destroy_canvas(&self, canvas: Canvas) {
        unsafe {
            self.device.destroy_image(canvas.image, None);
            self.device.free_memory(canvas.memory, None);
        }
    }

    fn destroy_swapchain(&self, swapchain: Swapchain) {
        unsafe {
            for s in swapchain.rendered {
                self.device.destroy_semaphore(s, None);
            }
            self.swapchain_fn.destroy_swapchain(swapchain.handle, None);
        }
    }

    /// One frame: acquires a swapchain image, records `draw` (which must
    /// leave the canvas written by transfer in TRANSFER_SRC_OPTIMAL), blits
    /// the canvas into the image, submits, presents and waits. `ctx` is the
    /// context adopted from this host (`adopt`).
    pub fn frame(
        &mut self,
        ctx: &Context,
        draw: impl FnOnce(Recording<'_>, &Canvas) -> Result<()>,
    ) -> Result<Presented> {
        let stale = Presented {
            drawn: false,
            stale: true,
        };
        let (Some(swapchain), Some(canvas)) = (&self.swapchain, &self.canvas) else {
            return Ok(stale);
        };
        let acquired = unsafe {
            self.swapchain_fn
                .acquire_next_image(swapchain.handle, u64::MAX, self.acquired, vk::Fence::null())
        };
        let index = match acquired {
            Ok((index, _)) => index as usize,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok(stale),
            Err(e) => return Err(vk_err("vkAcquireNextImageKHR")(e)),
        };
        if ctx.device().handle() != self.device.handle() {
            return Err(Error::invalid(
                "view context",
                "another device",
                "frame takes the context adopted from this host",
            ));
        }
        let (device, cmd) = (&self.device, self.cmd);
        let target = swapchain.images[index];
        unsafe {
            device
                .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .map_err(vk_err("vkResetCommandBuffer"))?;
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            device
                .begin_command_buffer(cmd, &begin)
                .map_err(vk_err("vkBeginCommandBuffer"))?;
        }
        // SAFETY: `cmd` is this host's, on the device `ctx` adopted, begun
        // above and submitted to its queue below; the fence wait before this
        // returns outlives everything `draw` borrowed to record.
        let rec = unsafe { Recording::adopt(ctx, cmd) };
        let drawn = draw(rec, canvas);
        // SAFETY: the acquired swapchain image, of the swapchain's extent.
        unsafe { blit::record_to_swapchain(device, rec, (canvas.image, canvas.extent), target, swapchain.extent) };
        unsafe { device.end_command_buffer(cmd) }.map_err(vk_err("vkEndCommandBuffer"))?;
        drawn?;
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.acquired)
            .stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(swapchain.rendered[index])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        unsafe { device.queue_submit2(self.queue, &submit, self.fence) }.map_err(vk_err("vkQueueSubmit2"))?;
        let wait = [swapchain.rendered[index]];
        let chains = [swapchain.handle];
        let indices = [index as u32];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        let presented = unsafe { self.swapchain_fn.queue_present(self.queue, &present) };
        unsafe {
            device
                .wait_for_fences(&[self.fence], true, u64::MAX)
                .map_err(vk_err("vkWaitForFences"))?;
            device.reset_fences(&[self.fence]).map_err(vk_err("vkResetFences"))?;
        }
        match presented {
            Ok(suboptimal) => Ok(Presented {
                drawn: true,
                stale: suboptimal,
            }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented {
                drawn: true,
                stale: true,
            }),
            Err(e) => Err(vk_err("vkQueuePresentKHR")(e)),
        }
    }

    /// Waits for the device and destroys the window's objects (swapchain,
    /// canvas, command pool, semaphores), keeping the device and instance;
    /// `Drop` destroys those.
    pub fn release(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
        }
        if let Some(s) = self.swapchain.take() {
            self.destroy_swapchain(s);
        }
        if let Some(c) = self.canvas.take() {
            self.destroy_canvas(c);
        }
        unsafe {
            self.device.destroy_fence(self.fence, None);
            self.device.destroy_semaphore(self.acquired, None);
            self.device.destroy_command_pool(self.pool, None);
        }
        self.fence = vk::Fence::null();
        self.acquired = vk::Semaphore::null();
        self.pool = vk::CommandPool::null();
    }
}

impl Drop for Host {
    /// Every lacuna object (the adopted `Context` included) must be gone.
    fn drop(&mut self) {
        self.release();
        unsafe {
            self.device.destroy_device(None);
            self.surface_fn.destroy_surface(self.surface, None);
            self.instance.destroy_instance(None);
        }
    }
}
