//! The k-d tree built with GPU reductions (Zellmann et al. 2019): per-8^3
//! brick tight boxes of active footprints computed on the GPU in shared
//! memory, Morton-ordered by the radix sort; the tight box of a region is a
//! GPU reduction over the Morton range of its bricks. The recursion runs on
//! the host, breadth first with binned candidate planes on the 8-voxel raster,
//! and all reductions of one tree level go to the GPU in one dispatch (the
//! paper launched kernels per plane).

use super::{
    binned_planes, cheaper_as_leaf, choose, forced_plane, halves, longest_axis, volume, Candidate, IBox, KdNode,
    KdParams, RASTER,
};
use super::{kd_variants, Depth, BINS, KD, MAX_LEAF};
use crate::accel::builder::{Builder, PerContext, RangeKind, Ranges};
use crate::accel::cost::CostModel;
use crate::accel::method::{BuildInput, Built, March, Method};
use crate::accel::morton::{MortonPush, MAX_BRICKS_PER_AXIS};
use crate::accel::params::{Param, Params, COLLAPSE};
use crate::accel::stats::Stats;
use crate::accel::tree::{GpuTree, STORAGE_XFER, TREE_MARCH};
use crate::error::{Error, Result};
use crate::gpu::record::{self};
use crate::gpu::shaders::{self, build_box_query, build_brick_tight, build_morton};
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation, Timer, Timings};
use crate::prims::{entry_barrier, RadixSort};
use crate::tf::{GpuTransferFunction, LUT_SIZE};
use crate::volume::GpuVolume;

/// Builds k-d trees on the device from Morton-ordered bricks (Zellmann et
/// al. 2019); its kernels are made once and reused for every build.
pub struct KdGpuBuilder {
    ctx: Context,
    tight: Kernel,
    morton: Kernel,
    query: Kernel,
    sort: RadixSort,
}

const EMPTY: i32 = i32::MAX;

fn decode(r: &[[i32; 4]], q: usize) -> Option<IBox> {
    let (lo, hi) = (r[2 * q], r[2 * q + 1]);
    if lo[0] == EMPTY || (0..3).any(|a| lo[a] >= hi[a]) {
        None
    } else {
        Some([[lo[0], lo[1], lo[2]], [hi[0], hi[1], hi[2]]])
    }
}

