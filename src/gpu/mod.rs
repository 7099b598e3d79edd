//! The thin `ash` layer: loader and instance, device selection and
//! requirements, the context (own or adopted), memory, kernels from the
//! reflected shaders, recording and barriers, timestamp timer and timings,
//! validation messenger. Imports nothing of lacuna but `error`.

mod context;
mod device;
mod instance;
mod kernel;
mod memory;
pub mod record;
mod requirements;
pub mod shaders;
mod timer;
pub mod timings;
mod validation;

pub use ash::vk;
pub use context::{Context, ContextOptions};
pub use device::{list_devices, select_device, DeviceInfo, DeviceSummary};
pub use gpu_allocator::MemoryLocation;
pub use kernel::{Binding, Kernel};
pub use requirements::{required_features, AdoptInfo, EnabledFeatures, REQUIRED_EXTENSIONS};
pub use shaders::{LocalDim, Shader};

/// Compile-time check that a `#[repr(C)]` push-constant block has the size of
/// the shader's block as reflected from its SPIR-V.
macro_rules! check_push {
    ($ty:ty, $shader:expr) => {
        const _: () = assert!(
            std::mem::size_of::<$ty>() == $shader.push_size as usize,
            concat!(
                "push block ",
                stringify!($ty),
                " does not match the shader ",
                stringify!($shader)
            )
        );
    };
}
pub(crate) use check_push;
pub use memory::{check_image3d, Buffer, Image3d, Staging, TexelBuffer};
pub use timer::{OptionalTimer, Pass, Timer};
pub use timings::Timings;
pub use validation::ValidationMessage;
