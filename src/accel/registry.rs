//! The registry: the [`Method`] trait every structure implements, the
//! [`TABLE`] of them, and what iterates it ([`Builder`], the renderer's
//! kernel cache, the CLI, the bench and the tests).

use super::bricks::{self, GpuBricks};
use super::classify::Classify;
use super::cost::CostModel;
use super::stats::Stats;
use super::tree::GpuTree;
use super::{auto, distance, grid, hybrid, kd, lbvh, naive, octree};
use crate::error::{Error, Result};
use crate::gpu::timings::Timings;
use crate::gpu::{vk, Binding, Context, Shader, Timer};
use crate::prims::BrickMinMax;
use crate::spatial::Traversal;
use crate::tf::{GpuTransferFunction, TransferFunction};
use crate::volume::{GpuVolume, Volume};
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Every structure, one line each, in the order the CLI and the bench list them.
pub const TABLE: &[Accel] = &[
    Accel(&naive::Naive),
    Accel(&lbvh::LbvhMethod),
    Accel(&grid::GridMethod),
    Accel(&distance::DistanceMethod { octants: false }),
    Accel(&distance::DistanceMethod { octants: true }),
    Accel(&kd::cpu::KdCpu),
    Accel(&kd::gpu::KdGpu),
    Accel(&hybrid::HybridMethod),
    Accel(&octree::OctreeMethod(Traversal::O84)),
    Accel(&octree::OctreeMethod(Traversal::O89)),
    Accel(&octree::OctreeMethod(Traversal::O93)),
    Accel(&octree::OctreeMethod(Traversal::Rev)),
    Accel(&auto::AutoMethod),
];

/// Which per-volume value ranges (computed once per volume upload) a
/// structure's build reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RangeKind {
    /// None: naive marching, and builders that read the volume itself.
    None,
    /// 8^3 brick ranges over the one-voxel apron.
    Bricks,
    /// Macro-cell ranges (`BuildOptions::cell`) over the apron.
    Cells,
}

/// The march kernel that renders a structure: a shader of `glsl/march/`,
/// its specialization constants and its push-block size.
#[derive(Clone, Copy, Debug)]
pub struct March {
    pub shader: Shader,
    pub constants: &'static [u32],
    pub push_size: usize,
}

impl March {
    /// A kernel without push constants or specialization.
    pub const fn plain(shader: Shader) -> Self {
        March {
            shader,
            constants: &[],
            push_size: 0,
        }
    }
}

/// What a build reads: the volume and transfer function on the host (for
/// host-built structures) and on the GPU.
pub struct BuildInput<'a> {
    pub volume: &'a Volume,
    pub gpu_volume: &'a GpuVolume,
    pub tf: &'a TransferFunction,
    pub gpu_tf: &'a GpuTransferFunction,
}

/// Parameters of every structure (the paper's columns); each structure reads
/// the ones [`Method::params`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct BuildOptions {
    pub classify: Classify,
    pub kd: kd::KdParams,
    /// Macro-cell edge of the grid and the hybrid (a power of two).
    pub cell: u32,
    /// Cost-driven leaves for the trees (`accel::cost`): a subtree or
    /// region cheaper as one leaf becomes one. Off reproduces the paper.
    pub collapse: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            classify: Classify::Range,
            kd: kd::KdParams::default(),
            cell: grid::CELL,
            collapse: false,
        }
    }
}

impl BuildOptions {
    /// Checks every parameter, before any GPU work.
    pub fn validate(&self) -> Result<()> {
        grid::check_cell(self.cell)
    }
}

/// A built structure: what its march kernel reads beyond the four bindings
/// every march kernel has (render parameters, volume, LUT, frame).
pub trait Built {
    /// Bindings 4.. of the march kernel, in binding order.
    fn bindings(&self) -> Vec<Binding<'_>>;
    /// The march kernel's push constants (empty for none).
    fn push(&self) -> Vec<u8> {
        Vec::new()
    }
    /// The paper's Table 1 statistics (None for naive). May read the
    /// structure back once; builds read back only a collapsed tree's root
    /// (`GpuTree::whole_box_leaf`).
    fn stats(&self) -> Result<Option<Stats>>;
    /// The tree, for structures in the shared tree node format.
    fn tree(&self) -> Option<&GpuTree> {
        None
    }
    /// For `auto`: what it chose (the structure frames are marched with).
    fn choice(&self) -> Option<&auto::Choice> {
        None
    }
    /// Whether this is a tree of one leaf covering the volume, which
    /// `Builder::build` marches with the naive kernel.
    fn marched_naively(&self) -> bool {
        false
    }
}

