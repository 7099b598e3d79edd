//! `Context`: the instance, device, queue and allocator every GPU object uses.
//! Either created headless here or adopted from a host engine's handles, in
//! which case the instance and device are never destroyed by lacuna.

use super::device::{compute_family, device_info, select, DeviceInfo};
use super::instance::{create_instance, load_entry};
use super::kernel_cache::KernelCache;
use super::order::Order;
use super::requirements::{missing_requirement, required_features, AdoptInfo, EnabledFeatures, REQUIRED_EXTENSIONS};
use super::retire::{destroy, Retirement};
use super::validation::{Messenger, ValidationMessage};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

/// How to create a headless context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable `VK_LAYER_KHRONOS_validation` with synchronization validation
    /// and collect its messages (see [`Context::validation_messages`]).
    pub validation: bool,
    /// Device selector: an index from `lacuna devices` or a case-insensitive
    /// substring of the device name. `None` reads `LACUNA_DEVICE`.
    pub device: Option<String>,
}

impl ContextOptions {
    /// Options from the environment: `LACUNA_VALIDATE=1`, `LACUNA_DEVICE`.
    pub fn from_env() -> Self {
        ContextOptions {
            validation: switched_on(std::env::var("LACUNA_VALIDATE").ok().as_deref()),
            device: None,
        }
    }
}

/// An environment switch: off where unset, empty, 0, false, no or off (any case).
fn switched_on(value: Option<&str>) -> bool {
    value.is_some_and(|v| !["", "0", "false", "no", "off"].contains(&v.trim().to_ascii_lowercase().as_str()))
}

#[cfg(test)]
mod switch_tests {
    #[test]
    fn only_a_value_that_means_yes_switches_on() {
        for off in [None, Some(""), Some("0"), Some("false"), Some("No"), Some(" OFF ")] {
            assert!(!super::switched_on(off), "{off:?}");
        }
        for on in [Some("1"), Some("true"), Some("yes"), Some("on")] {
            assert!(super::switched_on(on), "{on:?}");
        }
    }
}

pub(crate) struct Inner {
    _entry: Option<ash::Entry>,
    pub(crate) instance: ash::Instance,
    pub(crate) physical_device: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    pub(crate) push_descriptor: ash::khr::push_descriptor::Device,
    /// Present when the instance has `VK_EXT_debug_utils` (validation on): GPU
    /// objects get names that validation messages and capture tools show.
    debug_utils: Option<ash::ext::debug_utils::Device>,
    pub(super) queue: Mutex<vk::Queue>,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Command pools no submission is recording with (one each).
    pub(super) command_pools: Mutex<Vec<vk::CommandPool>>,
    /// Held from a submission to its wait: lacuna's submissions run on the
    /// device one after another (their recording need not).
    pub(super) order: Order,
    messenger: Option<Messenger>,
    pub(crate) info: DeviceInfo,
    /// Every kernel made on this context (`Kernel` borrows their objects).
    pub(crate) kernels: KernelCache,
    /// Submissions lacuna made on the queue (`Context::submissions`).
    pub(super) submissions: std::sync::atomic::AtomicU64,
    /// Objects dropped while a submission of lacuna's was in flight.
    pub(super) retirement: Mutex<Retirement>,
    owned: bool,
}

/// A cheap, clonable handle; GPU objects keep one so they can free themselves.
#[derive(Clone)]
pub struct Context {
    pub(crate) inner: Arc<Inner>,
}

