//! The traversal cost model of cost-driven leaves, with constants measured on
//! the device (`Builder::cost_model`, measured once per context).
//!
//! A ray crossing a box B costs, in GPU nanoseconds,
//!
//! - marched as one leaf: `entry_ns + sample_ns * chord(B) / STEP`, where
//!   `chord(B) = 4 V(B) / S(B)` is the mean chord of a convex body over
//!   uniformly distributed lines (Cauchy), so `chord / STEP` samples;
//! - as an inner node: `step_ns + sum over children c of S(c) / S(B) * cost(c)`
//!   (the surface-area heuristic: `S(c) / S(B)` is the chance that a line
//!   meeting B meets c).
//!
//! A subtree becomes one leaf where the first is not larger. The sample
//! terms agree when the children tile the node (`4 sum V(c) / S(B)`), so a
//! fully active node always collapses; what a collapse buys is traversal
//! steps and leaf entries, what it pays is samples through empty space.
//!
//! **Measured, not guessed.** `measure` renders four small scenes with the
//! tree march kernel (`glsl/march/bvh.comp`, the kernel that marches the
//! trees) and times each with GPU timestamps: 32x32 orthographic rays along
//! z through a 64^3 volume, each ray crossing the whole depth,
//!
//! | scene | tree | step | per ray |
//! |---|---|---|---|
//! | A | one leaf, the volume | 0.5 | 1 entry, 128 samples |
//! | A' | one leaf, the volume | 2 | 1 entry, 32 samples |
//! | B | 32 slabs of 2 voxels across the ray | 2 | 31 inner steps, 32 entries, 32 samples |
//! | C | 32x32 columns of 2x2 voxels along the rays | 2 | 10 inner steps, 1 entry, 32 samples |
//!
//! so `sample_ns = (A - A') / 96`, `step_ns = (C - A') / 10` and `entry_ns =
//! (B - A') / 31 - step_ns`, per ray (B and C take few samples, so the
//! traversal terms are not small differences of large times). Each scene is dispatched `REPEATS`
//! times, interleaved, after one untimed warm-up round (lavapipe compiles
//! on first use), and the median is taken; about a millisecond of GPU time
//! on lavapipe. A constant that noise drives to or below zero is clamped to
//! `FLOOR_NS`.

use super::builder::{Builder, PerContext};
use super::stats::Stats;
use super::tree::{GpuTree, Node};
use crate::desc::{DEFAULT_STEP, ERT_OFF};
use crate::error::{Error, Result};
use crate::gpu::record::Access;
use crate::gpu::shaders::{self, blocks::RenderParams, march_bvh, MarchCommon};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation, TexelBuffer, Timer};
use crate::tf::{TransferFunction, LUT_SIZE};
use crate::volume::{GpuVolume, Volume, VoxelData, VoxelType};

/// The sample spacing (voxels) the collapse plans for: the frame's default
/// step. A finer step makes samples dearer relative to steps and entries, so
/// a tree collapsed for it stays exact at any step, only less tuned.
pub const STEP: f32 = DEFAULT_STEP;

/// The least value of a measured constant (ns).
pub const FLOOR_NS: f64 = 1e-3;

/// Timed dispatches per scene (the median is kept).
const REPEATS: usize = 7;
/// Calibration volume edge (voxels) and image edge (rays).
const EDGE: u32 = 64;
const RAYS: u32 = 32;
/// Slabs of the B scene; inner depth of the C scene's tree of RAYS^2 columns.
const SLABS: u32 = 32;
const COLUMN_DEPTH: u32 = 10;

/// GPU time per unit of traversal work, in nanoseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CostModel {
    /// One marched lattice sample (volume fetch, LUT, compositing).
    pub sample_ns: f64,
    /// One inner node visited (its span and both children's spans).
    pub step_ns: f64,
    /// One leaf entered (its span, the skip to its first lattice point).
    pub entry_ns: f64,
}

/// Box surface area and volume, in voxel units.
fn area_volume(lo: [i32; 3], hi: [i32; 3]) -> (f32, f32) {
    let e = [0, 1, 2].map(|a| (hi[a] - lo[a]).max(0) as f32);
    (2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]), e[0] * e[1] * e[2])
}

impl PerContext for CostModel {
    fn new(ctx: &Context) -> Result<Self> {
        CostModel::measure(ctx)
    }
}

