//! Naive marching: every lattice sample from the ray's entry to its exit.
//! The reference every other structure's image must equal bit for bit.

use super::builder::{Builder, RangeKind, Ranges};
use super::method::{Accel, BuildInput, Built, March, Method, Structure};
use super::params::Params;
use super::stats::Stats;
use crate::desc::Mode;
use crate::error::Result;
use crate::gpu::Recording;
use crate::gpu::{shaders, Bound, Timer};

/// Naive marching (`--accel naive`): every lattice sample, the reference.
pub struct Naive;

/// The naive entry (what a tree of one leaf covering the volume, or `auto`
/// finding nothing to skip, is marched as).
pub const NAIVE: Accel = Accel(&Naive);

/// Nothing to build and nothing to bind.
pub(crate) struct NoData;

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for NoData {
    fn bindings(&self) -> Vec<Bound<'_>> {
        Vec::new()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        Ok(None)
    }
}

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for Naive {
    fn name(&self) -> &'static str {
        "naive"
    }
    fn description(&self) -> &'static str {
        "every lattice sample from entry to exit (the reference)"
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::None)
    }
    fn skips(&self) -> bool {
        false
    }
    fn march(&self) -> March {
        March::plain(shaders::MARCH_NAIVE)
    }
    /// Every mode: the reference.
    fn marches(&self, _: &Mode) -> bool {
        true
    }
    fn record_build(
        &self,
        _: &Builder,
        _: Recording<'_>,
        _: Option<&mut Timer>,
        _: &BuildInput,
        _: &Ranges,
        _: &Params,
    ) -> Result<Box<dyn Built>> {
        Ok(Box::new(NoData))
    }
}

impl Structure {
    /// Naive marching: no structure at all.
    pub fn naive() -> Structure {
        Structure {
            accel: NAIVE,
            params: Params::default(),
            mode: None,
            volume: None,
            built_for: None,
            made_on: None,
            built: Box::new(NoData),
            _keep: None,
        }
    }
}
