//! `Context`: the instance, device, queue and allocator every GPU object uses.
//! Either created headless here or adopted from a host engine's handles, in
//! which case the instance and device are never destroyed by lacuna.

use super::validation::{Messenger, ValidationMessage, VALIDATION_LAYER};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

const INSTALL_HINT: &str =
    "install a Vulkan driver (Debian/Ubuntu CPU driver: apt install mesa-vulkan-drivers libvulkan1)";

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
        let validation = std::env::var("LACUNA_VALIDATE").is_ok_and(|v| !v.is_empty() && v != "0");
        ContextOptions {
            validation,
            device: None,
        }
    }
}

/// Facts about the device that lacuna checks before using it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub driver: String,
    pub device_type: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub max_storage_buffer_range: u64,
    pub max_texel_buffer_elements: u32,
    pub max_image_dimension_3d: u32,
    pub max_compute_work_group_count: [u32; 3],
    pub max_compute_work_group_invocations: u32,
    pub max_compute_shared_memory_size: u32,
    pub max_push_constants_size: u32,
    pub max_memory_allocation_size: u64,
    pub subgroup_size: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Valid bits of the queue's timestamps (0 = no timestamps).
    pub timestamp_valid_bits: u32,
    /// Largest device-local heap in bytes.
    pub device_local_bytes: u64,
    /// Fractional bits of the sampler's filtering weights (Vulkan requires >= 4).
    pub sub_texel_precision_bits: u32,
}

impl DeviceInfo {
    pub fn api_string(&self) -> String {
        let v = self.api_version;
        format!(
            "{}.{}.{}",
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        )
    }

    pub fn type_string(&self) -> &'static str {
        match self.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        }
    }

    /// Fails with a message naming `limit` when `value > max`.
    pub fn check(&self, what: impl Into<String>, limit: &'static str, value: u64, max: u64) -> Result<()> {
        if value > max {
            return Err(Error::DeviceLimit {
                what: what.into(),
                limit,
                max,
                device: self.name.clone(),
            });
        }
        Ok(())
    }
}

/// The handles a host engine lends to lacuna. The device must have been
/// created with Vulkan 1.3, the extensions of [`REQUIRED_EXTENSIONS`] and the
/// features [`required_features`] sets, and `enabled` must say what it was
/// created with (Vulkan cannot be asked afterwards); `queue` must belong to
/// `queue_family` and support compute. Drop the `Context` (and everything made
/// with it) before destroying the device.
pub struct AdoptInfo {
    /// When given (and the instance was created with `VK_EXT_debug_utils`),
    /// lacuna attaches its own messenger and collects validation messages
    /// exactly as for a context it created.
    pub entry: Option<ash::Entry>,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    /// What the device was created with.
    pub enabled: EnabledFeatures,
}

/// Device extensions lacuna needs (kernels bind with push descriptors).
pub const REQUIRED_EXTENSIONS: [&std::ffi::CStr; 1] = [ash::khr::push_descriptor::NAME];

/// The Vulkan 1.2 and 1.3 features lacuna needs, set (chain them into your
/// `VkDeviceCreateInfo`, with your own): 1.3 `synchronization2` (every
/// barrier) and `maintenance4` (workgroup sizes from specialization
/// constants); 1.2 `vulkanMemoryModel` with device scope (the LBVH refit's
/// acquire/release atomics). All are required of every Vulkan 1.3 device.
pub fn required_features() -> (
    vk::PhysicalDeviceVulkan12Features<'static>,
    vk::PhysicalDeviceVulkan13Features<'static>,
) {
    (
        vk::PhysicalDeviceVulkan12Features::default()
            .vulkan_memory_model(true)
            .vulkan_memory_model_device_scope(true),
        vk::PhysicalDeviceVulkan13Features::default()
            .synchronization2(true)
            .maintenance4(true),
    )
}

/// What a host created its device with, as `Context::adopt` checks it: the
/// instance's `apiVersion`, the enabled device extensions and the enabled
/// Vulkan 1.2 / 1.3 features (copies of the structs chained into
/// `VkDeviceCreateInfo`; their `p_next` is not read).
#[derive(Clone, Debug, Default)]
pub struct EnabledFeatures {
    pub api_version: u32,
    pub extensions: Vec<std::ffi::CString>,
    pub vulkan12: vk::PhysicalDeviceVulkan12Features<'static>,
    pub vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
}

