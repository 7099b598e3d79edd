//! Naive marching: every lattice sample from the ray's entry to its exit.
//! The reference every other structure's image must equal bit for bit.

use super::registry::{BuildInput, BuildOptions, Builder, Built, March, Method, RangeKind, Ranges};
use super::stats::Stats;
use crate::error::Result;
use crate::gpu::{shaders, vk, Binding, Timer};

pub struct Naive;

/// Nothing to build and nothing to bind.
pub(crate) struct NoData;

impl Built for NoData {
    fn bindings(&self) -> Vec<Binding<'_>> {
        Vec::new()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        Ok(None)
    }
}

impl Method for Naive {
    fn name(&self) -> &'static str {
        "naive"
    }
    fn description(&self) -> &'static str {
        "every lattice sample from entry to exit (the reference)"
    }
    fn ranges(&self) -> RangeKind {
        RangeKind::None
    }
    fn params(&self, _: &BuildOptions) -> Vec<(&'static str, String)> {
        Vec::new()
    }
    fn march(&self) -> March {
        March::plain(shaders::MARCH_NAIVE)
    }
    fn record_build(
        &self,
        _: &Builder,
        _: vk::CommandBuffer,
        _: Option<&mut Timer>,
        _: &BuildInput,
        _: &Ranges,
        _: &BuildOptions,
    ) -> Result<Box<dyn Built>> {
        Ok(Box::new(NoData))
    }
}
