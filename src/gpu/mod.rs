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
pub use context::{list_devices, AdoptInfo, Context, ContextOptions, DeviceInfo, DeviceSummary};
pub use gpu_allocator::MemoryLocation;
pub use kernel::{Binding, Kernel};
pub use memory::{Buffer, Image3d};
pub use timer::{Pass, Timer};
pub use validation::ValidationMessage;