impl KdGpuBuilder {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(KdGpuBuilder {
            ctx: ctx.clone(),
            tight: Kernel::new::<build_brick_tight::Push>(ctx, &shaders::BUILD_BRICK_TIGHT)?,
            morton: Kernel::new::<MortonPush>(ctx, &shaders::BUILD_MORTON)?,
            query: Kernel::new::<build_box_query::Push>(ctx, &shaders::BUILD_BOX_QUERY)?,
            sort: RadixSort::new(ctx)?,
        })
    }

    /// Answers tight-box queries on the GPU in one submission ("queries").
    fn run_queries(&self, timer: &mut Timer, s: &Sorted, queries: &[IBox]) -> Result<(Vec<Option<IBox>>, f64)> {
        let n = queries.len() as u64;
        let words_q: Vec<[i32; 4]> = queries
            .iter()
            .flat_map(|q| [[q[0][0], q[0][1], q[0][2], 0], [q[1][0], q[1][1], q[1][2], 0]])
            .collect();
        let mut qbuf = Buffer::new(
            &self.ctx,
            "kd queries",
            n * 32,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        qbuf.host_mut()?[..(n * 32) as usize].copy_from_slice(bytemuck::cast_slice(&words_q));
        let rbuf = Buffer::new(
            &self.ctx,
            "kd query results",
            n * 32,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuToCpu,
        )?;
        let groups = record::groups_linear(self.ctx.info(), "kd queries", n, 1)?;
        let c = s.counts;
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            let pass = timer.begin(cmd, "queries")?;
            entry_barrier(cmd);
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.query.dispatch(
                    cmd,
                    &build_box_query::Bindings {
                        codes: Binding::Storage(&s.codes),
                        order: Binding::Storage(&s.order),
                        boxes: Binding::Storage(&s.boxes),
                        queries: Binding::Storage(&qbuf),
                        results: Binding::Storage(&rbuf),
                    }
                    .list(),
                    // counts.w: bricks.
                    bytemuck::bytes_of(&build_box_query::Push {
                        counts: [c[0], c[1], c[2], s.total as u32],
                        queries: n as u32,
                        groups_x: groups[0],
                        brick: RASTER as u32,
                        pad: 0,
                    }),
                    groups,
                )
            }?;
            timer.end(cmd, pass);
            cmd.barrier(record::Access::COMPUTE_WRITE, record::Access::HOST_READ);
            Ok(())
        })?;
        let ms = timer.results()?.get("queries").unwrap_or(0.0);
        let r: Vec<[i32; 4]> = bytemuck::pod_collect_to_vec(&rbuf.host()?[..(n * 32) as usize]);
        Ok(((0..queries.len()).map(|q| decode(&r, q)).collect(), ms))
    }

    /// Builds the tree for a TF. Phases: "bricks", "morton", "sort" and
    /// "queries" (GPU timestamps, the last summed over the levels), "host"
    /// (the recursion's wall time net of the queries) and "upload".
    pub fn build(
        &self,
        gv: &GpuVolume,
        tf: &GpuTransferFunction,
        params: &KdParams,
        collapse: Option<&CostModel>,
    ) -> Result<(GpuTree, Timings)> {
        // The volume's views and the TF's tables are bound: this context's only.
        self.ctx.check_is(gv.context(), "volume")?;
        self.ctx.check_is(tf.context(), "transfer function")?;
        tf.check_channels(gv.channels)?;
        let mut timings = Timings::default();
        let mut timer = Timer::new(&self.ctx, 4)?;
        let sorted = self.sorted_bricks(gv, tf, &mut timer, &mut timings)?;
        let start = std::time::Instant::now();
        let mut query_ms = 0.0;
        // Breadth first: the root query, then one batch of queries per level.
        let (root, ms) = self.run_queries(&mut timer, &sorted, &[[[0; 3], gv.dims.map(|d| d as i32)]])?;
        query_ms += ms;
        let mut arena: Vec<(IBox, Option<(usize, usize)>)> = Vec::new();
        let mut pending: Vec<usize> = Vec::new();
        let root_vol = root[0].map_or(0, |b| volume(&b));
        if let Some(b) = root[0] {
            arena.push((b, None));
            pending.push(0);
        }
        while !pending.is_empty() {
            // Per pending node: its candidate planes (binned, then the forced one).
            let mut plans: Vec<(usize, usize, Vec<i32>, Option<i32>)> = Vec::new();
            let mut queries: Vec<IBox> = Vec::new();
            for &id in &pending {
                let b = arena[id].0;
                if params.halts(volume(&b), root_vol) {
                    continue;
                }
                let axis = longest_axis(&b);
                let planes = binned_planes(&b, axis, params.bins);
                let forced = forced_plane(&b, params).map(|(_, p)| p);
                for &p in planes.iter().chain(forced.iter()) {
                    let (l, r) = halves(&b, axis, p);
                    queries.push(l);
                    queries.push(r);
                }
                plans.push((id, axis, planes, forced));
            }
            let mut next = Vec::new();
            if !queries.is_empty() {
                let (results, ms) = self.run_queries(&mut timer, &sorted, &queries)?;
                query_ms += ms;
                let mut q = 0;
                for (id, _axis, planes, forced) in plans {
                    let b = arena[id].0;
                    let cands: Vec<Candidate> = planes
                        .iter()
                        .map(|&p| {
                            let c = (p, results[q], results[q + 1]);
                            q += 2;
                            c
                        })
                        .collect();
                    let forced_c = forced.map(|p| {
                        let c: Candidate = (p, results[q], results[q + 1]);
                        q += 2;
                        c
                    });
                    let chosen = choose(&b, &cands).map(|i| cands[i]).or(forced_c);
                    if let Some((_, Some(l), Some(r))) = chosen {
                        if collapse.is_some_and(|m| cheaper_as_leaf(m, &b, &l, &r)) {
                            continue;
                        }
                        let (li, ri) = (arena.len(), arena.len() + 1);
                        arena.push((l, None));
                        arena.push((r, None));
                        arena[id].1 = Some((li, ri));
                        next.push(li);
                        next.push(ri);
                    }
                }
            }
            pending = next;
        }
        timings.push("queries", query_ms);
        // Host time of the recursion, net of the GPU query time above.
        timings.push("host", (start.elapsed().as_secs_f64() * 1e3 - query_ms).max(0.0));
        fn to_node(arena: &[(IBox, Option<(usize, usize)>)], i: usize) -> KdNode {
            match arena[i].1 {
                None => KdNode::Leaf(arena[i].0),
                Some((l, r)) => KdNode::Inner(arena[i].0, Box::new(to_node(arena, l)), Box::new(to_node(arena, r))),
            }
        }
        let root = (!arena.is_empty()).then(|| to_node(&arena, 0));
        let nodes = super::flatten(root.as_ref());
        let stats = Stats {
            unit: "8^3 bricks",
            total_bricks: sorted.total,
            active_bricks: sorted.active,
            ..Default::default()
        };
        let start = std::time::Instant::now();
        let tree = GpuTree::upload(&self.ctx, &nodes, stats)?;
        timings.push("upload", start.elapsed().as_secs_f64() * 1e3);
        Ok((tree, timings))
    }

    /// Per-brick tight boxes ("bricks") and their Morton order ("morton", "sort").
    fn sorted_bricks(
        &self,
        gv: &GpuVolume,
        tf: &GpuTransferFunction,
        timer: &mut Timer,
        timings: &mut Timings,
    ) -> Result<Sorted> {
        let brick = RASTER as u32;
        let counts = gv.dims.map(|d| d.div_ceil(brick));
        if counts.iter().any(|&c| c > MAX_BRICKS_PER_AXIS) {
            return Err(Error::invalid(
                "volume",
                format!("{:?}", gv.dims),
                format!("Morton codes address at most {MAX_BRICKS_PER_AXIS} bricks per axis"),
            ));
        }
        let total = counts.iter().map(|&c| c as u64).product::<u64>();
        crate::prims::check_range(self.ctx.info(), "brick boxes", total * 32)?;
        let boxes = Buffer::new(
            &self.ctx,
            "brick tight boxes",
            total * 32,
            STORAGE_XFER,
            MemoryLocation::GpuOnly,
        )?;
        let codes = Buffer::new(
            &self.ctx,
            "brick codes",
            total * 4,
            STORAGE_XFER,
            MemoryLocation::GpuOnly,
        )?;
        let order = Buffer::new(
            &self.ctx,
            "brick order",
            total * 4,
            STORAGE_XFER,
            MemoryLocation::GpuOnly,
        )?;
        let dummy = Buffer::new(&self.ctx, "unused list", 4, STORAGE_XFER, MemoryLocation::GpuOnly)?;
        let scratch = self.sort.scratch(total)?;
        let info = self.ctx.info();
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            let pass = timer.begin(cmd, "bricks")?;
            let groups = record::groups_linear(info, "brick boxes", total, 1)?;
            // dims.w: brick edge; counts.w: total bricks.
            let push = build_brick_tight::Push {
                dims: [gv.dims[0], gv.dims[1], gv.dims[2], brick],
                counts: [counts[0], counts[1], counts[2], total as u32],
                lo: gv.norms.map(|n| n[0]),
                scale: gv.norms.map(|n| n[1]),
                groups_x: groups[0],
                lut_size: LUT_SIZE as u32,
                channels: gv.channels,
                tf_stride: tf.channel_step() * tf.max_stride,
                pool_brick: gv.brick_edge(),
                ..Default::default()
            };
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.tight.dispatch(
                    cmd,
                    &build_brick_tight::Bindings {
                        volume_tex: Binding::Sampled(gv.image.view, gv.sampler),
                        transfer_max: Binding::Storage(&tf.max_table),
                        boxes: Binding::Storage(&boxes),
                        brick_table: Binding::Texels(gv.brick_table()),
                        pool_1: Binding::Sampled(gv.pool_views()[0], gv.sampler),
                        pool_2: Binding::Sampled(gv.pool_views()[1], gv.sampler),
                        pool_3: Binding::Sampled(gv.pool_views()[2], gv.sampler),
                    }
                    .list(),
                    bytemuck::bytes_of(&push),
                    groups,
                )
            }?;
            timer.end(cmd, pass);
            let pass = timer.begin(cmd, "morton")?;
            let groups = record::groups_linear(info, "morton", total, self.morton.local_size()[0])?;
            // SAFETY: every binding is a live object of this context borrowed for
            // the call, or the host's (`Recording::adopt`, `HostImage::new`).
            unsafe {
                self.morton.dispatch(
                    cmd,
                    &build_morton::Bindings {
                        active_bricks: Binding::Storage(&dummy),
                        codes: Binding::Storage(&codes),
                        payload: Binding::Storage(&order),
                    }
                    .list(),
                    bytemuck::bytes_of(&MortonPush::every(counts, total as u32, groups[0])),
                    groups,
                )
            }?;
            timer.end(cmd, pass);
            let pass = timer.begin(cmd, "sort")?;
            self.sort.record(cmd, &codes, &order, total, 30, &scratch)?;
            timer.end(cmd, pass);
            Ok(())
        })?;
        timings.extend(timer.results()?);
        let host: Vec<[i32; 4]> = bytemuck::pod_collect_to_vec(&boxes.download(0, total * 32)?);
        let active = (0..total as usize).filter(|&b| decode(&host, b).is_some()).count() as u64;
        Ok(Sorted {
            counts,
            total,
            active,
            boxes,
            codes,
            order,
        })
    }
}

