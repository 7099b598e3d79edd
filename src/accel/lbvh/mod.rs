//! Linear BVH over the active 8^3 bricks, built entirely on the GPU:
//! classification, compaction of active bricks, 30-bit Morton codes of brick
//! coordinates, radix sort, Karras 2012 hierarchy emit (one invocation per
//! internal node, ties broken by index), and a bottom-up refit (one
//! invocation per leaf; the second to reach a node continues).
//!
//! Node format (32 bytes; `glsl/common/bvh_node.glsl`): `lo: [i32; 4]`,
//! `hi: [i32; 4]`. `lo[0..3]`/`hi[0..3]` are the node's box in voxel units
//! (leaves: the brick's footprint clipped to the volume). `lo[3]` is the left
//! child, or -1 for a leaf; `hi[3]` is the right child, or a leaf's brick
//! index. With n leaves, internal nodes are 0 ..= n-2 (root 0) and leaves
//! n-1 ..= 2n-2; a single leaf is node 0. Siblings' boxes lie on opposite
//! sides of their Morton split plane, which is what makes the stack traversal
//! visit leaves in ray order.

pub mod cpu;

use super::bricks::GpuBricks;
use super::builder::{Builder, PerContext, RangeKind, Ranges};
use super::classify::{Classifier, Classify, APRON, CLASSIFY};
use super::cost::CostModel;
use super::method::{BuildInput, Built, March, Method};
use super::morton::MortonPush;
use super::morton::MAX_BRICKS_PER_AXIS;
use super::params::{Param, Params, COLLAPSE};
use super::stats::Stats;
use super::tree::Sizes;
pub use super::tree::{height, GpuTree, Node};
use super::tree::{STORAGE_XFER, TREE_MARCH};
use crate::error::{Error, Result};
use crate::gpu::record::{self, Access};
use crate::gpu::shaders::{self, build_lbvh_collapse, build_lbvh_emit, build_lbvh_refit, build_morton};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation, OptionalTimer, Timer, Timings};
use crate::prims::{entry_barrier, Compact, CompactScratch, RadixSort, SortScratch};
use crate::tf::GpuTransferFunction;
use crate::volume::GpuVolume;

/// A built LBVH is a tree in the shared node format.
pub type Lbvh = GpuTree;

/// What an LBVH build reads.
#[derive(Clone, Copy)]
pub struct LbvhInput<'a> {
    pub classifier: &'a Classifier,
    pub mode: Classify,
    pub volume: &'a GpuVolume,
    /// The 8^3 brick ranges (`RangeKind::Bricks`).
    pub bricks: &'a GpuBricks,
    pub tf: &'a GpuTransferFunction,
    /// Cost-driven leaves with this model; None: the paper's tree.
    pub collapse: Option<&'a CostModel>,
}

/// Per-volume buffers of the selection phase (classify + compact).
pub struct SelectScratch {
    pub(crate) flags: Buffer,
    pub(crate) active: Buffer,
    pub(crate) count: Buffer,
    count_readback: Buffer,
    compact: CompactScratch,
}

/// Per-build buffers of the hierarchy phase for n active bricks.
pub struct HierarchyScratch {
    n: u64,
    codes: Buffer,
    payload: Buffer,
    parents: Buffer,
    visits: Buffer,
    /// (cost, area) per node, for the collapse.
    costs: Buffer,
    sort: SortScratch,
}

/// Builds linear BVHs over active bricks on the device (Karras 2012); its
/// kernels are made once and reused for every build.
pub struct LbvhBuilder {
    ctx: Context,
    compact: Compact,
    sort: RadixSort,
    morton: Kernel,
    emit: Kernel,
    refit: Kernel,
    collapse: Kernel,
}

