//! `--accel auto`: the fastest exact structure for this volume, transfer
//! function and frame. Its candidates are naive marching, the distance
//! maps (octant maps on small grids, else cube maps) at cells 4 and 8, the
//! macro-cell grid at cells 8 and 16, those the device holds, and on GPUs
//! a collapsed k-d tree built on the device (`choose::candidates`,
//! `choose::prices_tree`). Each is built, and its kernel counted on a
//! sparse sample of the frame's tiles (`probe`): iterations of the sample
//! loop, traversal steps and regions, per SIMD group. The device's kernel
//! constants (`model`, measured once per device, driver and kernel build:
//! `calibrate`, `cache`) price each count; the cheapest wins. A close call
//! (a runner-up within `choose::CLOSE` of the best, or naive within
//! `choose::NAIVE_GUARD` of a skipping best) is settled by timing the close
//! ones, and the k-d tree, which the model overprices on GPUs, is timed
//! against the best (`choose::with_tree`): on a quarter to an eighth of the
//! frame's tiles, or on the whole frame where it is predicted to take only
//! a few milliseconds (`choose::to_time`, `choose::trial_tiles`).
//!
//! The frames are those the build is for (`BuildInput::frames`: camera,
//! step, early termination, sample filter, size, mode), so the choice
//! accounts for all of them; a build for several views (an orbit) is
//! priced and timed on up to `choose::PRICED_VIEWS` of them, each probed
//! with a whole frame's tiles. Re-made on every build, i.e. every transfer
//! function change; a new time step keeps it while it holds (`keep.rs`,
//! `Builder::build_step`). See `docs/structures.md`, "auto".

pub mod cache;
pub mod calibrate;
pub mod choose;
pub mod keep;
pub mod model;

use super::builder::{Builder, RangeKind, Ranges};
use super::method::{Accel, BuildInput, Built, March, MarchedAs, MarchedKind, Method, Structure};
use super::naive::NAIVE;
use super::params::{Param, Params};
use super::probe::{time_interleaved, Counts, FrameProbe, Statistic, COUNT_TILES};
use super::stats::Stats;
use crate::desc::FrameDesc;
use crate::error::{Error, Result};
use crate::gpu::{Bound, DeviceInfo, Timings};
use crate::volume::GpuVolume;
pub use cache::{CostTable, Source};
pub use choose::{Candidate, Priced, OCTANT_CELLS};
pub use keep::{StepBuild, KEEP_SHARE};
pub use model::{CostKey, KernelCost};
use std::time::Instant;

/// Timed rounds of a close call (after one untimed); the least time of
/// each candidate counts (noise only adds time, and a cold shader cache
/// slows more than the first dispatch).
const TRIAL_ROUNDS: usize = 3;

/// The size of the frame auto prices candidates on when the build names
/// none (`BuildInput::frames` empty): the default orbit at this size.
pub const DEFAULT_FRAME: u32 = 512;

/// What auto chose and why.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Choice {
    /// The structure the frames are marched with.
    pub accel: Accel,
    /// `distance-octant (cell 4)`, `grid (cell 16)`, `kd-gpu (MLS=32, collapsed)` or `naive`.
    pub label: String,
    /// Every candidate as priced, in candidate order (naive first).
    pub priced: Vec<Priced>,
    /// Whether the choice was settled by timing: a close call, or the k-d
    /// tree against the best prediction (`choose::with_tree`).
    pub timed: bool,
    /// Whether the trial ran for the k-d tree alone (no close call).
    pub timed_for_tree: bool,
    /// Whether that trial timed whole frames (else a sample of the tiles).
    pub timed_whole_frames: bool,
    /// The views it was priced and timed on (`choose::priced_views`): the
    /// predictions are their mean, the trial times their sum.
    pub views: usize,
    /// Where the kernel constants came from (one per distinct source).
    pub model: Vec<String>,
    /// Candidates left out, and why.
    pub notes: Vec<String>,
    /// The chosen candidate: its structure and parameters (what a later
    /// time step keeps, `Builder::build_step`).
    #[cfg_attr(feature = "serde", serde(skip))]
    pub candidate: Candidate,
    /// The share of the chosen structure's regions that were active when
    /// it was chosen (None: naive, or a structure with no share to compare).
    pub share: Option<f64>,
    /// The mode and transfer function (its spec) it was chosen for: a
    /// later step keeps it only for the same.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub mode: crate::desc::Mode,
    pub tf: String,
    /// Time steps this choice has been kept for without pricing (0: priced
    /// for this build), and the share of active regions on the last.
    pub kept: u32,
    pub share_now: Option<f64>,
}

