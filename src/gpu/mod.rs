//! The thin `ash` layer: loader and instance, device selection and
//! requirements, the context (own or adopted), memory, kernels from the
//! reflected shaders (each made once per context, from SPIR-V pruned of
//! what its specialization constants rule out: `prune`), recording and barriers,
//! timestamp timer and timings, validation messenger, and the deferred
//! destruction of what a submission in flight may use (`retire`). Imports nothing of
//! lacuna but `error`.

mod binding;
mod context;
mod device;
mod host_read;
mod image;
mod instance;
mod kernel;
mod kernel_cache;
mod memory;
mod order;
mod prune;
pub mod record;
mod requirements;
mod retire;
pub mod shaders;
mod submit;
mod timer;
pub mod timings;
mod validation;

pub use ash::vk;
pub use binding::{Binding, Bound};
pub use context::{Context, ContextOptions};
pub use device::{list_devices, select_device, DeviceInfo, DeviceSummary};
pub use gpu_allocator::MemoryLocation;
pub use kernel::Kernel;
pub use record::{Access, Recording};
pub use requirements::{required_features, AdoptInfo, EnabledFeatures, REQUIRED_EXTENSIONS};
pub(crate) use retire::Retired;
pub use shaders::{LocalDim, Shader};

/// Compile-time check that a host type is laid out as a struct the shaders
/// declare (generated into `shaders::blocks` from the SPIR-V): the same size,
/// and each named field at the offset of the shader member it pairs with.
/// A member renamed in the GLSL fails to compile here; one moved or resized
/// fails the assertion.
macro_rules! check_layout {
    ($host:ty => $shader:ty { $($field:ident : $member:ident),* $(,)? }) => {
        const _: () = {
            assert!(
                std::mem::size_of::<$host>() == std::mem::size_of::<$shader>(),
                concat!(stringify!($host), " and ", stringify!($shader), " differ in size")
            );
            $(assert!(
                std::mem::offset_of!($host, $field) == std::mem::offset_of!($shader, $member),
                concat!(stringify!($host), ".", stringify!($field), " is not at ", stringify!($shader), ".", stringify!($member))
            );)*
        };
    };
}
pub(crate) use check_layout;
pub use host_read::HostRead;
pub use image::{check_image3d, check_image3d_of, Image3d};
pub use memory::{Buffer, Staging, TexelBuffer};
pub use timer::{OptionalTimer, Pass, Timer};
pub use timings::Timings;
pub use validation::ValidationMessage;
