//! Empty space skipping structures. A structure is one module that
//! implements [`Method`] (what it reads, how it builds, which march kernel
//! renders it, its parameters and statistics) plus one line in [`TABLE`].
//! The builder, renderer, CLI, bench and tests all iterate the table; see
//! `docs/structures.md` for the checklist.

pub mod auto;
pub mod bricks;
pub mod classify;
pub mod cost;
pub mod distance;
pub mod grid;
pub mod hybrid;
pub mod kd;
pub mod lbvh;
pub mod morton;
pub mod naive;
pub mod octree;
mod registry;
mod stats;
pub mod tree;

pub use bricks::GpuBricks;
pub use classify::{Classifier, Classify};
pub use cost::CostModel;
pub use registry::{
    parse_collapse, Accel, BuildInput, BuildOptions, Builder, Built, KernelSet, March, Method, RangeKind, Ranges,
    Structure, TABLE,
};
pub use stats::Stats;
