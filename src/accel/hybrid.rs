//! Hybrid grid (Zellmann et al. 2019): a shallow k-d tree (few leaves) over
//! the global macro-cell grid. `glsl/march/hybrid.comp` traverses the tree to
//! a leaf, then steps through the grid's cells inside it by 3D-DDA.

use super::builder::{Builder, RangeKind, Ranges};
use super::grid::{self, Grid};
use super::kd;
use super::method::{BuildInput, Built, March, Method};
use super::params::{Param, Params};
use super::stats::Stats;
use super::tree::GpuTree;
use crate::error::Result;
use crate::gpu::shaders::{self, march_hybrid};
use crate::gpu::{Binding, Bound, Timer, Timings};

/// A shallow k-d tree whose leaves are marched through the macro-cell grid
/// (`--accel hybrid`).
pub struct Hybrid {
    pub tree: GpuTree,
    pub grid: Grid,
}

/// `--accel hybrid`.
pub struct HybridMethod;

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for HybridMethod {
    fn name(&self) -> &'static str {
        "hybrid"
    }
    fn description(&self) -> &'static str {
        "shallow CPU k-d tree over the macro-cell grid (Zellmann et al. 2019)"
    }
    fn params(&self) -> &'static [Param] {
        &[grid::CELL_PARAM]
    }
    fn ranges(&self, p: &Params) -> Result<RangeKind> {
        Ok(RangeKind::Cells(p.int("cell")?))
    }
    fn march(&self) -> March {
        March::plain(shaders::MARCH_HYBRID)
    }
    /// Host-driven: the tree is built on the CPU, the grid on the GPU.
    fn recordable(&self) -> bool {
        false
    }
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let ctx = builder.context();
        let shallow = kd::KdParams {
            depth: kd::Depth::Shallow,
            ..kd::KdParams::default()
        };
        let (tree, mut t) = kd::cpu::build(ctx, input.volume, input.tf, &shallow, None)?;
        let cells = ranges.cells(p.int("cell")?)?;
        let mut timer = Timer::new(ctx, 1)?;
        let grid = ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            grid::record(builder, cmd, Some(&mut timer), input, cells)
        })?;
        t.extend(timer.results()?);
        Ok((Box::new(Hybrid { tree, grid }), t))
    }
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for Hybrid {
    fn bindings(&self) -> Vec<Bound<'_>> {
        march_hybrid::Own {
            nodes: Binding::Storage(&self.tree.nodes),
            count: Binding::Storage(&self.tree.count),
            cell_flags: Binding::Texels(&self.grid.flags),
        }
        .list()
    }
    fn push(&self) -> Vec<u8> {
        bytemuck::bytes_of(&self.grid.push()).to_vec()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        self.tree.stats().map(Some)
    }
}