/// The first thing lacuna needs that `enabled` lacks on `device`, named.
fn missing_requirement(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    device: &ash::Device,
    enabled: &EnabledFeatures,
) -> Option<String> {
    let version = |v: u32| format!("{}.{}", vk::api_version_major(v), vk::api_version_minor(v));
    let device_version = unsafe { instance.get_physical_device_properties(pd) }.api_version;
    if device_version < vk::API_VERSION_1_3 {
        return Some(format!("Vulkan 1.3 (the device supports {})", version(device_version)));
    }
    if enabled.api_version < vk::API_VERSION_1_3 {
        return Some(format!(
            "Vulkan 1.3 (the instance asked for {})",
            version(enabled.api_version)
        ));
    }
    for ext in REQUIRED_EXTENSIONS {
        let listed = enabled.extensions.iter().any(|e| e.as_c_str() == ext);
        if !listed {
            return Some(format!("device extension {}", ext.to_string_lossy()));
        }
    }
    // A listed extension the device was not really created with would abort
    // at the first dispatch: ask the device for its command.
    let push =
        unsafe { (instance.fp_v1_0().get_device_proc_addr)(device.handle(), c"vkCmdPushDescriptorSetKHR".as_ptr()) };
    if push.is_none() {
        return Some(format!(
            "device extension {} (vkCmdPushDescriptorSetKHR is not loaded on this device)",
            ash::khr::push_descriptor::NAME.to_string_lossy()
        ));
    }
    let (v12, v13) = (&enabled.vulkan12, &enabled.vulkan13);
    let features = [
        ("Vulkan 1.3 feature synchronization2", v13.synchronization2),
        ("Vulkan 1.3 feature maintenance4", v13.maintenance4),
        ("Vulkan 1.2 feature vulkanMemoryModel", v12.vulkan_memory_model),
        (
            "Vulkan 1.2 feature vulkanMemoryModelDeviceScope",
            v12.vulkan_memory_model_device_scope,
        ),
    ];
    features
        .iter()
        .find(|(_, on)| *on == vk::FALSE)
        .map(|(name, _)| name.to_string())
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
    queue: Mutex<vk::Queue>,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    command_pool: Mutex<vk::CommandPool>,
    messenger: Option<Messenger>,
    pub(crate) info: DeviceInfo,
    owned: bool,
}

/// A cheap, clonable handle; GPU objects keep one so they can free themselves.
#[derive(Clone)]
pub struct Context {
    pub(crate) inner: Arc<Inner>,
}

/// A physical device as listed by `lacuna devices`.
#[derive(Clone, Debug)]
pub struct DeviceSummary {
    pub index: usize,
    pub name: String,
    pub device_type: String,
    pub api: String,
    pub driver: String,
    pub usable: bool,
}

fn load_entry() -> Result<ash::Entry> {
    unsafe { ash::Entry::load() }.map_err(|e| Error::NoDevice(format!("no Vulkan loader found ({e}); {INSTALL_HINT}")))
}

fn create_instance(entry: &ash::Entry, validation: bool) -> Result<ash::Instance> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"lacuna")
        .engine_name(c"lacuna")
        .api_version(vk::API_VERSION_1_3);
    let mut layers = Vec::new();
    let mut extensions = Vec::new();
    let features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut validation_features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&features);
    if validation {
        let available =
            unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
        let found = available
            .iter()
            .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
        if !found {
            return Err(Error::NoDevice(
                "validation requested but VK_LAYER_KHRONOS_validation is not installed (Debian: apt install vulkan-validationlayers)"
                    .into(),
            ));
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if validation {
        info = info.push_next(&mut validation_features);
    }
    unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => {
            Error::NoDevice(format!("no Vulkan 1.3 driver is installed; {INSTALL_HINT}"))
        }
        result => Error::Vulkan {
            call: "vkCreateInstance",
            result,
        },
    })
}