impl LbvhBuilder {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(LbvhBuilder {
            ctx: ctx.clone(),
            compact: Compact::new(ctx)?,
            sort: RadixSort::new(ctx)?,
            morton: Kernel::new::<MortonPush>(ctx, &shaders::BUILD_MORTON)?,
            emit: Kernel::new::<build_lbvh_emit::Push>(ctx, &shaders::BUILD_LBVH_EMIT)?,
            refit: Kernel::new::<build_lbvh_refit::Push>(ctx, &shaders::BUILD_LBVH_REFIT)?,
            collapse: Kernel::new::<build_lbvh_collapse::Push>(ctx, &shaders::BUILD_LBVH_COLLAPSE)?,
        })
    }

    pub fn select_scratch(&self, bricks: &GpuBricks) -> Result<SelectScratch> {
        if bricks.counts.iter().any(|&c| c > MAX_BRICKS_PER_AXIS) {
            return Err(Error::invalid(
                "volume",
                format!("{:?} bricks", bricks.counts),
                format!("30-bit Morton codes address at most {MAX_BRICKS_PER_AXIS} bricks per axis"),
            ));
        }
        let c = &self.ctx;
        Ok(SelectScratch {
            flags: Buffer::new(
                c,
                "brick flags",
                bricks.total * 4,
                STORAGE_XFER,
                MemoryLocation::GpuOnly,
            )?,
            active: Buffer::new(
                c,
                "active bricks",
                bricks.total * 4,
                STORAGE_XFER,
                MemoryLocation::GpuOnly,
            )?,
            count: Buffer::new(c, "active count", 4, STORAGE_XFER, MemoryLocation::GpuOnly)?,
            count_readback: Buffer::new(
                c,
                "active count readback",
                4,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?,
            compact: self.compact.scratch(bricks.total)?,
        })
    }

    /// Records classification and compaction ("classify", "compact") and a
    /// copy of the active count to host memory: after the submission,
    /// `active_count(scratch)` is n and `scratch.active[0..n]` the active
    /// brick indices in ascending order.
    pub fn record_select(
        &self,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        input: &LbvhInput,
        s: &SelectScratch,
    ) -> Result<()> {
        self.record_classify_compact(cmd, timer, input, s)?;
        cmd.barrier(Access::COMPUTE_WRITE, Access::TRANSFER_READ);
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: 4,
        }];
        cmd.copy_buffer(&s.count, &s.count_readback, &region)?;
        cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
        Ok(())
    }

    /// "classify" and "compact" of `record_select`, without the copy.
    fn record_classify_compact(
        &self,
        cmd: Recording<'_>,
        mut timer: Option<&mut Timer>,
        input: &LbvhInput,
        s: &SelectScratch,
    ) -> Result<()> {
        let LbvhInput {
            classifier,
            mode,
            volume,
            bricks,
            tf,
            ..
        } = *input;
        let pass = timer.begin(cmd, "classify")?;
        classifier.record(cmd, mode, volume, bricks, tf, &s.flags)?;
        timer.end(cmd, pass);
        let pass = timer.begin(cmd, "compact")?;
        self.compact
            .record(cmd, &s.flags, bricks.total, &s.active, &s.count, &s.compact)?;
        timer.end(cmd, pass);
        Ok(())
    }

    /// The active count copied by `record_select` (after its submission).
    pub fn active_count(&self, s: &SelectScratch) -> Result<u32> {
        Ok(bytemuck::pod_read_unaligned(&s.count_readback.host()?[..4]))
    }

    pub fn hierarchy_scratch(&self, n: u64) -> Result<HierarchyScratch> {
        let c = &self.ctx;
        let nodes = (2 * n).max(1);
        Ok(HierarchyScratch {
            n,
            codes: Buffer::new(c, "morton codes", n * 4, STORAGE_XFER, MemoryLocation::GpuOnly)?,
            payload: Buffer::new(c, "sorted bricks", n * 4, STORAGE_XFER, MemoryLocation::GpuOnly)?,
            parents: Buffer::new(c, "lbvh parents", nodes * 4, STORAGE_XFER, MemoryLocation::GpuOnly)?,
            visits: Buffer::new(c, "lbvh visits", n * 4, STORAGE_XFER, MemoryLocation::GpuOnly)?,
            costs: Buffer::new(c, "lbvh costs", nodes * 8, STORAGE_XFER, MemoryLocation::GpuOnly)?,
            sort: self.sort.scratch(n)?,
        })
    }

    /// Allocates the node array for n leaves (checked against
    /// `maxStorageBufferRange`).
    pub fn nodes_buffer(&self, n: u64) -> Result<Buffer> {
        let bytes = (2 * n).max(1) * 32;
        crate::prims::check_range(self.ctx.info(), "LBVH nodes", bytes)?;
        Buffer::new(&self.ctx, "lbvh nodes", bytes, STORAGE_XFER, MemoryLocation::GpuOnly)
    }

    /// Records Morton codes, the sort, the emit and the refit ("morton",
    /// "sort", "emit", "refit") for the active bricks listed in
    /// `select.active`, then with a cost model the collapse into cost-driven
    /// leaves ("collapse"). Ends with compute writes of `nodes`. The kernels
    /// take the active count n from `select.count` on the GPU; `h.n` is what
    /// the pass is sized for: n itself (the host-driven build), or the brick
    /// capacity when `active[n..h.n]` holds `u32::MAX` (a recorded build:
    /// those entries sort last and the threads past n return).
    pub fn record_hierarchy(
        &self,
        cmd: Recording<'_>,
        mut timer: Option<&mut Timer>,
        input: &LbvhInput,
        select: &SelectScratch,
        h: &HierarchyScratch,
        nodes: &Buffer,
    ) -> Result<()> {
        let LbvhInput {
            volume,
            bricks,
            collapse,
            ..
        } = *input;
        let (active, count) = (&select.active, &select.count);
        let n = h.n;
        if n == 0 {
            return Ok(());
        }
        // The kernels index `active` and the nodes up to the capacity `n`
        // (the GPU's count is clamped to it).
        let need = [n * 4, (2 * n).max(1) * 32];
        if active.size() < need[0] || nodes.size() < need[1] {
            return Err(Error::invalid(
                "LBVH buffers",
                format!("{} and {} bytes", active.size(), nodes.size()),
                format!(
                    "{n} leaves need {} bytes of active bricks and {} of nodes",
                    need[0], need[1]
                ),
            ));
        }
        let info = self.ctx.info();
        let c = bricks.counts;
        entry_barrier(cmd);
        let pass = timer.begin(cmd, "morton")?;
        let groups = record::groups_linear(info, "morton", n, self.morton.local_size()[0])?;
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.morton.dispatch(
                cmd,
                &build_morton::Bindings {
                    active_bricks: Binding::Storage(active),
                    codes: Binding::Storage(&h.codes),
                    payload: Binding::Storage(&h.payload),
                }
                .list(),
                bytemuck::bytes_of(&MortonPush::list(c, n as u32, groups[0])),
                groups,
            )
        }?;
        timer.end(cmd, pass);
        let pass = timer.begin(cmd, "sort")?;
        self.sort.record(cmd, &h.codes, &h.payload, n, 30, &h.sort)?;
        timer.end(cmd, pass);
        let pass = timer.begin(cmd, "emit")?;
        entry_barrier(cmd);
        cmd.fill_buffer(&h.visits, 0, vk::WHOLE_SIZE, 0)?;
        cmd.fill_buffer(&h.parents, 0, 4, u32::MAX)?;
        cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ_WRITE);
        self.record_emit(cmd, &h.codes, n, count, nodes, &h.parents)?;
        timer.end(cmd, pass);
        let pass = timer.begin(cmd, "refit")?;
        cmd.compute_to_compute();
        let groups = record::groups_linear(info, "refit", n, self.refit.local_size()[0])?;
        let d = volume.dims;
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.refit.dispatch(
                cmd,
                &build_lbvh_refit::Bindings {
                    payload: Binding::Storage(&h.payload),
                    nodes: Binding::Storage(nodes),
                    parents: Binding::Storage(&h.parents),
                    visits: Binding::Storage(&h.visits),
                    count: Binding::Storage(count),
                }
                .list(),
                // dims.w: brick edge.
                bytemuck::bytes_of(&build_lbvh_refit::Push {
                    dims: [d[0], d[1], d[2], bricks.brick],
                    counts: [c[0], c[1], c[2], 0],
                    groups_x: groups[0],
                    cap: n as u32,
                }),
                groups,
            )
        }?;
        timer.end(cmd, pass);
        if let Some(model) = collapse {
            let pass = timer.begin(cmd, "collapse")?;
            self.record_collapse(cmd, model, count, h, nodes)?;
            timer.end(cmd, pass);
        }
        Ok(())
    }

    /// The collapse climb after the refit (its visit counters reset first).
    fn record_collapse(
        &self,
        cmd: Recording<'_>,
        model: &CostModel,
        count: &Buffer,
        h: &HierarchyScratch,
        nodes: &Buffer,
    ) -> Result<()> {
        cmd.barrier(Access::COMPUTE_READ_WRITE, Access::TRANSFER_WRITE);
        cmd.fill_buffer(&h.visits, 0, vk::WHOLE_SIZE, 0)?;
        cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ_WRITE);
        cmd.compute_to_compute();
        let groups = record::groups_linear(self.ctx.info(), "collapse", h.n, self.collapse.local_size()[0])?;
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.collapse.dispatch(
                cmd,
                &build_lbvh_collapse::Bindings {
                    nodes: Binding::Storage(nodes),
                    parents: Binding::Storage(&h.parents),
                    visits: Binding::Storage(&h.visits),
                    costs: Binding::Storage(&h.costs),
                    count: Binding::Storage(count),
                }
                .list(),
                // `CostModel::gpu_constants`.
                bytemuck::bytes_of(&build_lbvh_collapse::Push {
                    model: model.gpu_constants(),
                    cap: h.n as u32,
                }),
                groups,
            )
        }
    }

    fn record_emit(
        &self,
        cmd: Recording<'_>,
        codes: &Buffer,
        n: u64,
        count: &Buffer,
        nodes: &Buffer,
        parents: &Buffer,
    ) -> Result<()> {
        if n < 2 {
            return Ok(());
        }
        let groups = record::groups_linear(self.ctx.info(), "emit", n - 1, self.emit.local_size()[0])?;
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe {
            self.emit.dispatch(
                cmd,
                &build_lbvh_emit::Bindings {
                    codes: Binding::Storage(codes),
                    nodes: Binding::Storage(nodes),
                    parents: Binding::Storage(parents),
                    count: Binding::Storage(count),
                }
                .list(),
                bytemuck::bytes_of(&build_lbvh_emit::Push {
                    groups_x: groups[0],
                    cap: n as u32,
                    ..Default::default()
                }),
                groups,
            )
        }
    }

    /// Runs the hierarchy emit alone on sorted `codes` (duplicates allowed)
    /// and returns the nodes' child links, for testing the emit in isolation.
    pub fn emit_links(&self, codes: &[u32]) -> Result<Vec<[i32; 2]>> {
        let n = codes.len() as u64;
        if n < 2 {
            return Ok(Vec::new());
        }
        let c = Buffer::with_data(&self.ctx, "codes", bytemuck::cast_slice(codes), STORAGE_XFER)?;
        let nodes = self.nodes_buffer(n)?;
        let parents = Buffer::new(&self.ctx, "parents", 2 * n * 4, STORAGE_XFER, MemoryLocation::GpuOnly)?;
        let count = Buffer::with_data(&self.ctx, "count", bytemuck::bytes_of(&(n as u32)), STORAGE_XFER)?;
        self.ctx
            .submit_and_wait(|cmd| self.record_emit(cmd, &c, n, &count, &nodes, &parents))?;
        let nodes: Vec<Node> = bytemuck::pod_collect_to_vec(&nodes.download(0, (n - 1) * 32)?);
        Ok(nodes.iter().map(|n| [n.lo[3], n.hi[3]]).collect())
    }

    /// Builds the LBVH for a transfer function: two submissions (selection,
    /// then the hierarchy sized to the active count), with cost-driven
    /// leaves when a cost model is given. Returns the structure and the GPU
    /// time of each phase.
    pub fn build(&self, input: &LbvhInput) -> Result<(Lbvh, Timings)> {
        let bricks = input.bricks;
        let select = self.select_scratch(bricks)?;
        let mut timer = Timer::new(&self.ctx, 8)?;
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            self.record_select(cmd, Some(&mut timer), input, &select)
        })?;
        let mut timings = timer.results()?;
        let n = self.active_count(&select)? as u64;
        let h = self.hierarchy_scratch(n)?;
        let nodes = self.nodes_buffer(n)?;
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            self.record_hierarchy(cmd, Some(&mut timer), input, &select, &h, &nodes)
        })?;
        timings.extend(timer.results()?);
        let node_count = if n == 0 { 0 } else { 2 * n - 1 };
        let lbvh = Lbvh {
            nodes,
            count: select.count,
            sizes: std::sync::OnceLock::from(Sizes::lbvh(n as u32)),
            keep: None,
            stats: Stats {
                unit: "8^3 bricks",
                total_bricks: bricks.total,
                active_bricks: n,
                nodes: node_count,
                leaves: n,
                height: 0,
                bytes: node_count * 32,
            },
            // Derived from a node readback only when statistics are asked
            // for (a collapse leaves fewer reachable nodes).
            shape: std::sync::OnceLock::new(),
            whole_box: false,
        };
        Ok((lbvh, timings))
    }

    /// Records the whole build into `cmd` with no CPU round trip: the
    /// hierarchy is sized for every brick (`bricks.total`), the active list
    /// is filled with `u32::MAX` before the compaction so the entries past
    /// the active count n get the largest key and sort last, and the emit,
    /// refit and collapse read n from the compaction's count buffer. The
    /// first 2n - 1 nodes are those of `build`, bit for bit. Phases as in
    /// `build`; begins with the `prims` entry barrier, ends with compute
    /// writes. The returned tree keeps the scratch buffers the command
    /// buffer uses; its leaf and node counts and statistics are read back
    /// on first request, after the submission completed.
    pub fn record_build(&self, cmd: Recording<'_>, mut timer: Option<&mut Timer>, input: &LbvhInput) -> Result<Lbvh> {
        let bricks = input.bricks;
        let select = self.select_scratch(bricks)?;
        let capacity = bricks.total;
        let h = self.hierarchy_scratch(capacity)?;
        let nodes = self.nodes_buffer(capacity)?;
        // A fresh buffer: no earlier access to order. The compaction's entry
        // barrier makes the fill visible to its writes and to the Morton pass.
        cmd.fill_buffer(&select.active, 0, vk::WHOLE_SIZE, u32::MAX)?;
        self.record_classify_compact(cmd, timer.as_deref_mut(), input, &select)?;
        self.record_hierarchy(cmd, timer, input, &select, &h, &nodes)?;
        let SelectScratch {
            flags,
            active,
            count,
            count_readback,
            compact,
        } = select;
        Ok(Lbvh {
            nodes,
            count,
            sizes: std::sync::OnceLock::new(),
            stats: Stats {
                unit: "8^3 bricks",
                total_bricks: bricks.total,
                ..Stats::default()
            },
            shape: std::sync::OnceLock::new(),
            keep: Some(Box::new((flags, active, count_readback, compact, h))),
            whole_box: false,
        })
    }
}

