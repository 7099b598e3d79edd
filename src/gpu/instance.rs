//! The Vulkan loader and instance lacuna creates for a headless context
//! (with the validation layer and its synchronization validation on request).

use super::validation::VALIDATION_LAYER;
use crate::error::{Error, Result, VkContext};
use ash::vk;

pub(crate) const INSTALL_HINT: &str =
    "install a Vulkan driver (Debian/Ubuntu CPU driver: apt install mesa-vulkan-drivers libvulkan1)";

pub(crate) fn load_entry() -> Result<ash::Entry> {
    unsafe { ash::Entry::load() }.map_err(|e| Error::NoDevice(format!("no Vulkan loader found ({e}); {INSTALL_HINT}")))
}

pub(crate) fn create_instance(entry: &ash::Entry, validation: bool) -> Result<ash::Instance> {
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