struct Sorted {
    counts: [u32; 3],
    total: u64,
    active: u64,
    boxes: Buffer,
    codes: Buffer,
    order: Buffer,
}

impl PerContext for KdGpuBuilder {
    fn new(ctx: &Context) -> Result<Self> {
        KdGpuBuilder::new(ctx)
    }
}

/// `--accel kd-gpu`.
pub struct KdGpu;

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for KdGpu {
    fn name(&self) -> &'static str {
        "kd-gpu"
    }
    fn description(&self) -> &'static str {
        "k-d tree built with GPU reductions over Morton-ordered bricks (Zellmann et al. 2019)"
    }
    fn params(&self) -> &'static [Param] {
        &[KD, MAX_LEAF, BINS, COLLAPSE]
    }
    fn check(&self, p: &Params) -> Result<()> {
        KdParams::from_params(p).map(|_| ())
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::None)
    }
    fn march(&self) -> March {
        TREE_MARCH
    }
    fn variants(&self) -> Result<Vec<(String, Params)>> {
        kd_variants(self, &[(Depth::Shallow, 32), (Depth::Deep, 128)])
    }
    /// Host-driven: the host recursion submits one batch of queries per level.
    fn recordable(&self) -> bool {
        false
    }
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        _: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let kd = builder.shared::<KdGpuBuilder>()?;
        let collapse = p.switch("collapse")?;
        let model = collapse.then(|| builder.cost_model()).transpose()?;
        let (mut tree, mut t) = kd.build(
            input.gpu_volume,
            input.gpu_tf,
            &KdParams::from_params(p)?,
            model.as_ref(),
        )?;
        tree.check_whole_box(input.gpu_volume.dims, collapse, &mut t)?;
        Ok((Box::new(tree), t))
    }
}