/// A skipping structure: what it reads, how it is built, how it is marched.
/// Implement it in the structure's module and add one line to [`TABLE`].
pub trait Method: Sync {
    /// The CLI name (`--accel NAME`).
    fn name(&self) -> &'static str;
    /// One line for listings: what it is and who it is after.
    fn description(&self) -> &'static str;
    /// The per-volume ranges its build reads.
    fn ranges(&self) -> RangeKind;
    /// Its macro-cell edge when `--cell` is not given (structures that read
    /// cell ranges).
    fn default_cell(&self) -> u32 {
        grid::CELL
    }
    /// The parameters it reads from `options`, as (name, value) for
    /// printouts, EXR metadata and bench records.
    fn params(&self, options: &BuildOptions) -> Vec<(&'static str, String)>;
    /// Its march kernel.
    fn march(&self) -> March;
    /// The parameter sets the exactness checks (the identity tests and
    /// `bench --suite hard`) build it with: (label, options).
    fn variants(&self) -> Vec<(String, BuildOptions)> {
        vec![(self.name().to_string(), BuildOptions::default())]
    }
    /// Whether `record_build` records the whole build into one command
    /// buffer. Host-driven builders (a CPU build, a readback, one submission
    /// per tree level) return false and implement `build` instead.
    fn recordable(&self) -> bool {
        true
    }
    /// Records the build for the input's transfer function into `cmd`,
    /// timing its passes with `timer`. Barriers: begins with the `prims`
    /// entry barrier (earlier compute and transfer writes visible) and ends
    /// with compute writes; order the march after it with a barrier from
    /// `Access::COMPUTE_WRITE` to `Access::COMPUTE_READ`.
    fn record_build(
        &self,
        builder: &Builder,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        options: &BuildOptions,
    ) -> Result<Box<dyn Built>> {
        let _ = (builder, cmd, timer, input, ranges, options);
        Err(Error::Unsupported(format!(
            "{} is built by the host (it reads results back between passes): call build, not record_build",
            self.name()
        )))
    }
    /// Builds and waits: the path a transfer-function change takes. Returns
    /// the structure and the time of each phase. The default submits
    /// `record_build` once.
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        options: &BuildOptions,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let ctx = builder.context();
        let mut timer = Timer::new(ctx, 16)?;
        let built = ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            self.record_build(builder, cmd, Some(&mut timer), input, ranges, options)
        })?;
        Ok((built, timer.results()?))
    }
}

/// A handle to a registry entry: cheap to copy, compared by name.
#[derive(Clone, Copy)]
pub struct Accel(pub &'static dyn Method);

impl Accel {
    /// Every registered structure ([`TABLE`]).
    pub const ALL: &'static [Accel] = TABLE;

    /// Naive marching, the reference every structure must equal.
    pub fn naive() -> Accel {
        TABLE[0]
    }

    pub fn method(self) -> &'static dyn Method {
        self.0
    }

    pub fn name(self) -> &'static str {
        self.0.name()
    }

    pub fn is_naive(self) -> bool {
        self == Accel::naive()
    }

    /// The registered structures except naive.
    pub fn skipping() -> impl Iterator<Item = Accel> {
        TABLE.iter().copied().filter(|a| !a.is_naive())
    }
}

impl PartialEq for Accel {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Accel {}

impl std::hash::Hash for Accel {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state)
    }
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::fmt::Display for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Accel {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        TABLE.iter().copied().find(|a| a.name() == s).ok_or_else(|| {
            let names: Vec<&str> = TABLE.iter().map(|a| a.name()).collect();
            Error::invalid("accel", s, format!("expected one of: {}", names.join(", ")))
        })
    }
}

#[cfg(feature = "serde")]
impl serde::Serialize for Accel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// A tree collapsed (or built) to one leaf covering the volume box, marched
/// with the naive kernel: it keeps the tree's statistics, binds nothing.
struct MarchedNaively(Box<dyn Built>);

impl Built for MarchedNaively {
    fn bindings(&self) -> Vec<Binding<'_>> {
        Vec::new()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        self.0.stats()
    }
    fn tree(&self) -> Option<&GpuTree> {
        self.0.tree()
    }
    fn marched_naively(&self) -> bool {
        true
    }
}

/// A built structure with the registry entry that built it.
pub struct Structure {
    pub accel: Accel,
    pub built: Box<dyn Built>,
}

impl Structure {
    /// Naive marching: no structure at all.
    pub fn naive() -> Structure {
        Structure::nothing(Accel::naive())
    }

    /// A structure with nothing to bind (naive, or an entry that needs no data).
    pub fn nothing(accel: Accel) -> Structure {
        Structure {
            accel,
            built: Box::new(naive::NoData),
        }
    }

    pub fn accel(&self) -> Accel {
        self.accel
    }

    /// The paper's Table 1 statistics (None for naive).
    pub fn stats(&self) -> Result<Option<Stats>> {
        self.built.stats()
    }

    /// The tree, for structures in the shared tree node format.
    pub fn tree(&self) -> Option<&GpuTree> {
        self.built.tree()
    }

