//! Hybrid grid (Zellmann et al. 2019): a shallow k-d tree (few leaves) over
//! the global macro-cell grid. `glsl/march/hybrid.comp` traverses the tree to
//! a leaf, then steps through the grid's cells inside it by 3D-DDA.

use super::classify::Classifier;
use super::grid::{self, Grid, GridPush};
use super::kd;
use super::registry::{BuildInput, BuildOptions, Builder, Built, March, Method, RangeKind, Ranges};
use super::stats::Stats;
use super::tree::GpuTree;
use crate::error::Result;
use crate::gpu::timings::Timings;
use crate::gpu::{shaders, Binding, Timer};

pub struct Hybrid {
    pub tree: GpuTree,
    pub grid: Grid,
}

/// `--accel hybrid`.
pub struct HybridMethod;

impl Method for HybridMethod {
    fn name(&self) -> &'static str {
        "hybrid"
    }
    fn description(&self) -> &'static str {
        "shallow CPU k-d tree over the macro-cell grid (Zellmann et al. 2019)"
    }
    fn ranges(&self) -> RangeKind {
        RangeKind::Cells
    }
    fn params(&self, o: &BuildOptions) -> Vec<(&'static str, String)> {
        vec![("cell", o.cell.to_string())]
    }
    fn march(&self) -> March {
        March {
            shader: shaders::MARCH_HYBRID,
            constants: &[],
            push_size: std::mem::size_of::<GridPush>(),
        }
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
        options: &BuildOptions,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let ctx = builder.context();
        let shallow = kd::KdParams {
            depth: kd::Depth::Shallow,
            ..options.kd
        };
        let (tree, mut t) = kd::cpu::build(ctx, input.volume, input.tf, &shallow, None)?;
        let classifier = builder.kernels::<Classifier>()?;
        let cells = ranges.cells(options.cell)?;
        let mut timer = Timer::new(ctx, 1)?;
        let grid = ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            grid::record(
                ctx,
                &classifier,
                cmd,
                Some(&mut timer),
                input.gpu_volume,
                cells,
                input.gpu_tf,
            )
        })?;
        t.extend(timer.results()?);
        Ok((Box::new(Hybrid { tree, grid }), t))
    }
}

impl Built for Hybrid {
    fn bindings(&self) -> Vec<Binding<'_>> {
        vec![
            Binding::Storage(&self.tree.nodes),
            Binding::Storage(&self.tree.count),
            Binding::Storage(&self.grid.flags),
        ]
    }
    fn push(&self) -> Vec<u8> {
        bytemuck::bytes_of(&self.grid.push()).to_vec()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        self.tree.stats().map(Some)
    }
    fn tree(&self) -> Option<&GpuTree> {
        Some(&self.tree)
    }
}