impl Builder {
    /// The traversal cost model of this device, measured on first use (a
    /// few small timed dispatches) and kept.
    pub fn cost_model(&self) -> Result<CostModel> {
        self.shared::<CostModel>().map(|m| *m)
    }

    /// Builds with `model` instead of measuring one: a model kept from an
    /// earlier run (`results.json`'s `setup.cost_model`) gives the same
    /// collapsed trees whatever the machine's load.
    pub fn set_cost_model(&self, model: CostModel) {
        self.put(model)
    }
}

impl CostModel {
    /// The constants in f32, in the order `glsl/build/lbvh_collapse.comp`
    /// reads them: sample cost per voxel of chord at `STEP`, step, entry.
    pub fn gpu_constants(&self) -> [f32; 4] {
        [
            (self.sample_ns / STEP as f64) as f32,
            self.step_ns as f32,
            self.entry_ns as f32,
            0.0,
        ]
    }

    /// Expected cost of box `[lo, hi]` marched as one leaf, per ray meeting
    /// it, and its surface area. In f32 with the GPU kernel's operation order,
    /// so the CPU reference makes the same decisions.
    pub fn leaf(&self, lo: [i32; 3], hi: [i32; 3]) -> (f32, f32) {
        let [per_voxel, _, entry, _] = self.gpu_constants();
        let (s, v) = area_volume(lo, hi);
        let chord = if s > 0.0 { 4.0 * v / s } else { 0.0 };
        (entry + per_voxel * chord, s)
    }

    /// Expected cost of an inner node of area `s` whose children have (cost,
    /// area) `l` and `r`.
    pub fn inner(&self, s: f32, l: (f32, f32), r: (f32, f32)) -> f32 {
        let step = self.gpu_constants()[1];
        if s > 0.0 {
            step + (l.1 * l.0 + r.1 * r.0) / s
        } else {
            step + l.0 + r.0
        }
    }

    /// Measures the constants on `ctx`'s device (see the module docs).
    pub fn measure(ctx: &Context) -> Result<CostModel> {
        let probe = Probe::new(ctx)?;
        let scenes = [
            (probe.tree(&[Node::leaf([0; 3], [EDGE as i32; 3], 0)])?, STEP),
            (probe.tree(&[Node::leaf([0; 3], [EDGE as i32; 3], 0)])?, 4.0 * STEP),
            (probe.tree(&balanced(&slabs()))?, 4.0 * STEP),
            (probe.tree(&balanced(&columns()))?, 4.0 * STEP),
        ];
        let mut timer = Timer::new(ctx, (scenes.len() * REPEATS) as u32)?;
        if !timer.supported() {
            return Err(Error::Unsupported(
                "the cost model is measured with GPU timestamps, which this queue does not write".into(),
            ));
        }
        ctx.submit_and_wait(|cmd| {
            for (tree, step) in &scenes {
                probe.record(cmd, tree, *step)?;
            }
            Ok(())
        })?;
        ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            for r in 0..REPEATS {
                for (i, (tree, step)) in scenes.iter().enumerate() {
                    let pass = timer.begin(cmd, &format!("{i}/{r}"))?;
                    probe.record(cmd, tree, *step)?;
                    timer.end(cmd, pass);
                }
            }
            Ok(())
        })?;
        let t = timer.results()?;
        let median = |i: usize| {
            let v: Vec<f64> = (0..REPEATS).filter_map(|r| t.get(&format!("{i}/{r}"))).collect();
            crate::gpu::timings::median(v)
        };
        // ms per dispatch -> ns per ray.
        let per_ray = |i: usize| median(i) * 1e6 / (RAYS * RAYS) as f64;
        let (a, a4, b, c) = (per_ray(0), per_ray(1), per_ray(2), per_ray(3));
        let samples = (EDGE as f64 / STEP as f64) * (1.0 - 0.25);
        let step_ns = (c - a4) / COLUMN_DEPTH as f64;
        let model = CostModel {
            sample_ns: (a - a4) / samples,
            step_ns,
            entry_ns: (b - a4) / (SLABS - 1) as f64 - step_ns,
        };
        Ok(model.floored())
    }

    fn floored(self) -> CostModel {
        let f = |x: f64| if x.is_finite() { x.max(FLOOR_NS) } else { FLOOR_NS };
        CostModel {
            sample_ns: f(self.sample_ns),
            step_ns: f(self.step_ns),
            entry_ns: f(self.entry_ns),
        }
    }
}