impl PerContext for LbvhBuilder {
    fn new(ctx: &Context) -> Result<Self> {
        LbvhBuilder::new(ctx)
    }
}

/// `--accel lbvh`.
pub struct LbvhMethod;

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for LbvhMethod {
    fn name(&self) -> &'static str {
        "lbvh"
    }
    fn description(&self) -> &'static str {
        "linear BVH over active 8^3 bricks (Karras 2012), built on the GPU"
    }
    fn params(&self) -> &'static [Param] {
        &[CLASSIFY, APRON, COLLAPSE]
    }
    fn check(&self, p: &Params) -> Result<()> {
        Classify::from_params(p).map(|_| ())
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::Bricks)
    }
    fn march(&self) -> March {
        TREE_MARCH
    }
    fn variants(&self) -> Result<Vec<(String, Params)>> {
        Ok(vec![
            (self.name().to_string(), Params::defaults(self.params())),
            (
                format!("{} collapsed", self.name()),
                Params::resolve(self.params(), &[("collapse", "on")])?,
            ),
        ])
    }
    /// `record_build` sizes the hierarchy for every brick (no readback);
    /// `build` stays host-driven, sized by the active count read back
    /// between its two submissions.
    fn recordable(&self) -> bool {
        true
    }
    fn record_build(
        &self,
        builder: &Builder,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<Box<dyn Built>> {
        let lbvh = builder.shared::<LbvhBuilder>()?;
        let classifier = builder.shared::<Classifier>()?;
        // Measuring the model submits: a recorded build must not, so it
        // must have been measured (or given) beforehand.
        let model = match p.switch("collapse")? {
            true => Some(builder.made::<CostModel>().map(|m| *m).ok_or_else(|| {
                Error::invalid(
                    "recorded LBVH build",
                    "with collapse on",
                    "call builder.cost_model() (or set_cost_model) once before recording: measuring it submits",
                )
            })?),
            false => None,
        };
        let input = LbvhInput {
            classifier: &classifier,
            mode: Classify::from_params(p)?,
            volume: input.gpu_volume,
            bricks: ranges.bricks()?,
            tf: input.gpu_tf,
            collapse: model.as_ref(),
        };
        let tree = lbvh.record_build(cmd, timer, &input)?;
        Ok(Box::new(tree))
    }
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let lbvh = builder.shared::<LbvhBuilder>()?;
        let classifier = builder.shared::<Classifier>()?;
        let collapse = p.switch("collapse")?;
        let model = collapse.then(|| builder.cost_model()).transpose()?;
        let lbvh_input = LbvhInput {
            classifier: &classifier,
            mode: Classify::from_params(p)?,
            volume: input.gpu_volume,
            bricks: ranges.bricks()?,
            tf: input.gpu_tf,
            collapse: model.as_ref(),
        };
        let (mut tree, mut t) = lbvh.build(&lbvh_input)?;
        tree.check_whole_box(input.gpu_volume.dims, collapse, &mut t)?;
        Ok((Box::new(tree), t))
    }
}
