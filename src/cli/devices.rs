//! `lacuna devices`: the Vulkan devices and whether lacuna can use them.

use lacuna::{Error, Result};
use std::process::ExitCode;

pub fn run() -> Result<ExitCode> {
    let list = lacuna::gpu::list_devices()?;
    if list.is_empty() {
        return Err(Error::NoDevice(
            "no Vulkan device found; install a driver (Debian: apt install mesa-vulkan-drivers libvulkan1)".into(),
        ));
    }
    for d in list {
        say!(
            "{}: {} ({}, Vulkan {}, {}){}",
            d.index,
            d.name,
            d.device_type,
            d.api,
            d.driver,
            if d.usable {
                ""
            } else {
                " [unusable: needs Vulkan 1.3, compute, VK_KHR_push_descriptor, subgroup vote]"
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}
