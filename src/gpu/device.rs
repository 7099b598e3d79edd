//! Physical devices: what lacuna reads of one (`DeviceInfo`), the listing
//! `lacuna devices` prints, and the choice of device (`LACUNA_DEVICE`, else
//! the first usable discrete GPU, integrated, virtual, CPU).

use super::instance::{create_instance, load_entry, INSTALL_HINT};
use super::requirements::has_subgroup_vote;
use crate::error::{Error, Result, VkContext};
use ash::vk;

/// lavapipe's cap on a shader's loop passes (`DeviceInfo::loop_pass_limit`).
const LLVMPIPE_LOOP_PASSES: u64 = 65535;

/// Facts about the device that lacuna checks before using it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub driver: String,
    /// The driver's version and pipeline cache UUID: what a device-specific
    /// cache (auto's cost model) is kept under.
    pub driver_version: u32,
    pub pipeline_cache_uuid: [u8; 16],
    pub device_type: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub max_storage_buffer_range: u64,
    pub max_uniform_buffer_range: u64,
    pub max_texel_buffer_elements: u32,
    pub max_image_dimension_3d: u32,
    pub max_compute_work_group_count: [u32; 3],
    pub max_compute_work_group_invocations: u32,
    pub max_compute_work_group_size: [u32; 3],
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
    /// Storage buffer descriptors' offsets are multiples of this.
    pub min_storage_buffer_offset_alignment: u64,
    /// Loop passes one SIMD group may run in a dispatch, all of a kernel's
    /// loops together, where the driver caps them: lavapipe (llvmpipe)
    /// silently ends every loop of a shader once they have run 65535 passes
    /// between them (Mesa's `LP_MAX_TGSI_LOOP_ITERATIONS`), so a longer
    /// march would stop short: bounded before a frame is recorded
    /// (`limits::check_loop_passes`) and checked by the march itself after
    /// (`Renderer::check_whole`).
    pub loop_pass_limit: Option<u64>,
}

impl DeviceInfo {
    /// Whether the device is the host's CPU (lavapipe, SwiftShader): its
    /// memory is the host's.
    pub fn is_cpu(&self) -> bool {
        self.device_type == vk::PhysicalDeviceType::CPU
    }

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

    /// Fails, naming the limit, when a storage buffer of `bytes` read as
    /// `texels` texels exceeds `maxStorageBufferRange` or
    /// `maxTexelBufferElements` (checked in that order).
    pub fn check_texel_buffer(&self, what: impl Into<String>, bytes: u64, texels: u64) -> Result<()> {
        let what = what.into();
        self.check(
            what.clone(),
            "maxStorageBufferRange",
            bytes,
            self.max_storage_buffer_range,
        )?;
        self.check(
            what,
            "maxTexelBufferElements",
            texels,
            self.max_texel_buffer_elements as u64,
        )
    }

    /// The limit `check_texel_buffer` would name, if any.
    pub fn exceeded_buffer_limit(&self, bytes: u64, texels: u64) -> Option<&'static str> {
        match self.check_texel_buffer("", bytes, texels) {
            Err(Error::DeviceLimit { limit, .. }) => Some(limit),
            _ => None,
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

/// The compute queue family (preferring one with timestamps) of a device.
pub(crate) fn compute_family(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<(u32, u32)> {
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

pub(crate) fn device_info(instance: &ash::Instance, pd: vk::PhysicalDevice, timestamp_valid_bits: u32) -> DeviceInfo {
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
        driver_version: p.driver_version,
        pipeline_cache_uuid: p.pipeline_cache_uuid,
        device_type: p.device_type,
        api_version: p.api_version,
        max_storage_buffer_range: l.max_storage_buffer_range as u64,
        max_uniform_buffer_range: l.max_uniform_buffer_range as u64,
        max_texel_buffer_elements: l.max_texel_buffer_elements,
        max_image_dimension_3d: l.max_image_dimension3_d,
        max_compute_work_group_count: l.max_compute_work_group_count,
        max_compute_work_group_invocations: l.max_compute_work_group_invocations,
        max_compute_work_group_size: l.max_compute_work_group_size,
        max_compute_shared_memory_size: l.max_compute_shared_memory_size,
        max_push_constants_size: l.max_push_constants_size,
        max_memory_allocation_size: v11.max_memory_allocation_size,
        subgroup_size: subgroup.subgroup_size,
        timestamp_period: l.timestamp_period,
        timestamp_valid_bits,
        device_local_bytes,
        sub_texel_precision_bits: l.sub_texel_precision_bits,
        min_storage_buffer_offset_alignment: l.min_storage_buffer_offset_alignment,
        loop_pass_limit: (driver.driver_id == vk::DriverId::MESA_LLVMPIPE).then_some(LLVMPIPE_LOOP_PASSES),
    }
}

fn usable(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let p = unsafe { instance.get_physical_device_properties(pd) };
    p.api_version >= vk::API_VERSION_1_3
        && compute_family(instance, pd).is_some()
        && supports_push_descriptor(instance, pd)
        && has_subgroup_vote(instance, pd)
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

pub(crate) fn select(instance: &ash::Instance, selector: Option<&str>) -> Result<vk::PhysicalDevice> {
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
                "device '{}' lacks Vulkan 1.3, a compute queue, VK_KHR_push_descriptor or subgroup vote",
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
                "no Vulkan 1.3 device with compute, VK_KHR_push_descriptor and subgroup vote (have {}); {INSTALL_HINT}",
                listing()
            ))
        })
}