/// Leaf boxes of the B scene: `SLABS` slabs across the rays, front to back.
fn slabs() -> Vec<[[i32; 3]; 2]> {
    let thick = (EDGE / SLABS) as i32;
    let e = EDGE as i32;
    (0..SLABS as i32)
        .map(|k| [[0, 0, k * thick], [e, e, (k + 1) * thick]])
        .collect()
}

/// Leaf boxes of the C scene: one column along z per ray, in Morton order
/// of (x, y), so halving the list halves the columns by a plane.
fn columns() -> Vec<[[i32; 3]; 2]> {
    let w = (EDGE / RAYS) as i32;
    let spread = |v: u32| (0..16).fold(0u32, |acc, b| acc | ((v >> b) & 1) << (2 * b));
    let mut cols: Vec<(u32, i32, i32)> = (0..RAYS)
        .flat_map(|y| (0..RAYS).map(move |x| (x, y)))
        .map(|(x, y)| (spread(x) | spread(y) << 1, x as i32, y as i32))
        .collect();
    cols.sort_unstable();
    cols.iter()
        .map(|&(_, x, y)| [[x * w, y * w, 0], [(x + 1) * w, (y + 1) * w, EDGE as i32]])
        .collect()
}

/// A balanced tree over `leaves` (halving the list at every node); inner
/// boxes are the unions.
fn balanced(leaves: &[[[i32; 3]; 2]]) -> Vec<Node> {
    fn build(leaves: &[[[i32; 3]; 2]], first: usize, out: &mut Vec<Node>) -> (usize, [[i32; 3]; 2]) {
        let me = out.len();
        out.push(Node::default());
        if leaves.len() == 1 {
            let b = leaves[0];
            out[me] = Node::leaf(b[0], b[1], first as i32);
            return (me, b);
        }
        let half = leaves.len() / 2;
        let (l, lb) = build(&leaves[..half], first, out);
        let (r, rb) = build(&leaves[half..], first + half, out);
        let lo = [0, 1, 2].map(|a| lb[0][a].min(rb[0][a]));
        let hi = [0, 1, 2].map(|a| lb[1][a].max(rb[1][a]));
        out[me] = Node::inner(lo, hi, l as i32, r as i32);
        (me, [lo, hi])
    }
    let mut out = Vec::new();
    build(leaves, 0, &mut out);
    out
}

/// The calibration scene: a volume, a transfer function and the tree march
/// kernel with its own parameter and frame buffers.
struct Probe {
    ctx: Context,
    kernel: Kernel,
    volume: GpuVolume,
    /// A frame LUT (glsl/common/tf.glsl): the corrected table, then the raw one.
    lut: TexelBuffer,
    no_cells: TexelBuffer,
    params: Vec<Buffer>,
    frame: Buffer,
    /// The march status binding (never written: the kernel is unspecialized,
    /// so it checks no loop cap).
    status: Buffer,
}

