//! Hybrid grid (Zellmann et al. 2019): a shallow k-d tree (few leaves) over
//! the global macro-cell grid. `glsl/march/hybrid.comp` traverses the tree to
//! a leaf, then steps through the grid's cells inside it by 3D-DDA.

use super::grid::Grid;
use super::tree::GpuTree;

pub struct Hybrid {
    pub tree: GpuTree,
    pub grid: Grid,
}