impl Choice {
    /// `distance-octant (cell 4)`, `grid (cell 16)`, `kd-gpu (MLS=32, collapsed)` or `naive`.
    pub fn describe(&self) -> String {
        self.label.clone()
    }

    /// The chosen candidate's predicted frame time over naive's.
    pub fn predicted_vs_naive(&self) -> f64 {
        let chosen = self.priced.iter().find(|p| p.label == self.label);
        match (chosen, self.priced.first()) {
            (Some(c), Some(n)) if n.predicted > 0.0 => c.predicted / n.predicted,
            _ => 1.0,
        }
    }

    /// One line with the figures behind the choice.
    pub fn reason(&self) -> String {
        let predicted: Vec<String> = self
            .priced
            .iter()
            .map(|p| format!("{} {}", p.label, ms(p.predicted)))
            .collect();
        let per = match self.views {
            1 => String::new(),
            n => format!(" (a frame, the mean of {n} views)"),
        };
        let mut line = format!("predicted ms{per}: {}", predicted.join(", "));
        if self.timed {
            let timed: Vec<String> = self
                .priced
                .iter()
                .filter_map(|p| p.trial.map(|t| format!("{} {}", p.label, ms(t))))
                .collect();
            let on = match (self.timed_whole_frames, self.views) {
                (true, 1) => "whole frames".to_string(),
                (false, 1) => "the probe tiles".to_string(),
                (true, n) => format!("whole frames of {n} views, summed"),
                (false, n) => format!("the probe tiles of {n} views, summed"),
            };
            let why = match self.timed_for_tree {
                true => "the tree against the best",
                false => "close",
            };
            line.push_str(&format!("; {why}, timed on {on}: {}", timed.join(", ")));
        }
        line.push_str(&format!("; model {}", self.model.join(", ")));
        if let (true, Some(then), Some(now)) = (self.kept > 0, self.share, self.share_now) {
            line.push_str(&format!(
                "; kept for {} new time step(s) without pricing: active regions {:.2} % (at the choice {:.2} %)",
                self.kept,
                100.0 * now,
                100.0 * then
            ));
        }
        if !self.notes.is_empty() {
            line.push_str(&format!("; {}", self.notes.join("; ")));
        }
        line
    }
}

/// Milliseconds for the reason line: three decimals below 1 ms (a GPU's
/// 0.051), two below 10, one above.
fn ms(v: f64) -> String {
    match v {
        v if v >= 10.0 => format!("{v:.1}"),
        v if v >= 1.0 => format!("{v:.2}"),
        v => format!("{v:.3}"),
    }
}

/// The built structure and the choice behind it
/// (`Structure::built_as::<Chosen>()`).
pub struct Chosen {
    pub choice: Choice,
    inner: Box<dyn Built>,
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for Chosen {
    fn bindings(&self) -> Vec<Bound<'_>> {
        self.inner.bindings()
    }
    fn push(&self) -> Vec<u8> {
        self.inner.push()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        self.inner.stats()
    }
    fn octants(&self) -> crate::desc::Octants {
        self.inner.octants()
    }
    fn marched_as(&self) -> Option<MarchedAs> {
        Some(MarchedAs {
            accel: self.choice.accel,
            label: self.choice.describe(),
            reason: self.choice.reason(),
            kind: MarchedKind::Choice,
        })
    }
}

/// `--accel auto`.
pub struct AutoMethod;

/// `--accel auto`, as registered.
pub const AUTO: Accel = Accel(&AutoMethod);