    /// Whether this tree is one leaf covering the volume, marched with the
    /// naive kernel (`accel` is then naive; `stats` and `tree` are the tree's).
    pub fn marched_naively(&self) -> bool {
        self.built.marched_naively()
    }

    /// For `auto`: what it chose; `accel` is then the chosen structure.
    pub fn choice(&self) -> Option<&auto::Choice> {
        self.built.choice()
    }
}

/// Per-volume value ranges, each with the GPU time it took (ms).
pub struct Ranges {
    /// 8^3 brick ranges; None if no structure in use reads them.
    pub bricks: Option<(GpuBricks, f64)>,
    /// Macro-cell ranges; None if no structure in use reads them.
    pub cells: Option<(GpuBricks, f64)>,
}

impl Ranges {
    /// The 8^3 brick ranges.
    pub fn bricks(&self) -> Result<&GpuBricks> {
        self.bricks.as_ref().map(|b| &b.0).ok_or_else(|| {
            Error::invalid(
                "ranges",
                "no brick ranges",
                "this structure needs 8^3 brick ranges (Builder::ranges_for with it)",
            )
        })
    }

    /// The macro-cell ranges of `cell`^3 cells.
    pub fn cells(&self, cell: u32) -> Result<&GpuBricks> {
        match &self.cells {
            Some((c, _)) if c.brick == cell => Ok(c),
            Some((c, _)) => Err(Error::invalid(
                "cell",
                cell.to_string(),
                format!("ranges were computed for cells of {}", c.brick),
            )),
            None => Err(Error::invalid(
                "ranges",
                "no cell ranges",
                "this structure needs cell ranges (Builder::ranges_for with it)",
            )),
        }
    }

    /// GPU milliseconds of the per-volume ranges of `kind` (0 for none; NaN
    /// for recorded ranges, which the caller's timer timed).
    pub fn ms(&self, kind: RangeKind) -> Result<f64> {
        Ok(match kind {
            RangeKind::None => 0.0,
            RangeKind::Bricks => self.bricks.as_ref().map(|b| b.1).ok_or_else(|| self.missing("brick"))?,
            RangeKind::Cells => self.cells.as_ref().map(|c| c.1).ok_or_else(|| self.missing("cell"))?,
        })
    }

    fn missing(&self, what: &str) -> Error {
        Error::invalid("ranges", format!("no {what} ranges"), "not computed for this volume")
    }
}

/// A set of kernels a structure's build uses, created once per context on
/// first use ([`Builder::kernels`]).
pub trait KernelSet: Send + Sync + Sized + 'static {
    fn new(ctx: &Context) -> Result<Self>;
}

/// Builds every structure. Kernel sets are created once per context, when a
/// structure first needs them, and shared by every structure that does.
pub struct Builder {
    ctx: Context,
    kernels: Mutex<HashMap<TypeId, Arc<dyn Any + Send + Sync>>>,
    cost: Mutex<Option<CostModel>>,
}

