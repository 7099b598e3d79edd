//! Empty space skipping structures. Each structure is a module with the same
//! shape: a builder that records into a caller's command buffer (with a
//! convenience `build` that submits and waits, returning `Timings`), a
//! structure holding what its march kernel reads, and `Stats`. The registry
//! below (`Accel`) is the one line a new structure adds.

pub mod bricks;
pub mod classify;
pub mod grid;
pub mod hybrid;
pub mod kd;
pub mod lbvh;
pub mod morton;
pub mod octree;
mod stats;
pub mod tree;

pub use bricks::GpuBricks;
pub use classify::{Classifier, Classify};
pub use stats::Stats;

use crate::error::{Error, Result};
use crate::gpu::Context;
use crate::prims::BrickMinMax;
use crate::tf::{GpuTransferFunction, TransferFunction};
use crate::timings::Timings;
use crate::volume::{GpuVolume, Volume};

/// The registry of structures, by CLI name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Accel {
    /// Every lattice sample from entry to exit.
    Naive,
    /// Linear BVH over active 8^3 bricks (Karras 2012), built on the GPU.
    Lbvh,
    /// Macro-cell grid (`--cell`), 3D-DDA traversal.
    Grid,
    /// k-d tree built on the multi-core CPU from summed volume tables.
    KdCpu,
    /// k-d tree built with GPU reductions over Morton-ordered bricks.
    KdGpu,
    /// Shallow CPU k-d tree over the macro-cell grid.
    Hybrid,
    /// Octree over active 8^3 bricks, Glassner's 1984 traversal.
    Octree84,
    /// The same octree, Samet's 1989 neighbour-finding traversal.
    Octree89,
    /// The same octree, Gargantini & Atkinson's 1993 traversal.
    Octree93,
    /// The same octree, Revelles et al.'s 2000 parametric traversal.
    OctreeRev,
}

impl Accel {
    pub const ALL: [Accel; 10] = [
        Accel::Naive,
        Accel::Lbvh,
        Accel::Grid,
        Accel::KdCpu,
        Accel::KdGpu,
        Accel::Hybrid,
        Accel::Octree84,
        Accel::Octree89,
        Accel::Octree93,
        Accel::OctreeRev,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Accel::Naive => "naive",
            Accel::Lbvh => "lbvh",
            Accel::Grid => "grid",
            Accel::KdCpu => "kd-cpu",
            Accel::KdGpu => "kd-gpu",
            Accel::Hybrid => "hybrid",
            Accel::Octree84 => "octree-84",
            Accel::Octree89 => "octree-89",
            Accel::Octree93 => "octree-93",
            Accel::OctreeRev => "octree-rev",
        }
    }

    /// The octree traversal of an octree accel.
    pub fn octree_traversal(self) -> Option<crate::octree::Traversal> {
        use crate::octree::Traversal as T;
        match self {
            Accel::Octree84 => Some(T::O84),
            Accel::Octree89 => Some(T::O89),
            Accel::Octree93 => Some(T::O93),
            Accel::OctreeRev => Some(T::Rev),
            _ => None,
        }
    }
}

impl std::str::FromStr for Accel {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Accel::ALL.into_iter().find(|a| a.name() == s).ok_or_else(|| {
            Error::invalid(
                "accel",
                s,
                format!("expected one of: {}", Accel::ALL.map(|a| a.name()).join(", ")),
            )
        })
    }
}

impl std::fmt::Display for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A built structure, ready for its march kernel.
pub enum Structure {
    Naive,
    /// LBVH and k-d trees share the node format and the march kernel.
    Tree(Accel, Box<tree::GpuTree>),
    Grid(Box<grid::Grid>),
    Hybrid(Box<hybrid::Hybrid>),
    /// An octree over active bricks with one of the four traversals.
    Octree(Accel, Box<octree::VolumeOctree>),
}

impl Structure {
    pub fn accel(&self) -> Accel {
        match self {
            Structure::Naive => Accel::Naive,
            Structure::Tree(a, _) => *a,
            Structure::Grid(_) => Accel::Grid,
            Structure::Hybrid(_) => Accel::Hybrid,
            Structure::Octree(a, _) => *a,
        }
    }

    /// The paper's Table 1 statistics (None for naive). May read the
    /// structure back once; builds never do.
    pub fn stats(&self) -> Result<Option<Stats>> {
        Ok(match self {
            Structure::Naive => None,
            Structure::Tree(_, t) => Some(t.stats()?),
            Structure::Grid(g) => Some(g.stats()?),
            Structure::Hybrid(h) => Some(h.tree.stats()?),
            Structure::Octree(_, o) => Some(o.stats),
        })
    }

    /// The tree, for structures that have one.
    pub fn tree(&self) -> Option<&tree::GpuTree> {
        match self {
            Structure::Tree(_, t) => Some(t),
            Structure::Hybrid(h) => Some(&h.tree),
            _ => None,
        }
    }
}

/// What a build reads: the volume and transfer function on the host (the CPU
/// k-d tree) and on the GPU (everything else).
pub struct Scene<'a> {
    pub volume: &'a Volume,
    pub gpu_volume: &'a GpuVolume,
    pub tf: &'a TransferFunction,
    pub gpu_tf: &'a GpuTransferFunction,
}

/// Parameters of every structure (the paper's columns).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct BuildOptions {
    pub classify: Classify,
    pub kd: kd::KdParams,
    /// Macro-cell edge of the grid and the hybrid (a power of two).
    pub cell: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            classify: Classify::Range,
            kd: kd::KdParams::default(),
            cell: grid::CELL,
        }
    }
}