const TRIAL: Param = Param::choice(
    "trial",
    &["near", "always", "off"],
    "near",
    "auto: time the candidates on the frame's probe tiles when their predictions are close (near), always, or never (off)",
);

const TREE_PARAM: Param = Param::choice(
    "tree",
    &["auto", "on", "off"],
    "auto",
    "auto: also price a collapsed k-d tree built on the device (auto: on devices that are not CPUs, where it leads on sparse data; its build costs a CPU device more than it gains)",
);

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for AutoMethod {
    fn name(&self) -> &'static str {
        "auto"
    }
    fn description(&self) -> &'static str {
        "the fastest exact structure for this volume, TF and frame: naive, distance maps, the grid or (on GPUs) a k-d tree, priced by the device's measured kernel costs"
    }
    fn params(&self) -> &'static [Param] {
        &[TRIAL, TREE_PARAM]
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::None)
    }
    /// The ranges of every candidate the device holds for this volume.
    fn range_kinds(&self, p: &Params, volume: &GpuVolume, info: &DeviceInfo) -> Result<Vec<RangeKind>> {
        let tree = choose::prices_tree(info, p.choice("tree")?);
        let (candidates, _) = choose::candidates(info, volume.dims, &crate::desc::Mode::Composite, tree)?;
        choose::range_kinds(&candidates)
    }
    /// The naive kernel; frames use the chosen structure's
    /// (`Structure::marched_as`).
    fn march(&self) -> March {
        NAIVE.method().march()
    }
    /// auto builds its candidates through the builder, each classified for
    /// the mode: it reads the frame's own transfer function.
    fn classifies(&self) -> bool {
        false
    }
    /// Host-driven: it reads counts back and may time candidates.
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
        let views = match input.frames.is_empty() {
            true => vec![FrameDesc::builder(DEFAULT_FRAME, DEFAULT_FRAME)
                .mode(input.mode)
                .build()?],
            false => choose::priced_views(input.frames),
        };
        let tree = choose::prices_tree(builder.context().info(), p.choice("tree")?);
        let (choice, inner, timings) = choose(builder, input, ranges, &views, p.choice("trial")?, tree)?;
        Ok((Box::new(Chosen { choice, inner }), timings))
    }
}

/// auto's choice, where `s` is auto's build.
pub fn choice_of(s: &Structure) -> Option<&Choice> {
    s.built_as::<Chosen>().map(|c| &c.choice)
}

/// One probe of `tiles` tiles per view (every tile at `u32::MAX`). Not
/// fewer per view: the probe's blocks of tiles lie on a grid from the
/// frame's corner, and a sparser grid left ch2's few blocks mostly on its
/// background, where naive marching looked fastest.
fn probes_of<'a>(
    builder: &Builder,
    input: &BuildInput<'a>,
    views: &[FrameDesc],
    tiles: u32,
) -> Result<Vec<FrameProbe<'a>>> {
    views
        .iter()
        .map(|v| FrameProbe::new(builder, input.gpu_volume, input.tf, v, tiles))
        .collect()
}

/// `items` without those whose `cut` is true (the two run in step).
fn without_cut<T>(items: Vec<T>, cut: &[bool]) -> Vec<T> {
    items
        .into_iter()
        .zip(cut)
        .filter(|(_, &c)| !c)
        .map(|(x, _)| x)
        .collect()
}

