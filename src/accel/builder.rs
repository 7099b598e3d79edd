//! What every structure's build shares, knowing no structure: the context,
//! objects made once per context on first use (kernel sets, the cost
//! model), and the per-volume value ranges builds read. `Builder::build`
//! itself is in `method.rs`, beside the `Method` trait it calls.

use super::bricks::{self, GpuBricks, RangesFrom};
use super::bricks_host;
use crate::error::{Error, Result};
use crate::gpu::record::Access;
use crate::gpu::Recording;
use crate::gpu::{vk, Buffer, Context, MemoryLocation, Timer, Timings};
use crate::prims::brick_minmax::coarsens_exactly;
use crate::prims::BrickMinMax;
use crate::volume::{GpuVolume, Volume};
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Something made once per context, when a build first needs it, and shared
/// by every build that does: a structure's kernels, the cost model.
pub trait PerContext: Send + Sync + Sized + 'static {
    fn new(ctx: &Context) -> Result<Self>;
}

/// Which per-volume value ranges (computed once per volume upload) a build
/// reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RangeKind {
    /// None: naive marching, and builders that read the volume itself.
    None,
    /// 8^3 brick ranges over the one-voxel apron (phase "ranges").
    Bricks,
    /// Ranges of macro cells of this edge over the apron (phase "cell ranges").
    Cells(u32),
}

/// Per-volume value ranges, each with the GPU time it took (ms; NaN for
/// recorded ranges, which the caller's timer timed).
#[derive(Default)]
pub struct Ranges {
    bricks: Option<(GpuBricks, f64)>,
    cells: Vec<(GpuBricks, f64)>,
    /// The `content_id` of the volume they were computed over (None: none
    /// computed).
    volume: Option<u64>,
}

impl Ranges {
    /// The 8^3 brick ranges.
    pub fn bricks(&self) -> Result<&GpuBricks> {
        self.bricks
            .as_ref()
            .map(|b| &b.0)
            .ok_or_else(|| missing("8^3 brick ranges"))
    }

    /// The ranges of `cell`^3 macro cells.
    pub fn cells(&self, cell: u32) -> Result<&GpuBricks> {
        self.cell_entry(cell)
            .map(|c| &c.0)
            .ok_or_else(|| missing(&format!("ranges of {cell}^3 cells")))
    }

    fn cell_entry(&self, cell: u32) -> Option<&(GpuBricks, f64)> {
        self.cells.iter().find(|c| c.0.brick == cell)
    }

    /// Whether the ranges of `kind` are here.
    pub fn has(&self, kind: RangeKind) -> bool {
        match kind {
            RangeKind::None => true,
            RangeKind::Bricks => self.bricks.is_some(),
            RangeKind::Cells(cell) => self.cell_entry(cell).is_some(),
        }
    }

    /// GPU milliseconds of the ranges of `kind` (0 for none).
    pub fn ms(&self, kind: RangeKind) -> Result<f64> {
        match kind {
            RangeKind::None => Ok(0.0),
            RangeKind::Bricks => self.bricks.as_ref().map(|b| b.1).ok_or_else(|| missing("brick ranges")),
            RangeKind::Cells(cell) => self.cell_entry(cell).map(|c| c.1).ok_or_else(|| missing("cell ranges")),
        }
    }
}

fn missing(what: &str) -> Error {
    Error::invalid(
        "ranges",
        format!("no {what}"),
        "not computed for this volume (Builder::ranges with the structure's RangeKind)",
    )
}

/// A series step's bookkeeping through `record_kinds`: the builder's kept
/// copies (locked for the whole of `ranges_with`), which of them
/// hold which step once the submission completed, and the step's voxels
/// on the host with the timings of the passes made there.
type StepKeep<'a> = (
    &'a mut Vec<StepRanges>,
    &'a mut Vec<(u32, u64)>,
    Option<(&'a Volume, &'a mut Timings)>,
);

/// Builds structures: holds the context and what is made once per context.
pub struct Builder {
    ctx: Context,
    shared: Arc<Mutex<HashMap<TypeId, Arc<dyn Any + Send + Sync>>>>,
    /// What `put` replaced: recordings may still bind it (a stand-in
    /// buffer), so it lives as long as the builder.
    replaced: Arc<Mutex<Vec<Arc<dyn Any + Send + Sync>>>>,
    /// The last series step's ranges, per brick edge: the next step's
    /// start from them (`RangesFrom::Step`). Locked through `ranges_with`,
    /// from recording to marking their step: two threads' submissions may
    /// run in another order than they recorded, and each reads and
    /// rewrites the kept copies.
    step_ranges: Mutex<Vec<StepRanges>>,
}

