//! Empty space skipping structures. Each structure is a module with the same
//! shape: a builder that records into a caller's command buffer (with a
//! convenience `build` that submits and waits, returning `Timings`), a
//! structure holding what its march kernel reads, and `Stats`. The registry
//! below (`Accel`) is the one line a new structure adds.

pub mod bricks;
pub mod classify;
pub mod lbvh;
pub mod morton;
mod stats;

pub use bricks::GpuBricks;
pub use classify::{Classifier, Classify};
pub use stats::Stats;

use crate::error::{Error, Result};
use crate::gpu::Context;
use crate::prims::BrickMinMax;
use crate::tf::GpuTransferFunction;
use crate::timings::Timings;
use crate::volume::GpuVolume;

/// The registry of structures, by CLI name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Accel {
    /// Every lattice sample from entry to exit.
    Naive,
    /// Linear BVH over active 8^3 bricks (Karras 2012), built on the GPU.
    Lbvh,
}

impl Accel {
    pub const ALL: [Accel; 2] = [Accel::Naive, Accel::Lbvh];

    pub fn name(self) -> &'static str {
        match self {
            Accel::Naive => "naive",
            Accel::Lbvh => "lbvh",
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
    Lbvh(Box<lbvh::Lbvh>),
}

impl Structure {
    pub fn accel(&self) -> Accel {
        match self {
            Structure::Naive => Accel::Naive,
            Structure::Lbvh(_) => Accel::Lbvh,
        }
    }

    pub fn stats(&self) -> Option<Stats> {
        match self {
            Structure::Naive => None,
            Structure::Lbvh(l) => Some(l.stats),
        }
    }
}

/// Builds every structure; kernels are created once per context.
pub struct Builder {
    ctx: Context,
    minmax: BrickMinMax,
    classifier: Classifier,
    lbvh: lbvh::LbvhBuilder,
}

impl Builder {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Builder {
            ctx: ctx.clone(),
            minmax: BrickMinMax::new(ctx)?,
            classifier: Classifier::new(ctx)?,
            lbvh: lbvh::LbvhBuilder::new(ctx)?,
        })
    }

    /// Per-brick value ranges: once per volume upload ("ranges").
    pub fn bricks(&self, volume: &GpuVolume) -> Result<(GpuBricks, Timings)> {
        GpuBricks::compute(&self.ctx, &self.minmax, volume)
    }

    pub fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    pub fn lbvh(&self) -> &lbvh::LbvhBuilder {
        &self.lbvh
    }

    /// Builds `accel` for a transfer function: the path a TF change takes.
    pub fn build(
        &self,
        accel: Accel,
        volume: &GpuVolume,
        bricks: &GpuBricks,
        tf: &GpuTransferFunction,
        classify: Classify,
    ) -> Result<(Structure, Timings)> {
        match accel {
            Accel::Naive => Ok((Structure::Naive, Timings::default())),
            Accel::Lbvh => {
                let (l, t) = self.lbvh.build(&self.classifier, classify, volume, bricks, tf)?;
                Ok((Structure::Lbvh(Box::new(l)), t))
            }
        }
    }
}
