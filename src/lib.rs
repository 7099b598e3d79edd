//! lacuna: a Vulkan-native direct volume renderer for comparing empty space
//! skipping structures. See `README.md` and `docs/` for the design.

pub mod accel;
pub mod error;
pub mod gpu;
pub mod timings;

pub use error::{Error, Result};
pub use timings::Timings;
pub mod prims;
pub mod render;
pub mod tf;
pub mod volume;

pub use tf::TransferFunction;
pub use volume::Volume;