/// A copy of a series step's ranges of one brick edge.
struct StepRanges {
    /// The step's `StepMark::id`.
    step: u64,
    brick: u32,
    /// What else the ranges depend on: the grid, channels, normalisation.
    dims: [u32; 3],
    channels: u32,
    norms: [[f32; 2]; crate::volume::MAX_CHANNELS],
    ranges: Buffer,
}

impl StepRanges {
    /// Marks the copy as `volume`'s ranges, no step's until the submission
    /// that makes it completed (`Builder::ranges` then sets the step).
    fn pending(&mut self, volume: &GpuVolume) {
        (self.step, self.dims, self.channels, self.norms) = (0, volume.dims, volume.channels, volume.norms);
    }

    /// The bricks of `volume` whose ranges differ from these, where these
    /// are its step's or the step before's ranges of `brick`^3 bricks.
    fn changed_for(&self, volume: &GpuVolume, brick: u32) -> Option<Vec<u32>> {
        let same = self.brick == brick
            && self.dims == volume.dims
            && self.channels == volume.channels
            && self.norms == volume.norms;
        let mark = volume.step_mark().filter(|_| same)?;
        match &mark.since {
            _ if mark.id == self.step => Some(Vec::new()),
            Some((before, delta)) if *before == self.step => Some(delta.bricks_changed(brick)),
            _ => None,
        }
    }
}

