//! What lacuna needs of a device, and what a host lends when it adopts its
//! own device into lacuna (`Context::adopt` checks one against the other).

use ash::vk;

/// The handles a host engine lends to lacuna. The device must have been
/// created with Vulkan 1.3, the extensions of [`REQUIRED_EXTENSIONS`] and the
/// features [`required_features`] sets, on a device with subgroup vote
/// operations in compute shaders, and `enabled` must say what it was
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

/// Whether the device's compute kernels can vote across a subgroup
/// (`subgroupAny`: the march kernels light a group's samples only once one
/// of its lanes has a visible one). Not core in Vulkan 1.3, but every
/// desktop driver and lavapipe have it.
pub(crate) fn has_subgroup_vote(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
        && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::VOTE)
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
pub(crate) fn missing_requirement(
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
    // After the instance's version: the query is Vulkan 1.1's.
    if !has_subgroup_vote(instance, pd) {
        return Some("subgroup vote operations in compute shaders".to_string());
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