/// Builds, counts and prices the candidates; returns the choice, the
/// chosen structure's built data and the phases (each candidate's build,
/// "count", "calibrate" when constants were measured, "trial" when timed).
fn choose(
    builder: &Builder,
    input: &BuildInput,
    ranges: &Ranges,
    views: &[FrameDesc],
    trial: &str,
    tree: bool,
) -> Result<(Choice, Box<dyn Built>, Timings)> {
    let ctx = builder.context();
    let info = ctx.info();
    // Every frame is refused past the device's loop cap: no candidate's
    // build or counting frame is worth running then.
    for view in views {
        view.check_loop_passes(info, input.volume.dims)?;
    }
    let (all, mut notes) = choose::candidates(info, input.volume.dims, &input.mode, tree)?;
    let mut timings = Timings::default();
    let mut candidates = Vec::new();
    let mut built: Vec<Structure> = Vec::new();
    for c in all {
        if !ranges.has(c.ranges()?) {
            notes.push(format!("{}: its ranges were not computed for this volume", c.label));
            continue;
        }
        let (s, t) = match builder.build(c.accel, input, ranges, &c.params) {
            Ok(built) => built,
            // The tree's buffers are sized by its build: a device too small
            // for them leaves it out, never fails auto.
            Err(e) if c.is_tree() && e.is_device_too_small() => {
                notes.push(format!("no {}: {e}", c.label));
                continue;
            }
            Err(e) => return Err(e),
        };
        timings.push(format!("build {}", c.label), t.total());
        candidates.push(c);
        built.push(s);
    }
    let mut priced: Vec<Priced> = Vec::new();
    let mut model = Vec::new();
    let mut whole_frames = false;
    let mut for_tree = false;
    if built.len() > 1 {
        let start = Instant::now();
        let probes = probes_of(builder, input, views, COUNT_TILES)?;
        // Naive's counts come with the other candidates' (their counting
        // frames derive them): naive's own march is the dearest to count.
        let naive = |s: &Structure| s.marched_as().is_naive();
        let others = built.iter().any(|s| !naive(s));
        let counted: Vec<&Structure> = built.iter().filter(|s| !(others && naive(s))).collect();
        probes[0].prepare(&counted, true)?;
        // Per candidate, per view.
        let mut counts: Vec<Vec<Option<Counts>>> = vec![vec![None; probes.len()]; built.len()];
        let mut derived: Vec<Option<Counts>> = vec![None; probes.len()];
        let mut cut = vec![false; built.len()];
        'candidates: for (i, s) in built.iter().enumerate().filter(|(_, s)| !naive(s)) {
            for (v, probe) in probes.iter().enumerate() {
                match probe.count_both(s) {
                    Ok((own, from)) => {
                        counts[i][v] = Some(own);
                        derived[v] = derived[v].or(from);
                    }
                    // A device's loop cap cut its march on the probed tiles:
                    // its frame would be refused, so it is no candidate.
                    Err(Error::LoopCap { groups, .. }) => {
                        cut[i] = true;
                        notes.push(format!(
                            "{}: its counting frame ran into the device's loop cap in {groups} SIMD group(s), so it is left out",
                            candidates[i].label
                        ));
                        continue 'candidates;
                    }
                    Err(e) => return Err(e),
                }
            }
        }
        candidates = without_cut(std::mem::take(&mut candidates), &cut);
        built = without_cut(std::mem::take(&mut built), &cut);
        let counts = without_cut(counts, &cut);
        let counts = built
            .iter()
            .zip(counts)
            .map(|(s, per_view)| {
                let per_view = per_view.into_iter().zip(&derived).zip(&probes);
                per_view
                    .map(|((c, d), probe)| match (c, d) {
                        (Some(c), _) => Ok(c),
                        (None, Some(n)) => Ok(*n),
                        (None, None) => probe.count(s),
                    })
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?;
        timings.push("count", start.elapsed().as_secs_f64() * 1e3);
        let table = builder.shared::<CostTable>()?;
        let frame = &views[0];
        let constants = frame.kernel_constants(input.gpu_volume);
        let start = Instant::now();
        let mut calibrated = false;
        for ((c, s), counts) in candidates.iter().zip(&built).zip(&counts) {
            let key = CostKey::new(s.march(), constants);
            let (cost, source) = match table.get(info, &key) {
                Some(found) => found,
                None => {
                    calibrated = true;
                    let cost = calibrate::calibrate(builder, s.marched_as(), &c.params, frame, input.gpu_volume)?;
                    notes.extend(table.put(info, &key, cost));
                    (cost, Source::Measured)
                }
            };
            let source = source.to_string();
            if !model.contains(&source) {
                model.push(source);
            }
            let predicted = counts
                .iter()
                .zip(&probes)
                .map(|(c, probe)| cost.predict(c.scaled(probe.scale())))
                .sum::<f64>();
            priced.push(Priced {
                label: c.label.clone(),
                counts: counts.iter().fold(Counts::default(), |a, c| a.plus(c)),
                predicted: predicted / probes.len() as f64,
                trial: None,
            });
        }
        if calibrated {
            timings.push("calibrate", start.elapsed().as_secs_f64() * 1e3);
        }
        // Each probe holds two frames' worth of output: freed before the
        // trial's are made.
        drop(probes);
        let close = match trial {
            "off" => Vec::new(),
            t => choose::to_time(&priced, t == "always"),
        };
        let tree = candidates.iter().position(|c| c.is_tree());
        let timed = match trial {
            "off" => Vec::new(),
            _ => choose::with_tree(close.clone(), &priced, tree),
        };
        for_tree = close.is_empty() && !timed.is_empty();
        if !timed.is_empty() {
            let start = Instant::now();
            let tiles = choose::trial_tiles(&priced, &timed);
            let probes = probes_of(builder, input, views, tiles)?;
            // Small frames are whole at any wish.
            whole_frames = probes.iter().all(FrameProbe::whole_frame);
            let pairs: Vec<(&FrameProbe, &Structure)> = timed
                .iter()
                .flat_map(|&i| probes.iter().map(move |p| (p, i)))
                .map(|(p, i)| (p, &built[i]))
                .collect();
            probes[0].prepare(&timed.iter().map(|&i| &built[i]).collect::<Vec<_>>(), false)?;
            let times = time_interleaved(ctx, &pairs, TRIAL_ROUNDS, Statistic::Least)?;
            for (&i, t) in timed.iter().zip(times.chunks(probes.len())) {
                priced[i].trial = Some(t.iter().sum());
            }
            timings.push("trial", start.elapsed().as_secs_f64() * 1e3);
        }
    } else {
        priced.push(Priced {
            label: candidates[0].label.clone(),
            counts: Default::default(),
            predicted: 0.0,
            trial: None,
        });
        model.push("not needed: naive is the only candidate".into());
    }
    let timed = priced.iter().any(|p| p.trial.is_some());
    let pick = choose::pick(&priced);
    let structure = built.swap_remove(pick);
    let share = keep::share_of(&structure, &mut timings)?;
    let accel = structure.marched_as();
    let label = match accel == NAIVE {
        true => NAIVE.name().to_string(),
        false => candidates[pick].label.clone(),
    };
    let choice = Choice {
        accel,
        label,
        priced,
        timed,
        timed_for_tree: for_tree,
        timed_whole_frames: whole_frames,
        views: views.len(),
        model,
        notes,
        candidate: candidates.swap_remove(pick),
        share,
        mode: input.mode,
        tf: input.tf.spec.clone(),
        kept: 0,
        share_now: share,
    };
    Ok((choice, structure.built, timings))
}

impl Builder {
    /// Keeps auto's kernel constants in files under `folder` too (one per
    /// device, driver and kernel build), read back by later runs; None:
    /// in memory only (the default).
    pub fn use_cost_cache(&self, folder: Option<std::path::PathBuf>) -> Result<()> {
        self.shared::<CostTable>()?.set_folder(folder);
        Ok(())
    }

    /// Measures auto's kernel constants again, whatever a cache holds (and
    /// rewrites it).
    pub fn recalibrate(&self) -> Result<()> {
        self.shared::<CostTable>()?.set_recalibrate(true);
        Ok(())
    }

    /// Prices every kernel with `cost` instead of measuring (tests, hosts
    /// that measured their own); None: measure again.
    pub fn set_kernel_costs(&self, cost: Option<KernelCost>) -> Result<()> {
        self.shared::<CostTable>()?.set_given(cost);
        Ok(())
    }
}

impl super::builder::PerContext for CostTable {
    fn new(_: &crate::gpu::Context) -> Result<Self> {
        Ok(CostTable::default())
    }
}
