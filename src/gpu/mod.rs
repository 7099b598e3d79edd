//! The thin `ash` layer: context (own or adopted), memory, kernels,
//! recording and barriers, timestamp timer, validation messenger.

mod context;
mod kernel;
mod memory;
pub mod record;
pub mod shaders;
mod timer;
mod validation;

pub use ash::vk;
pub use context::{
    list_devices, required_features, select_device, AdoptInfo, Context, ContextOptions, DeviceInfo, DeviceSummary,
    EnabledFeatures, REQUIRED_EXTENSIONS,
};
pub use gpu_allocator::MemoryLocation;
pub use kernel::{Binding, Kernel};
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
pub use validation::ValidationMessage;