impl Probe {
    fn new(ctx: &Context) -> Result<Probe> {
        let n = EDGE as usize;
        // A varied ramp, so fetches are not all of one texel.
        let data: Vec<u8> = (0..n * n * n).map(|i| ((i * 7 + i / n * 13) % 256) as u8).collect();
        let volume = Volume::new("cost probe", [EDGE; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data))?;
        let tf = TransferFunction::parse("ramp:0:1")?;
        let tables = [tf.corrected_lut(STEP), tf.lut().to_vec()].concat();
        let lut = Buffer::with_data(
            ctx,
            "cost probe LUT",
            bytemuck::cast_slice(&tables),
            vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
        )?;
        let lut = TexelBuffer::new(ctx, lut, vk::Format::R32G32B32A32_SFLOAT)?;
        let frame = Buffer::new(
            ctx,
            "cost probe frame",
            (RAYS * RAYS) as u64 * 16,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        let params = [STEP, 4.0 * STEP]
            .iter()
            .map(|&dt| {
                Buffer::with_data(
                    ctx,
                    "cost probe params",
                    bytemuck::bytes_of(&probe_params(dt)),
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Probe {
            ctx: ctx.clone(),
            kernel: Kernel::new::<()>(ctx, &shaders::MARCH_BVH)?,
            volume: GpuVolume::upload(ctx, &volume)?,
            lut,
            no_cells: crate::volume::no_cells(ctx)?,
            params,
            frame,
            status: Buffer::new(
                ctx,
                "cost probe status",
                16,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?,
        })
    }

    fn tree(&self, nodes: &[Node]) -> Result<GpuTree> {
        GpuTree::upload(&self.ctx, nodes, Stats::default())
    }

    fn record(&self, cmd: Recording<'_>, tree: &GpuTree, step: f32) -> Result<()> {
        let params = &self.params[usize::from(step != STEP)];
        // Dispatches write the same frame (and may write the same status):
        // order them.
        cmd.barrier(Access::COMPUTE_READ_WRITE, Access::COMPUTE_READ_WRITE);
        let groups = self.kernel.groups("cost probe", [RAYS, RAYS, 1])?;
        let mut bindings = MarchCommon {
            params: Binding::Storage(params),
            volume_tex: Binding::Sampled(self.volume.image.view, self.volume.sampler),
            tf_lut: Binding::Texels(&self.lut),
            frame: Binding::Storage(&self.frame),
            // Composite frames write no depth and read no gradient.
            frame_depth: Binding::Storage(&self.frame),
            gradient_tex: Binding::Sampled(self.volume.image.view, self.volume.sampler),
            volume_cells: Binding::Texels(&self.no_cells),
            gradient_cells: Binding::Texels(&self.no_cells),
            brick_table: Binding::Texels(self.volume.brick_table()),
            pool_1: Binding::Sampled(self.volume.pool_views()[0], self.volume.sampler),
            pool_2: Binding::Sampled(self.volume.pool_views()[1], self.volume.sampler),
            pool_3: Binding::Sampled(self.volume.pool_views()[2], self.volume.sampler),
            march_status: Binding::Storage(&self.status),
        }
        .list();
        bindings.extend(
            march_bvh::Own {
                nodes: Binding::Storage(&tree.nodes),
                count: Binding::Storage(&tree.count),
            }
            .list(),
        );
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe { self.kernel.dispatch(cmd, &bindings, &[], groups) }
    }
}

/// The render parameters of the probe: RAYS^2 orthographic rays along +z,
/// one per 2x2 voxel column, early termination off.
fn probe_params(dt: f32) -> RenderParams {
    let cell = (EDGE / RAYS) as f32;
    RenderParams {
        base: [0.0, 0.0, -1.0],
        du: [cell, 0.0, 0.0],
        dv: [0.0, cell, 0.0],
        eye_or_dir: [0.0, 0.0, 1.0],
        step: dt,
        ert: ERT_OFF,
        lut_size: LUT_SIZE as u32,
        dims: [EDGE; 3],
        image: [RAYS, RAYS],
        norm: [0.0, 1.0],
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_tiled_by_its_children_collapses_under_any_constants() {
        for m in [
            CostModel {
                sample_ns: 1.0,
                step_ns: 1e-3,
                entry_ns: 1e-3,
            },
            CostModel {
                sample_ns: 1e-3,
                step_ns: 50.0,
                entry_ns: 3.0,
            },
        ] {
            let (l_lo, l_hi, r_lo, r_hi) = ([0, 0, 0], [8, 16, 16], [8, 0, 0], [16, 16, 16]);
            let (leaf, s) = m.leaf(l_lo, r_hi);
            let inner = m.inner(s, m.leaf(l_lo, l_hi), m.leaf(r_lo, r_hi));
            assert!(leaf <= inner, "{m:?}: leaf {leaf} > inner {inner}");
        }
    }

    #[test]
    fn calibration_trees_have_the_shapes_the_formulas_assume() {
        for (leaves, depth) in [(slabs(), 5), (columns(), COLUMN_DEPTH)] {
            let nodes = balanced(&leaves);
            assert_eq!(nodes.len(), 2 * leaves.len() - 1);
            assert_eq!(super::super::tree::height(&nodes), depth + 1);
            assert_eq!(nodes[0].bounds(), ([0; 3], [EDGE as i32; 3]));
        }
        // Every column is one ray's: 2x2 voxels, distinct.
        let mut c: Vec<_> = columns().iter().map(|b| (b[0][0], b[0][1])).collect();
        c.sort_unstable();
        c.dedup();
        assert_eq!(c.len() as u32, RAYS * RAYS);
    }
}