/// Per-volume value ranges: 8^3 bricks (LBVH) and macro cells (grid, hybrid).
pub struct Ranges {
    /// 8^3 brick ranges (the LBVH); None if not computed.
    pub bricks: Option<GpuBricks>,
    /// Macro-cell ranges (grid, hybrid); None if not computed.
    pub cells: Option<GpuBricks>,
}

impl Ranges {
    fn bricks(&self) -> Result<&GpuBricks> {
        self.bricks.as_ref().ok_or_else(|| {
            Error::invalid(
                "ranges",
                "cells only",
                "the LBVH and the octrees need 8^3 brick ranges (Builder::ranges)",
            )
        })
    }

    fn cells(&self, cell: u32) -> Result<&GpuBricks> {
        match &self.cells {
            Some(c) if c.brick == cell => Ok(c),
            Some(c) => Err(Error::invalid(
                "cell",
                cell.to_string(),
                format!("ranges were computed for cells of {}", c.brick),
            )),
            None => Err(Error::invalid(
                "ranges",
                "bricks only",
                "the grid and hybrid need cell ranges (Builder::ranges)",
            )),
        }
    }
}

/// Builds every structure; kernels are created once per context.
pub struct Builder {
    ctx: Context,
    minmax: BrickMinMax,
    classifier: Classifier,
    lbvh: lbvh::LbvhBuilder,
    kd_gpu: kd::gpu::KdGpuBuilder,
}

impl Builder {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Builder {
            ctx: ctx.clone(),
            minmax: BrickMinMax::new(ctx)?,
            classifier: Classifier::new(ctx)?,
            lbvh: lbvh::LbvhBuilder::new(ctx)?,
            kd_gpu: kd::gpu::KdGpuBuilder::new(ctx)?,
        })
    }

    /// Per-brick and per-cell value ranges: once per volume upload
    /// ("ranges", "cell ranges").
    pub fn ranges(&self, volume: &GpuVolume, cell: u32) -> Result<(Ranges, Timings)> {
        self.ranges_for(&Accel::ALL, volume, cell)
    }

    /// Only the ranges `accels` use: brick ranges for the LBVH and the octrees, cell ranges
    /// for the grid and the hybrid, none for naive and the k-d trees.
    pub fn ranges_for(&self, accels: &[Accel], volume: &GpuVolume, cell: u32) -> Result<(Ranges, Timings)> {
        grid::check_cell(cell)?;
        let mut t = Timings::default();
        let mut ranges = Ranges {
            bricks: None,
            cells: None,
        };
        if accels
            .iter()
            .any(|a| *a == Accel::Lbvh || a.octree_traversal().is_some())
        {
            let (b, tb) = GpuBricks::compute(&self.ctx, &self.minmax, volume, bricks::BRICK)?;
            t.extend(tb);
            ranges.bricks = Some(b);
        }
        if accels.iter().any(|a| matches!(a, Accel::Grid | Accel::Hybrid)) {
            let (c, tc) = GpuBricks::compute(&self.ctx, &self.minmax, volume, cell)?;
            t.push("cell ranges", tc.get("ranges").unwrap_or(0.0));
            ranges.cells = Some(c);
        }
        Ok((ranges, t))
    }

    pub fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    pub fn lbvh(&self) -> &lbvh::LbvhBuilder {
        &self.lbvh
    }

    /// Builds `accel` for the scene's transfer function: the path a TF change
    /// takes. Returns the structure and its timings per phase.
    pub fn build(
        &self,
        accel: Accel,
        scene: &Scene,
        ranges: &Ranges,
        options: &BuildOptions,
    ) -> Result<(Structure, Timings)> {
        let (v, tf) = (scene.gpu_volume, scene.gpu_tf);
        match accel {
            Accel::Naive => Ok((Structure::Naive, Timings::default())),
            Accel::Lbvh => {
                let (l, t) = self
                    .lbvh
                    .build(&self.classifier, options.classify, v, ranges.bricks()?, tf)?;
                Ok((Structure::Tree(Accel::Lbvh, Box::new(l)), t))
            }
            Accel::Grid => {
                let (g, t) = grid::build(&self.ctx, &self.classifier, v, ranges.cells(options.cell)?, tf)?;
                Ok((Structure::Grid(Box::new(g)), t))
            }
            Accel::KdCpu => {
                let (tree, t) = kd::cpu::build(&self.ctx, scene.volume, scene.tf, &options.kd)?;
                Ok((Structure::Tree(Accel::KdCpu, Box::new(tree)), t))
            }
            Accel::KdGpu => {
                let (tree, t) = self.kd_gpu.build(v, tf, &options.kd)?;
                Ok((Structure::Tree(Accel::KdGpu, Box::new(tree)), t))
            }
            Accel::Hybrid => {
                let shallow = kd::KdParams {
                    depth: kd::Depth::Shallow,
                    ..options.kd
                };
                let (tree, mut t) = kd::cpu::build(&self.ctx, scene.volume, scene.tf, &shallow)?;
                let (g, tg) = grid::build(&self.ctx, &self.classifier, v, ranges.cells(options.cell)?, tf)?;
                t.extend(tg);
                Ok((
                    Structure::Hybrid(Box::new(hybrid::Hybrid {
                        tree,
                        grid: *Box::new(g),
                    })),
                    t,
                ))
            }
            Accel::Octree84 | Accel::Octree89 | Accel::Octree93 | Accel::OctreeRev => {
                let traversal = accel.octree_traversal().expect("an octree accel");
                let (o, t) = octree::build(
                    &self.ctx,
                    &self.classifier,
                    options.classify,
                    v,
                    ranges.bricks()?,
                    tf,
                    traversal,
                )?;
                Ok((Structure::Octree(accel, Box::new(o)), t))
            }
        }
    }
}
