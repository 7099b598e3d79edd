//! lacuna: a Vulkan-native direct volume renderer for comparing empty space
//! skipping structures. The README follows (its example is compiled as a doc test).
#![doc = include_str!("../README.md")]

pub mod accel;
pub mod bench;
pub mod error;
pub mod gpu;
pub mod timings;

pub use error::{Error, Result};
pub use timings::Timings;
pub mod octree;
pub mod prims;
pub mod render;
pub mod scene;
pub mod tf;
pub mod volume;

pub use tf::TransferFunction;
pub use volume::Volume;