impl Builder {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Builder {
            ctx: ctx.clone(),
            shared: Arc::new(Mutex::new(HashMap::new())),
            replaced: Default::default(),
            step_ranges: Mutex::new(Vec::new()),
        })
    }

    /// A builder sharing this one's per-context objects (kernels, the cost
    /// model) with series step ranges of its own: `bench` times each
    /// structure's new step as if it played the series alone.
    pub fn fork(&self) -> Builder {
        Builder {
            ctx: self.ctx.clone(),
            shared: self.shared.clone(),
            replaced: self.replaced.clone(),
            step_ranges: Mutex::new(Vec::new()),
        }
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// The `T` of this context (kernels, the cost model), made on first use.
    pub fn shared<T: PerContext>(&self) -> Result<Arc<T>> {
        let mut map = self.shared.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(k) = map.get(&TypeId::of::<T>()) {
            if let Ok(k) = Arc::clone(k).downcast::<T>() {
                return Ok(k);
            }
        }
        let k = Arc::new(T::new(&self.ctx)?);
        map.insert(TypeId::of::<T>(), k.clone());
        Ok(k)
    }

    /// Uses `value` as this context's `T` from now on (a cost model
    /// measured earlier, for builds that do not depend on the machine's
    /// load).
    pub fn put<T: PerContext>(&self, value: T) {
        let mut map = self.shared.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(old) = map.insert(TypeId::of::<T>(), Arc::new(value)) {
            self.replaced.lock().unwrap_or_else(|p| p.into_inner()).push(old);
        }
    }

    /// The `T` of this context if a build made it already (nothing is made).
    pub fn made<T: PerContext>(&self) -> Option<Arc<T>> {
        let map = self.shared.lock().unwrap_or_else(|p| p.into_inner());
        map.get(&TypeId::of::<T>())
            .and_then(|k| Arc::clone(k).downcast::<T>().ok())
    }

    /// The per-volume ranges of every kind in `kinds` (each once), computed
    /// and waited for: once per volume upload. A series step's
    /// (`GpuVolume::step_mark`) start from the step before's where this
    /// builder computed them: only the bricks whose voxels changed are
    /// computed, the same ranges bit for bit.
    pub fn ranges(&self, kinds: &[RangeKind], volume: &GpuVolume) -> Result<(Ranges, Timings)> {
        self.ranges_with(kinds, volume, None)
    }

    /// As `ranges`, with `host`, the voxels `volume` holds (trusted, as
    /// `replace`'s `previous`: others give wrong ranges): on a CPU device a
    /// series step's changed bricks of a one-channel 8- or 16-bit volume
    /// with its cells copy are then computed there (`bricks_host`: the same
    /// ranges, faster than the device's pass on lavapipe), timed as "PASS
    /// (host)". Anything else is made as `ranges` makes it.
    pub fn ranges_with(
        &self,
        kinds: &[RangeKind],
        volume: &GpuVolume,
        host: Option<&Volume>,
    ) -> Result<(Ranges, Timings)> {
        let mut step_ranges = self.step_ranges.lock().unwrap_or_else(|p| p.into_inner());
        // One submission, one timed pass a kind.
        let passes = distinct(kinds)?.len() as u32;
        let mut timer = Timer::new(&self.ctx, passes)?;
        let mut kept = Vec::new();
        let mut host_t = Timings::default();
        let host = host.map(|h| (h, &mut host_t));
        let mut ranges = self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            let kept = Some((&mut *step_ranges, &mut kept, host));
            self.record_kinds(cmd, Some(&mut timer), kinds, volume, kept)
        })?;
        // The copies kept for the next step are whole now.
        for (brick, step) in kept {
            if let Some(k) = step_ranges.iter_mut().find(|k| k.brick == brick) {
                k.step = step;
            }
        }
        drop(step_ranges);
        let mut t = timer.results()?;
        t.extend(host_t);
        let several = ranges.cells.len() > 1;
        // A pass's time, on the device or the host.
        let ms = |pass: String| t.get(&format!("{pass} (host)")).map_or_else(|| t.phase(&pass), Ok);
        if let Some((_, at)) = &mut ranges.bricks {
            *at = ms(size_and_pass(RangeKind::Bricks, several).1)?;
        }
        for (b, at) in &mut ranges.cells {
            *at = ms(size_and_pass(RangeKind::Cells(b.brick), several).1)?;
        }
        Ok((ranges, t))
    }

    /// As `ranges`, recorded into `cmd` (passes "ranges" and "cell ranges"
    /// on `timer`), every brick from the voxels: the ranges are ready after
    /// the submission, and `Ranges::ms` is NaN for them (read the caller's
    /// timer). Ends with compute writes: a barrier from
    /// `Access::COMPUTE_WRITE` to `Access::COMPUTE_READ` before a build
    /// reads them (`record_build` begins with one).
    pub fn record_ranges(
        &self,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        kinds: &[RangeKind],
        volume: &GpuVolume,
    ) -> Result<Ranges> {
        self.record_kinds(cmd, timer, kinds, volume, None)
    }

    /// `record_ranges`; with `kept`, from and for a series step's kept
    /// ranges, `kept` hearing which copies hold which step once the
    /// submission completed, and with the step's host voxels where given
    /// (host passes timed there).
    fn record_kinds(
        &self,
        cmd: Recording<'_>,
        mut timer: Option<&mut Timer>,
        kinds: &[RangeKind],
        volume: &GpuVolume,
        mut kept: Option<StepKeep>,
    ) -> Result<Ranges> {
        self.ctx.check_is(cmd.context(), "command buffer")?;
        self.ctx.check_is(volume.context(), "volume")?;
        let mut ranges = Ranges {
            volume: Some(volume.content_id()),
            ..Ranges::default()
        };
        let kinds = distinct(kinds)?;
        let several = several_cells(&kinds);
        let minmax = self.shared::<BrickMinMax>()?;
        for kind in kinds {
            let (size, pass) = size_and_pass(kind, several);
            let mut b = GpuBricks::allocate(&self.ctx, volume, size)?;
            let finer = ranges.finer(size).filter(|_| coarsens_exactly(volume));
            let step = volume.step_mark().map(|m| m.id);
            match (finer, step, kept.as_mut()) {
                (Some(f), _, _) => b.record(cmd, timer.as_deref_mut(), &pass, &minmax, volume, RangesFrom::Finer(f))?,
                (None, Some(step), Some((copies, kept, host))) => {
                    let host = host.as_mut().map(|(v, t)| (*v, &mut **t));
                    let b = (&mut b, host);
                    self.record_step_ranges(cmd, (timer.as_deref_mut(), &pass), &minmax, b, copies, volume)?;
                    kept.push((size, step));
                }
                _ => b.record(cmd, timer.as_deref_mut(), &pass, &minmax, volume, RangesFrom::Volume)?,
            }
            ranges.insert(kind, b, f64::NAN);
        }
        Ok(ranges)
    }

    /// Records `b`'s ranges from the step before's where this builder kept
    /// them (only the changed bricks computed), else from the volume, and a
    /// copy of them for the next step (marked as no step's until the
    /// submission completed: `ranges`).
    fn record_step_ranges(
        &self,
        cmd: Recording<'_>,
        (timer, pass): (Option<&mut Timer>, &str),
        minmax: &BrickMinMax,
        (b, host): (&mut GpuBricks, Option<(&Volume, &mut Timings)>),
        kept: &mut Vec<StepRanges>,
        volume: &GpuVolume,
    ) -> Result<()> {
        let at = kept.iter().position(|k| k.brick == b.brick);
        let changed = at.and_then(|i| Some((i, kept[i].changed_for(volume, b.brick)?)));
        if let (Some((i, changed)), Some((host, timings))) = (&changed, host) {
            let i = *i;
            let t = std::time::Instant::now();
            if bricks_host::serves(volume, host)
                && bricks_host::step_on_host(host, volume.norms[0], changed, &mut kept[i].ranges, b)
            {
                timings.push(format!("{pass} (host)"), t.elapsed().as_secs_f64() * 1e3);
                kept[i].pending(volume);
                return Ok(());
            }
        }
        match changed {
            Some((i, changed)) => {
                let from = RangesFrom::Step {
                    ranges: &kept[i].ranges,
                    changed,
                };
                b.record(cmd, timer, pass, minmax, volume, from)?;
            }
            None => b.record(cmd, timer, pass, minmax, volume, RangesFrom::Volume)?,
        }
        let i = match at.filter(|&i| kept[i].ranges.size() == b.ranges.size()) {
            Some(i) => i,
            None => {
                if let Some(i) = at {
                    kept.swap_remove(i);
                }
                let ranges = Buffer::new(
                    &self.ctx,
                    "last step's brick ranges",
                    b.ranges.size(),
                    vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST,
                    MemoryLocation::GpuOnly,
                )?;
                kept.push(StepRanges {
                    step: 0,
                    brick: b.brick,
                    dims: volume.dims,
                    channels: volume.channels,
                    norms: volume.norms,
                    ranges,
                });
                kept.len() - 1
            }
        };
        b.record_keep(cmd, &kept[i].ranges)?;
        if self.ctx.info().is_cpu() {
            // A later step may read the copy on the host (`step_on_host`).
            cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
        }
        kept[i].pending(volume);
        Ok(())
    }
}

