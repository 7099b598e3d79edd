//! Empty space skipping structures. The contract (`method`: the [`Method`]
//! trait, [`Built`], [`Accel`], [`Structure`]), what builds share
//! (`builder`: the context, per-context kernels, per-volume ranges) and
//! parameter schemas (`params`) know no structure; each structure is one
//! module implementing [`Method`]; `table` lists them, above them all. The
//! CLI, bench and tests iterate [`TABLE`]; see `docs/structures.md` for
//! what adding a structure touches.

pub mod auto;
pub mod bricks;
mod bricks_host;
mod build;
pub mod builder;
pub mod classify;
pub mod cost;
pub mod distance;
mod distance_host;
pub mod grid;
pub mod hybrid;
pub mod kd;
pub mod kernels;
pub mod lbvh;
pub mod method;
pub mod mode;
pub mod morton;
pub mod naive;
pub mod octree;
pub mod params;
pub mod probe;
mod stats;
pub mod table;
pub mod tree;

pub use bricks::GpuBricks;
pub use builder::{check_cell, Builder, PerContext, RangeKind, Ranges};
pub use classify::{Classifier, Classify};
pub use cost::CostModel;
pub use method::{Accel, BuildInput, Built, March, MarchedAs, MarchedKind, Method, Structure};
pub use params::{Param, Params};
pub use stats::Stats;
pub use table::TABLE;