impl Context {
    /// A headless context on the selected device.
    pub fn new(options: &ContextOptions) -> Result<Self> {
        let entry = load_entry()?;
        let instance = create_instance(&entry, options.validation)?;
        let built = (|| {
            let messenger = if options.validation {
                Some(Messenger::new(&entry, &instance)?)
            } else {
                None
            };
            let selector = options.device.clone().or_else(|| std::env::var("LACUNA_DEVICE").ok());
            let pd = select(&instance, selector.as_deref())?;
            let (family, _) = compute_family(&instance, pd)
                .ok_or_else(|| Error::NoDevice("the selected device has no compute queue".into()))?;
            let priorities = [1.0];
            let queues = [vk::DeviceQueueCreateInfo::default()
                .queue_family_index(family)
                .queue_priorities(&priorities)];
            let extensions = REQUIRED_EXTENSIONS.map(|e| e.as_ptr());
            let (mut v12, mut v13) = required_features();
            let info = vk::DeviceCreateInfo::default()
                .queue_create_infos(&queues)
                .enabled_extension_names(&extensions)
                .push_next(&mut v13)
                .push_next(&mut v12);
            let device = unsafe { instance.create_device(pd, &info, None) }.vk("vkCreateDevice")?;
            let queue = unsafe { device.get_device_queue(family, 0) };
            Ok((messenger, pd, device, queue, family))
        })();
        match built {
            Ok((messenger, pd, device, queue, family)) => {
                let (vulkan12, vulkan13) = required_features();
                let handles = AdoptInfo {
                    entry: Some(entry),
                    instance,
                    physical_device: pd,
                    device,
                    queue,
                    queue_family: family,
                    enabled: EnabledFeatures {
                        api_version: vk::API_VERSION_1_3,
                        extensions: REQUIRED_EXTENSIONS.iter().map(|e| (*e).to_owned()).collect(),
                        vulkan12,
                        vulkan13,
                    },
                };
                Self::assemble(handles, messenger, true)
            }
            Err(e) => {
                unsafe { instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    /// A context on `ContextOptions::from_env()`.
    pub fn from_env() -> Result<Self> {
        Self::new(&ContextOptions::from_env())
    }

    /// Adopts a host's instance, device and queue. lacuna creates its own
    /// allocator and command pools on them and destroys only those; dropping
    /// the context waits for nothing of the host's (lacuna's own submissions
    /// are waited for by the call that made them).
    ///
    /// Checks first that the device has what lacuna needs (Vulkan 1.3,
    /// [`REQUIRED_EXTENSIONS`], the features of [`required_features`] as
    /// `host.enabled` states them, subgroup vote in compute shaders; the
    /// extension is also probed on the device), and returns an error naming
    /// the first thing missing.
    ///
    /// # Safety
    /// The host guarantees that:
    /// - `instance`, `physical_device`, `device` and `queue` are valid, belong
    ///   together, and outlive the `Context` and every object made with it;
    /// - `host.enabled` is what the device was created with;
    /// - `queue` is of `queue_family`, and no other thread uses `queue` while a
    ///   lacuna convenience call (`submit_and_wait`: uploads, `build`,
    ///   `render`, downloads) runs, since lacuna submits on it then (the
    ///   `record_*` forms and `Renderer::new` submit nothing:
    ///   [`Context::submissions`]);
    /// - every command buffer given to a `record_*` call is submitted to a
    ///   queue of `queue_family`: lacuna's buffers and images are exclusive
    ///   to that family, it records no ownership transfers, and its timers'
    ///   timestamps are that family's;
    /// - `entry`, when given, is the loader `instance` was created with;
    /// - lacuna's objects are not in use by pending host work when dropped.
    pub unsafe fn adopt(host: AdoptInfo) -> Result<Self> {
        if let Some(missing) = missing_requirement(&host.instance, host.physical_device, &host.device, &host.enabled) {
            return Err(Error::NoDevice(format!(
                "the adopted device lacks {missing}, which lacuna needs (see gpu::required_features)"
            )));
        }
        let families = unsafe {
            host.instance
                .get_physical_device_queue_family_properties(host.physical_device)
        };
        let family = families.get(host.queue_family as usize).ok_or_else(|| {
            Error::invalid(
                "queue family",
                host.queue_family.to_string(),
                "not a queue family of this device",
            )
        })?;
        if !family.queue_flags.contains(vk::QueueFlags::COMPUTE) {
            return Err(Error::invalid(
                "queue family",
                host.queue_family.to_string(),
                "does not support compute",
            ));
        }
        let messenger = match &host.entry {
            // ash stands a panicking stub in for a command the instance
            // lacks, and a panic there aborts: probe it first.
            Some(entry) if !has_debug_utils(entry, &host.instance) => {
                return Err(Error::invalid(
                    "adopted instance",
                    "given with its entry",
                    "lacuna's validation messenger needs VK_EXT_debug_utils enabled on the instance; pass entry: None without it",
                ))
            }
            Some(entry) => Some(Messenger::new(entry, &host.instance)?),
            None => None,
        };
        Self::assemble(host, messenger, false)
    }

    /// The context on `handles`; `owned`: created here, destroyed with it.
    fn assemble(handles: AdoptInfo, messenger: Option<Messenger>, owned: bool) -> Result<Self> {
        let AdoptInfo {
            entry,
            instance,
            physical_device: pd,
            device,
            queue,
            queue_family: family,
            ..
        } = handles;
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let bits = families.get(family as usize).map_or(0, |f| f.timestamp_valid_bits);
        let info = device_info(&instance, pd, bits);
        let cleanup = |instance: &ash::Instance, device: &ash::Device| {
            if owned {
                unsafe {
                    device.destroy_device(None);
                    instance.destroy_instance(None);
                }
            }
        };
        let allocator = match Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: pd,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        }) {
            Ok(a) => a,
            Err(e) => {
                drop(messenger);
                cleanup(&instance, &device);
                return Err(Error::Memory {
                    what: "allocator".into(),
                    message: e.to_string(),
                });
            }
        };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let pool = match unsafe { device.create_command_pool(&pool_info, None) } {
            Ok(p) => p,
            Err(result) => {
                drop(allocator);
                drop(messenger);
                cleanup(&instance, &device);
                return Err(Error::Vulkan {
                    call: "vkCreateCommandPool",
                    result,
                });
            }
        };
        let push_descriptor = ash::khr::push_descriptor::Device::new(&instance, &device);
        let debug_utils = messenger
            .as_ref()
            .map(|_| ash::ext::debug_utils::Device::new(&instance, &device));
        Ok(Context {
            inner: Arc::new(Inner {
                _entry: entry,
                instance,
                physical_device: pd,
                device,
                push_descriptor,
                debug_utils,
                queue: Mutex::new(queue),
                queue_family: family,
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                command_pools: Mutex::new(vec![pool]),
                order: Order::default(),
                messenger,
                info,
                kernels: KernelCache::default(),
                submissions: Default::default(),
                retirement: Default::default(),
                owned,
            }),
        })
    }

    pub fn device(&self) -> &ash::Device {
        &self.inner.device
    }

    /// How many distinct kernels (SPIR-V and specialization) this context
    /// has created: each is created once and kept until the context goes.
    pub fn kernels_created(&self) -> usize {
        self.inner.kernels.len()
    }

    /// Whether `other` is a handle of this same context: objects made on
    /// one cannot be used on another (their handles are another device's).
    pub fn is(&self, other: &Context) -> bool {
        Arc::ptr_eq(&self.inner, &other.inner)
    }

    /// An error naming `what` unless `made_on` is this context (`is`).
    pub fn check_is(&self, made_on: &Context, what: &'static str) -> Result<()> {
        match self.is(made_on) {
            true => Ok(()),
            false => Err(Error::invalid(
                what,
                "of another lacuna Context",
                "lacuna uses what was uploaded and built on the context it works on",
            )),
        }
    }

    /// How many handles to this context exist (this one included): every
    /// object made on it holds one.
    #[doc(hidden)]
    pub fn handle_count(&self) -> usize {
        Arc::strong_count(&self.inner)
    }

    /// Names a GPU object for validation messages and capture tools (a no-op
    /// without `VK_EXT_debug_utils`).
    pub(crate) fn name_object<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(utils) = &self.inner.debug_utils else {
            return;
        };
        let Ok(name) = std::ffi::CString::new(name) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&name);
        // Naming is a debugging aid: a failure changes nothing else.
        let _ = unsafe { utils.set_debug_utils_object_name(&info) };
    }