/// The compute queue family (preferring one with timestamps) of a device.
fn compute_family(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<(u32, u32)> {
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let mut best: Option<(u32, u32)> = None;
    for (i, f) in families.iter().enumerate() {
        if f.queue_flags.contains(vk::QueueFlags::COMPUTE) {
            let better = match best {
                None => true,
                Some((_, bits)) => bits == 0 && f.timestamp_valid_bits > 0,
            };
            if better {
                best = Some((i as u32, f.timestamp_valid_bits));
            }
        }
    }
    best
}

fn supports_push_descriptor(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    exts.iter().any(|e| {
        e.extension_name_as_c_str()
            .is_ok_and(|n| n == ash::khr::push_descriptor::NAME)
    })
}

fn device_info(instance: &ash::Instance, pd: vk::PhysicalDevice, timestamp_valid_bits: u32) -> DeviceInfo {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut v11 = vk::PhysicalDeviceVulkan11Properties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut subgroup)
        .push_next(&mut v11)
        .push_next(&mut driver);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let p = props2.properties;
    let l = p.limits;
    let mem = unsafe { instance.get_physical_device_memory_properties(pd) };
    let device_local_bytes = mem.memory_heaps[..mem.memory_heap_count as usize]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);
    let name = p
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver_name = driver
        .driver_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver_info = driver
        .driver_info_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    DeviceInfo {
        name,
        driver: format!("{driver_name} {driver_info}").trim().to_string(),
        device_type: p.device_type,
        api_version: p.api_version,
        max_storage_buffer_range: l.max_storage_buffer_range as u64,
        max_texel_buffer_elements: l.max_texel_buffer_elements,
        max_image_dimension_3d: l.max_image_dimension3_d,
        max_compute_work_group_count: l.max_compute_work_group_count,
        max_compute_work_group_invocations: l.max_compute_work_group_invocations,
        max_compute_shared_memory_size: l.max_compute_shared_memory_size,
        max_push_constants_size: l.max_push_constants_size,
        max_memory_allocation_size: v11.max_memory_allocation_size,
        subgroup_size: subgroup.subgroup_size,
        timestamp_period: l.timestamp_period,
        timestamp_valid_bits,
        device_local_bytes,
        sub_texel_precision_bits: l.sub_texel_precision_bits,
    }
}

fn usable(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let p = unsafe { instance.get_physical_device_properties(pd) };
    p.api_version >= vk::API_VERSION_1_3
        && compute_family(instance, pd).is_some()
        && supports_push_descriptor(instance, pd)
}

fn summaries(instance: &ash::Instance) -> Result<Vec<(vk::PhysicalDevice, DeviceSummary)>> {
    let pds = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    Ok(pds
        .into_iter()
        .enumerate()
        .map(|(index, pd)| {
            let info = device_info(instance, pd, 0);
            let summary = DeviceSummary {
                index,
                name: info.name.clone(),
                device_type: info.type_string().to_string(),
                api: info.api_string(),
                driver: info.driver.clone(),
                usable: usable(instance, pd),
            };
            (pd, summary)
        })
        .collect())
}

/// Every physical device the Vulkan loader reports.
pub fn list_devices() -> Result<Vec<DeviceSummary>> {
    let entry = load_entry()?;
    let instance = create_instance(&entry, false)?;
    let result = summaries(&instance).map(|v| v.into_iter().map(|(_, s)| s).collect());
    unsafe { instance.destroy_instance(None) };
    result
}

/// The physical device lacuna would choose on `instance` (a host's too):
/// `selector` (an index or a name substring, as `LACUNA_DEVICE`), else the
/// first usable discrete GPU, else integrated, virtual, CPU.
pub fn select_device(instance: &ash::Instance, selector: Option<&str>) -> Result<vk::PhysicalDevice> {
    select(instance, selector)
}