impl Builder {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Builder {
            ctx: ctx.clone(),
            kernels: Mutex::new(HashMap::new()),
            cost: Mutex::new(None),
        })
    }

    /// The traversal cost model of this device, measured on first use (a
    /// few small timed dispatches; see `accel::cost`) and kept.
    pub fn cost_model(&self) -> Result<CostModel> {
        let mut cost = self.cost.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(m) = *cost {
            return Ok(m);
        }
        let m = CostModel::measure(&self.ctx)?;
        *cost = Some(m);
        Ok(m)
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// The kernel set `K` of this context, created on first use.
    pub fn kernels<K: KernelSet>(&self) -> Result<Arc<K>> {
        let mut map = self.kernels.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(k) = map.get(&TypeId::of::<K>()) {
            if let Ok(k) = Arc::clone(k).downcast::<K>() {
                return Ok(k);
            }
        }
        let k = Arc::new(K::new(&self.ctx)?);
        map.insert(TypeId::of::<K>(), k.clone());
        Ok(k)
    }

    /// Per-volume ranges of every kind `accels` read (brick ranges as
    /// "ranges", cell ranges of `cell`^3 as "cell ranges"): once per volume
    /// upload.
    pub fn ranges_for(&self, accels: &[Accel], volume: &GpuVolume, cell: u32) -> Result<(Ranges, Timings)> {
        grid::check_cell(cell)?;
        let reads = |k: RangeKind| accels.iter().any(|a| a.method().ranges() == k);
        let mut t = Timings::default();
        let mut ranges = Ranges {
            bricks: None,
            cells: None,
        };
        if reads(RangeKind::Bricks) || reads(RangeKind::Cells) {
            let minmax = self.kernels::<BrickMinMax>()?;
            if reads(RangeKind::Bricks) {
                let (b, ms) = GpuBricks::compute(&self.ctx, &minmax, volume, bricks::BRICK)?;
                t.push("ranges", ms);
                ranges.bricks = Some((b, ms));
            }
            if reads(RangeKind::Cells) {
                let (c, ms) = GpuBricks::compute(&self.ctx, &minmax, volume, cell)?;
                t.push("cell ranges", ms);
                ranges.cells = Some((c, ms));
            }
        }
        Ok((ranges, t))
    }

    /// As `ranges_for`, recorded into `cmd` (passes "ranges" and "cell
    /// ranges" on `timer`): the ranges are ready after the submission, and
    /// `Ranges::ms` is NaN for them (read the caller's timer). Ends with
    /// compute writes: a barrier from `Access::COMPUTE_WRITE` to
    /// `Access::COMPUTE_READ` before a build reads them (`record_build`
    /// begins with one).
    pub fn record_ranges_for(
        &self,
        cmd: vk::CommandBuffer,
        mut timer: Option<&mut Timer>,
        accels: &[Accel],
        volume: &GpuVolume,
        cell: u32,
    ) -> Result<Ranges> {
        grid::check_cell(cell)?;
        let reads = |k: RangeKind| accels.iter().any(|a| a.method().ranges() == k);
        let mut ranges = Ranges {
            bricks: None,
            cells: None,
        };
        for (kind, size, pass) in [
            (RangeKind::Bricks, bricks::BRICK, "ranges"),
            (RangeKind::Cells, cell, "cell ranges"),
        ] {
            if reads(kind) {
                let minmax = self.kernels::<BrickMinMax>()?;
                let b = GpuBricks::allocate(&self.ctx, volume, size)?;
                b.record(cmd, timer.as_deref_mut(), pass, &minmax, volume)?;
                match kind {
                    RangeKind::Bricks => ranges.bricks = Some((b, f64::NAN)),
                    _ => ranges.cells = Some((b, f64::NAN)),
                }
            }
        }
        Ok(ranges)
    }

    /// The ranges of every registered structure.
    pub fn ranges(&self, volume: &GpuVolume, cell: u32) -> Result<(Ranges, Timings)> {
        self.ranges_for(TABLE, volume, cell)
    }

    /// Builds `accel` for the input's transfer function and waits: the path
    /// a TF change takes. Returns the structure and its timings per phase.
    pub fn build(
        &self,
        accel: Accel,
        input: &BuildInput,
        ranges: &Ranges,
        options: &BuildOptions,
    ) -> Result<(Structure, Timings)> {
        options.validate()?;
        let (built, mut t) = accel.method().build(self, input, ranges, options)?;
        // `auto` is marched as the structure it chose.
        let accel = built.choice().map_or(accel, |c| c.accel);
        // Only trees the plain tree kernel marches: the hybrid walks a grid
        // inside its leaves, so its one-leaf tree still skips.
        let plain_tree = accel.method().march().shader.name == super::tree::TREE_MARCH.shader.name;
        let whole = match built.tree() {
            Some(tree) if plain_tree => t.cpu("root check", || {
                tree.whole_box_leaf(input.gpu_volume.dims, options.collapse)
            })?,
            _ => None,
        };
        if whole.is_some() {
            // One leaf that is the whole volume box: nothing to skip, so the
            // naive kernel takes the same samples without a traversal.
            let built = Box::new(MarchedNaively(built));
            return Ok((
                Structure {
                    accel: Accel::naive(),
                    built,
                },
                t,
            ));
        }
        Ok((Structure { accel, built }, t))
    }

    /// Records the build of a recordable structure into `cmd` (see
    /// [`Method::record_build`] for the barriers); host-driven structures
    /// return an error saying so.
    pub fn record_build(
        &self,
        accel: Accel,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        options: &BuildOptions,
    ) -> Result<Structure> {
        options.validate()?;
        let built = accel.method().record_build(self, cmd, timer, input, ranges, options)?;
        Ok(Structure { accel, built })
    }
}

impl KernelSet for BrickMinMax {
    fn new(ctx: &Context) -> Result<Self> {
        BrickMinMax::new(ctx)
    }
}

impl KernelSet for super::Classifier {
    fn new(ctx: &Context) -> Result<Self> {
        super::Classifier::new(ctx)
    }
}

/// `--collapse on|off`.
pub fn parse_collapse(s: &str) -> Result<bool> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        other => Err(Error::invalid("collapse", other, "expected on or off")),
    }
}

/// The cost-driven leaves parameter, as the trees print it.
pub(crate) fn collapse_param(on: bool) -> (&'static str, String) {
    ("collapse", if on { "on" } else { "off" }.to_string())
}

/// The classification parameter, as structures that classify 8^3 bricks print it.
pub(crate) fn classify_param(c: Classify) -> (&'static str, String) {
    ("classify", c.describe().to_string())
}
