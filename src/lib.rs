//! lacuna: a Vulkan-native direct volume renderer for comparing empty space
//! skipping structures. The README follows (its example is compiled as a doc test).
#![doc = include_str!("../README.md")]
// Bad input is an `Error`, never a panic: no unwrap/expect outside tests
// (the few invariants that remain carry an `allow` saying why).
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

// Layers, each using only those below it: cli (the binary) -> bench ->
// render / octree -> accel -> prims / spatial / scene -> desc / parallel ->
// volume / tf / frame -> gpu; limits and error are used by all.
pub mod accel;
#[cfg(feature = "bench")]
pub mod bench;
pub mod desc;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod limits;
pub mod octree;
pub mod parallel;
pub mod prims;
pub mod render;
pub mod scene;
pub mod spatial;
pub mod tf;
pub mod volume;

// The versions of the crates whose types the public API takes (`ash`'s
// handles in `gpu::AdoptInfo`, `glam`'s matrices in `render::CameraMatrices`),
// so an engine need not pin the same versions itself.
pub use ash;
pub use glam;

pub use error::{Error, Result};
pub use gpu::Timings;

pub use tf::TransferFunction;
pub use volume::Volume;