    pub fn instance(&self) -> &ash::Instance {
        &self.inner.instance
    }

    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.inner.physical_device
    }

    pub fn queue_family(&self) -> u32 {
        self.inner.queue_family
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.inner.info
    }

    pub(crate) fn format_properties(&self, format: vk::Format) -> vk::FormatProperties {
        unsafe {
            self.inner
                .instance
                .get_physical_device_format_properties(self.inner.physical_device, format)
        }
    }

    /// Whether sampled images of `format` (optimal tiling) filter linearly on
    /// this device: `SAMPLED_IMAGE_FILTER_LINEAR` is optional for R16 and R32F.
    pub fn filters_linearly(&self, format: vk::Format) -> bool {
        self.format_properties(format)
            .optimal_tiling_features
            .contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR)
    }

    /// Whether buffers of `format` can be read as uniform texel buffers.
    pub fn reads_texel_buffers(&self, format: vk::Format) -> bool {
        self.format_properties(format)
            .buffer_features
            .contains(vk::FormatFeatureFlags::UNIFORM_TEXEL_BUFFER)
    }

    /// Whether this context created (and will destroy) its instance and device.
    pub fn owns_device(&self) -> bool {
        self.inner.owned
    }

    pub fn validation_enabled(&self) -> bool {
        self.inner.messenger.is_some()
    }

    /// Every validation message collected so far (empty without validation):
    /// the first `MAX_KEPT` (1024) since they were last taken, and one more
    /// naming how many were dropped after them.
    pub fn validation_messages(&self) -> Vec<ValidationMessage> {
        self.inner
            .messenger
            .as_ref()
            .map(|m| m.store.lock().unwrap_or_else(|p| p.into_inner()).list())
            .unwrap_or_default()
    }

    /// Returns and clears the collected validation messages.
    pub fn take_validation_messages(&self) -> Vec<ValidationMessage> {
        self.inner
            .messenger
            .as_ref()
            .map(|m| m.store.lock().unwrap_or_else(|p| p.into_inner()).take())
            .unwrap_or_default()
    }

    pub(crate) fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.inner.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// How many command buffers lacuna has submitted on the queue (its
    /// convenience calls: uploads, `build`, `render`, downloads). The
    /// `record_*` forms submit nothing: a host can check that its recording
    /// left this unchanged.
    pub fn submissions(&self) -> u64 {
        self.inner.submissions.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// Whether `instance` has `VK_EXT_debug_utils`'s messenger command.
fn has_debug_utils(entry: &ash::Entry, instance: &ash::Instance) -> bool {
    let name = c"vkCreateDebugUtilsMessengerEXT";
    unsafe { entry.get_instance_proc_addr(instance.handle(), name.as_ptr()) }.is_some()
}

impl Drop for Inner {
    fn drop(&mut self) {
        unsafe {
            // An adopted device is the host's: its queues may be busy with its
            // own work, which lacuna must not wait for. Every lacuna
            // submission was waited for by the call that made it.
            if self.owned {
                let _ = self.device.device_wait_idle();
            }
            self.kernels.destroy_all(&self.device);
            let left = std::mem::take(&mut self.retirement.get_mut().unwrap_or_else(|p| p.into_inner()).waiting);
            destroy(
                &self.device,
                &self.allocator,
                left.into_iter().map(|(_, o)| o).collect(),
            );
            ManuallyDrop::drop(&mut self.allocator);
            for pool in self
                .command_pools
                .get_mut()
                .unwrap_or_else(|p| p.into_inner())
                .drain(..)
            {
                self.device.destroy_command_pool(pool, None);
            }
            if self.owned {
                self.device.destroy_device(None);
            }
            // The messenger must go before the instance it was created on.
            self.messenger.take();
            if self.owned {
                self.instance.destroy_instance(None);
            }
        }
    }
}
