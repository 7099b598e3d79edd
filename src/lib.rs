//! lacuna: a Vulkan-native direct volume renderer for comparing empty space
//! skipping structures. The README follows (its example is compiled as a doc test).
#![doc = include_str!("../README.md")]

// Layers, each using only those below it: cli (the binary) -> bench ->
// render / octree -> accel -> prims / spatial / scene -> volume / tf / frame
// -> gpu.
pub mod accel;
#[cfg(feature = "bench")]
pub mod bench;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod octree;
pub mod prims;
pub mod render;
pub mod scene;
pub mod spatial;
pub mod tf;
pub mod timings;
pub mod volume;

pub use error::{Error, Result};
pub use timings::Timings;

pub use tf::TransferFunction;
pub use volume::Volume;