fn select(instance: &ash::Instance, selector: Option<&str>) -> Result<vk::PhysicalDevice> {
    let all = summaries(instance)?;
    if all.is_empty() {
        return Err(Error::NoDevice(format!("no Vulkan device found; {INSTALL_HINT}")));
    }
    let listing = || {
        all.iter()
            .map(|(_, s)| format!("{}: {}", s.index, s.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(sel) = selector.filter(|s| !s.is_empty()) {
        let found = match sel.parse::<usize>() {
            Ok(i) => all.iter().find(|(_, s)| s.index == i),
            Err(_) => all
                .iter()
                .find(|(_, s)| s.name.to_lowercase().contains(&sel.to_lowercase())),
        };
        let (pd, s) = found
            .ok_or_else(|| Error::NoDevice(format!("LACUNA_DEVICE '{sel}' matches no device (have {})", listing())))?;
        if !s.usable {
            return Err(Error::NoDevice(format!(
                "device '{}' lacks Vulkan 1.3, a compute queue or VK_KHR_push_descriptor",
                s.name
            )));
        }
        return Ok(*pd);
    }
    let rank = |t: &str| match t {
        "discrete GPU" => 0,
        "integrated GPU" => 1,
        "virtual GPU" => 2,
        "CPU" => 3,
        _ => 4,
    };
    all.iter()
        .filter(|(_, s)| s.usable)
        .min_by_key(|(_, s)| (rank(&s.device_type), s.index))
        .map(|(pd, _)| *pd)
        .ok_or_else(|| {
            Error::NoDevice(format!(
                "no Vulkan 1.3 device with compute and VK_KHR_push_descriptor (have {}); {INSTALL_HINT}",
                listing()
            ))
        })
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
                Self::assemble(Some(entry), instance, pd, device, queue, family, messenger, true)
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
    /// allocator and command pool on them and destroys only those; dropping
    /// the context waits for nothing of the host's (lacuna's own submissions
    /// are waited for by the call that made them).
    ///
    /// Checks first that the device has what lacuna needs (Vulkan 1.3,
    /// [`REQUIRED_EXTENSIONS`], the features of [`required_features`] as
    /// `host.enabled` states them; the extension is also probed on the
    /// device), and returns an error naming the first thing missing.
    ///
    /// # Safety
    /// The host guarantees that:
    /// - `instance`, `physical_device`, `device` and `queue` are valid, belong
    ///   together, and outlive the `Context` and every object made with it;
    /// - `host.enabled` is what the device was created with;
    /// - `queue` is of `queue_family`, and no other thread uses `queue` while a
    ///   lacuna convenience call (`submit_and_wait`: uploads, `build`,
    ///   `render`, downloads) runs, since lacuna submits on it then;
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
            Some(entry) => Some(Messenger::new(entry, &host.instance)?),
            None => None,
        };
        Self::assemble(
            host.entry,
            host.instance,
            host.physical_device,
            host.device,
            host.queue,
            host.queue_family,
            messenger,
            false,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        entry: Option<ash::Entry>,
        instance: ash::Instance,
        pd: vk::PhysicalDevice,
        device: ash::Device,
        queue: vk::Queue,
        family: u32,
        messenger: Option<Messenger>,
        owned: bool,
    ) -> Result<Self> {
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
                command_pool: Mutex::new(pool),
                messenger,
                info,
                owned,
            }),
        })
    }

    pub fn device(&self) -> &ash::Device {
        &self.inner.device
    }

    /// Names a GPU object for validation messages and capture tools (a no-op
    /// without `VK_EXT_debug_utils`).
    pub fn name_object<H: vk::Handle>(&self, handle: H, name: &str) {
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

    fn format_properties(&self, format: vk::Format) -> vk::FormatProperties {
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

    /// Every validation message collected so far (empty without validation).
    pub fn validation_messages(&self) -> Vec<ValidationMessage> {
        self.inner
            .messenger
            .as_ref()
            .map(|m| m.store.lock().unwrap_or_else(|p| p.into_inner()).clone())
            .unwrap_or_default()
    }

    /// Returns and clears the collected validation messages.
    pub fn take_validation_messages(&self) -> Vec<ValidationMessage> {
        self.inner
            .messenger
            .as_ref()
            .map(|m| std::mem::take(&mut *m.store.lock().unwrap_or_else(|p| p.into_inner())))
            .unwrap_or_default()
    }

    pub(crate) fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.inner.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Records commands with `record`, submits them and waits for completion.
    pub fn submit_and_wait<T>(&self, record: impl FnOnce(vk::CommandBuffer) -> Result<T>) -> Result<T> {
        let device = self.device();
        let pool = self.inner.command_pool.lock().unwrap_or_else(|p| p.into_inner());
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        let result = (|| {
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            unsafe { device.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
            let value = record(cmd);
            unsafe { device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
            let value = value?;
            let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            let submitted = {
                let queue = self.inner.queue.lock().unwrap_or_else(|p| p.into_inner());
                unsafe { device.queue_submit2(*queue, &submit, fence) }.vk("vkQueueSubmit2")
            };
            let waited = submitted
                .and_then(|_| unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences"));
            unsafe { device.destroy_fence(fence, None) };
            waited.map(|_| value)
        })();
        unsafe { device.free_command_buffers(*pool, &[cmd]) };
        result
    }
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
            ManuallyDrop::drop(&mut self.allocator);
            self.device
                .destroy_command_pool(*self.command_pool.get_mut().unwrap_or_else(|p| p.into_inner()), None);
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