impl Ranges {
    /// A build over `volume` can read these: they were computed over its
    /// texels (this upload, this series step), or none were.
    pub fn check_volume(&self, volume: &GpuVolume) -> Result<()> {
        match self.volume {
            Some(id) if id != volume.content_id() => Err(crate::error::Error::invalid(
                "ranges",
                "of another upload or series step",
                "a build reads the ranges of the volume it is built over: compute them for it (Builder::ranges)",
            )),
            _ => Ok(()),
        }
    }

    /// The coarsest ranges here whose brick edge divides `edge` (and is
    /// smaller): the cheapest to make `edge`'s from.
    fn finer(&self, edge: u32) -> Option<&GpuBricks> {
        let bricks = self.bricks.iter().map(|b| &b.0);
        let cells = self.cells.iter().map(|c| &c.0);
        bricks
            .chain(cells)
            .filter(|b| b.brick < edge && edge.is_multiple_of(b.brick))
            .max_by_key(|b| b.brick)
    }

    fn insert(&mut self, kind: RangeKind, bricks: GpuBricks, ms: f64) {
        match kind {
            RangeKind::Bricks => self.bricks = Some((bricks, ms)),
            _ => self.cells.push((bricks, ms)),
        }
    }
}

/// The kinds that need computing, each once, finest first (coarser ranges
/// are made from finer ones); cell edges checked.
fn distinct(kinds: &[RangeKind]) -> Result<Vec<RangeKind>> {
    let mut out: Vec<RangeKind> = Vec::new();
    for &k in kinds {
        if let RangeKind::Cells(cell) = k {
            check_cell(cell)?;
        }
        if k != RangeKind::None && !out.contains(&k) {
            out.push(k);
        }
    }
    out.sort_by_key(|&k| size_and_pass(k, false).0);
    Ok(out)
}

/// Whether `kinds` holds ranges of more than one cell edge (then each
/// pass is named by its edge).
fn several_cells(kinds: &[RangeKind]) -> bool {
    kinds.iter().filter(|k| matches!(k, RangeKind::Cells(_))).count() > 1
}

/// A kind's brick edge and pass name: "ranges" (8^3 bricks), "cell
/// ranges", or "cell ranges 4" among several edges.
fn size_and_pass(kind: RangeKind, several: bool) -> (u32, String) {
    match kind {
        RangeKind::Cells(cell) if several => (cell, format!("cell ranges {cell}")),
        RangeKind::Cells(cell) => (cell, "cell ranges".into()),
        _ => (bricks::BRICK, "ranges".into()),
    }
}

/// Checks a macro-cell edge against the `cell` parameter's schema.
pub fn check_cell(cell: u32) -> Result<()> {
    super::params::CELL.parse(&cell.to_string()).map(|_| ())
}

impl PerContext for BrickMinMax {
    fn new(ctx: &Context) -> Result<Self> {
        BrickMinMax::new(ctx)
    }
}
