//! The benchmark runner. Per data set: every structure is built and rendered
//! until its times are stable (a cold shader cache compiles on first use),
//! then builds and frames are timed round-robin across the structures
//! (naive, A, B, ..., naive, A, B, ...) so that machine noise falls on all
//! alike; each record keeps min, median and max, its speed-up over naive
//! from the same rounds, its noise spread, and its image error against
//! naive. Then the speed-against-error sweep of sample filters, step sizes
//! and early-termination thresholds, against a manually filtered reference.

use super::config::{BenchConfig, ErrorConfig, StructureSpec, UNSTABLE_SPREAD};
use super::progress::Progress;
use super::record::{ErrorPoint, FrameTimes, ImageError, Record, Setup, Warmup};
use crate::accel::{Accel, BuildInput, BuildOptions, Builder, Ranges, Structure};
use crate::error::{Error, Result};
use crate::frame::{diff, Frame};
use crate::gpu::timings::{median, Timings};
use crate::gpu::{Context, Timer};
use crate::render::{Camera, Filter, Projection, RenderSettings, RenderTarget, Renderer};
use crate::tf::{GpuTransferFunction, TransferFunction};
use crate::volume::{BrickGrid, GpuVolume, LoadOptions, BRICK};
use crate::Volume;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

/// What a run produced.
pub struct BenchOutput {
    pub records: Vec<Record>,
    pub errors: Vec<ErrorPoint>,
    /// Frame 0 of each run, when asked for.
    pub frames: Vec<(String, Frame)>,
    pub notes: Vec<String>,
}

pub struct RunOptions {
    pub quiet: bool,
    pub keep_frames: bool,
}

/// Renders frames into one target, timing the march pass of each.
struct FrameTimer<'a> {
    ctx: &'a Context,
    renderer: &'a Renderer,
    target: RenderTarget,
    timer: Timer,
}

impl<'a> FrameTimer<'a> {
    fn new(ctx: &'a Context, renderer: &'a Renderer, width: u32, height: u32) -> Result<Self> {
        Ok(FrameTimer {
            ctx,
            renderer,
            target: RenderTarget::new(ctx, width, height)?,
            timer: Timer::new(ctx, 2)?,
        })
    }

    /// One frame: GPU ms of the march pass, and the frame when `read`.
    fn frame(
        &mut self,
        s: &Structure,
        v: &GpuVolume,
        tf: &GpuTransferFunction,
        settings: &RenderSettings,
        read: bool,
    ) -> Result<(f64, Option<Frame>)> {
        let (renderer, target, timer) = (self.renderer, &self.target, &mut self.timer);
        self.ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            renderer.record(cmd, Some(timer), s, target, v, tf, settings)?;
            if read {
                renderer.record_readback(cmd, target)?;
            }
            Ok(())
        })?;
        let ms = self.timer.results()?.phase("march")?;
        let frame = if read { Some(self.target.read()?) } else { None };
        Ok((ms, frame))
    }
}

fn orbit(config: &BenchConfig, view: u32, views: u32, step: f32, ert: Option<f32>, filter: Filter) -> RenderSettings {
    RenderSettings {
        width: config.size[0],
        height: config.size[1],
        camera: Camera {
            azimuth_deg: 360.0 * view as f64 / views as f64,
            elevation_deg: config.elevation,
            projection: Projection::Orthographic,
        },
        step,
        ert,
        filter,
    }
}

fn params_of(s: &StructureSpec) -> BTreeMap<String, String> {
    s.accel
        .method()
        .params(&s.options)
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

struct Loaded {
    spec: String,
    volume: Volume,
    tf: TransferFunction,
}

fn load(ctx: &Context, spec: &str, tf: Option<&str>) -> Result<Loaded> {
    let volume = Volume::load_within(spec, &LoadOptions::default(), Some(ctx.info()))?;
    let tf_spec = tf
        .map(str::to_string)
        .or_else(|| volume.default_tf.clone())
        .unwrap_or_else(|| "ramp:0:1".into());
    Ok(Loaded {
        spec: spec.to_string(),
        tf: TransferFunction::parse(&tf_spec)?,
        volume,
    })
}

/// The speed-against-error sweep of one data set, on its uploaded volume.
#[allow(clippy::too_many_arguments)]
fn error_sweep(
    config: &BenchConfig,
    e: &ErrorConfig,
    setup: &Setup,
    spec: &str,
    structure: &Structure,
    gv: &GpuVolume,
    lut: &GpuTransferFunction,
    filters: &[Filter],
    frames: &mut FrameTimer,
    progress: &Progress,
) -> Result<Vec<ErrorPoint>> {
    let mut points = Vec::new();
    let mut reference = Vec::new();
    for view in 0..e.frames {
        let settings = orbit(config, view, e.frames, e.reference_step, None, Filter::Manual);
        reference.push(
            frames
                .frame(&Structure::naive(), gv, lut, &settings, true)?
                .1
                .ok_or_else(|| missing("reference frame"))?,
        );
        progress.step(1);
    }
    for (&filter, &step, &ert) in filters
        .iter()
        .flat_map(|f| e.steps.iter().flat_map(move |s| e.ert.iter().map(move |t| (f, s, t))))
    {
        let ert = (ert > 0.0).then_some(ert);
        // A new step is a new workload: warm up again.
        let first = orbit(config, 0, e.frames, step, ert, filter);
        warm_up(config.warmup, config.warmup_cap, config.stable, |_| {
            Ok(frames.frame(structure, gv, lut, &first, false)?.0)
        })?;
        let (mut times, mut sq, mut max_abs, mut differing, mut pixels) = (Vec::new(), 0.0, 0.0f64, 0, 0u64);
        for view in 0..e.frames {
            let (ms, f) = frames.frame(
                structure,
                gv,
                lut,
                &orbit(config, view, e.frames, step, ert, filter),
                true,
            )?;
            let d = diff(&reference[view as usize], &f.ok_or_else(|| missing("sweep frame"))?)?;
            times.push(ms);
            sq += d.rmse * d.rmse * d.pixels as f64;
            pixels += d.pixels;
            max_abs = max_abs.max(d.max_abs);
            differing += d.differing;
            progress.step(1);
        }
        let rmse = (sq / pixels.max(1) as f64).sqrt();
        let psnr = (rmse > 0.0).then(|| 20.0 * (1.0 / rmse).log10());
        points.push(ErrorPoint {
            setup: setup.clone(),
            dataset: spec.to_string(),
            accel: structure.accel().name().into(),
            sweep_step: step,
            ert,
            filter: filter.to_string(),
            frame: FrameTimes::of(times),
            reference_step: e.reference_step,
            error: ImageError {
                rmse,
                psnr,
                max_abs,
                differing,
            },
        });
    }
    Ok(points)
}

/// One timed frame of the interleaved schedule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    pub view: u32,
    pub round: u32,
    /// Index into the structures, in timing order (naive first).
    pub structure: usize,
}

/// The order frames are timed in: for each view, `rounds` rounds, and in
/// each round every structure once, in order. A structure's frames of one
/// view are thus spread over the same stretch of time as every other's.
pub fn schedule(views: u32, rounds: u32, structures: usize) -> impl Iterator<Item = Slot> {
    (0..views).flat_map(move |view| {
        (0..rounds).flat_map(move |round| (0..structures).map(move |structure| Slot { view, round, structure }))
    })
}

/// How a warm-up ended: runs made, and whether it stopped at the cap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WarmedUp {
    pub runs: u32,
    pub capped: bool,
}

/// Runs `once` (which returns a time) at least `least` times and until two
/// consecutive times agree within the fraction `stable`, or `cap` times.
/// One run is never enough: on lavapipe the frames after the first are
/// still slow with a cold shader cache.
pub fn warm_up(least: u32, cap: u32, stable: f64, mut once: impl FnMut(u32) -> Result<f64>) -> Result<WarmedUp> {
    let least = least.max(2);
    let mut previous: Option<f64> = None;
    for i in 0..cap.max(least) {
        let t = once(i)?;
        if i + 1 >= least {
            if let Some(p) = previous {
                if (t - p).abs() <= stable * t.min(p) {
                    return Ok(WarmedUp {
                        runs: i + 1,
                        capped: false,
                    });
                }
            }
        }
        previous = Some(t);
    }
    Ok(WarmedUp {
        runs: cap.max(least),
        capped: true,
    })
}

/// max/min of positive times; 1 when there is nothing to compare.
fn spread(ms: &[f64]) -> f64 {
    let min = ms.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = ms.iter().cloned().fold(0.0, f64::max);
    if min > 0.0 && min.is_finite() {
        max / min
    } else {
        1.0
    }
}

/// The structures in timing order: naive first (added when the config has
/// none), the rest in config order.
fn timing_order(structures: Vec<StructureSpec>) -> Vec<StructureSpec> {
    let is_naive = |s: &StructureSpec| s.accel == Accel::naive();
    let mut out: Vec<StructureSpec> = structures.iter().filter(|s| is_naive(s)).take(1).cloned().collect();
    if out.is_empty() {
        out.push(StructureSpec {
            label: "naive".into(),
            accel: Accel::naive(),
            options: BuildOptions::default(),
        });
    }
    let first_naive = structures.iter().position(is_naive);
    out.extend(
        structures
            .into_iter()
            .enumerate()
            .filter(|(i, _)| Some(*i) != first_naive)
            .map(|(_, s)| s),
    );
    out
}

/// Per structure of one data set, while it is measured.
struct Run {
    structure: Structure,
    builds: Vec<Timings>,
    warmup: Warmup,
    /// Frame times by view, then round.
    times: Vec<Vec<f64>>,
    /// Frame 0 against naive's frame 0.
    error: Option<ImageError>,
    /// Frame 0, kept when asked for.
    first: Option<Frame>,
}

pub fn run(ctx: &Context, config: &BenchConfig, options: &RunOptions) -> Result<BenchOutput> {
    let structures = timing_order(
        config
            .structures
            .iter()
            .map(|s| s.resolve())
            .collect::<Result<Vec<_>>>()?,
    );
    let builder = Builder::new(ctx)?;
    let renderer = Renderer::new(ctx)?;
    let info = ctx.info();
    let setup = Setup {
        config: config.name.clone(),
        device: info.name.clone(),
        driver: info.driver.clone(),
        width: config.size[0],
        height: config.size[1],
        frames: config.frames,
        warmup: config.warmup,
        warmup_cap: config.warmup_cap,
        rounds: config.rounds,
        step: config.step,
        timed_ert: config.ert,
        camera: format!(
            "orthographic orbit, elevation {}, {} views",
            config.elevation, config.frames
        ),
        cost_model: structures
            .iter()
            .any(|s| s.options.collapse)
            .then(|| builder.cost_model())
            .transpose()?,
    };
    let least = config.warmup.max(2) as u64;
    let per_structure = 2 * least + config.builds as u64 + config.frames as u64 * config.rounds as u64;
    let sweep = config.error.as_ref().map_or(0, |e| {
        let n = e.datasets.as_ref().map_or(config.datasets.len(), |d| d.len()) as u64;
        let filters = e.filters.len().max(1);
        n * e.frames as u64 * (1 + (filters * e.steps.len() * e.ert.len()) as u64)
    });
    let timed_filter = config.timed_filter()?;
    let progress = Progress::new(
        config.datasets.len() as u64 * structures.len() as u64 * per_structure + sweep,
        options.quiet,
    );
    let mut out = BenchOutput {
        records: Vec::new(),
        errors: Vec::new(),
        frames: Vec::new(),
        notes: Vec::new(),
    };
    let mut frames = FrameTimer::new(ctx, &renderer, config.size[0], config.size[1])?;

    for ds in &config.datasets {
        progress.at(&format!("{} loading", ds.volume));
        let loaded = match load(ctx, &ds.volume, ds.tf.as_deref()) {
            Ok(l) => l,
            Err(Error::Io { path, .. }) if ds.optional => {
                let note = format!("skipped optional data set {} (missing {})", ds.volume, path.display());
                progress.note(&note);
                out.notes.push(note);
                progress.step(structures.len() as u64 * per_structure);
                continue;
            }
            Err(e) => return Err(e),
        };
        let (v, tf) = (&loaded.volume, &loaded.tf);
        let gv = GpuVolume::upload(ctx, v)?;
        let lut = tf.upload(ctx)?;
        let filter = timed_filter.unwrap_or_else(|| gv.default_filter());
        let settings = |view: u32| orbit(config, view, config.frames, config.step, config.ert, filter);
        let scene = BuildInput {
            volume: v,
            gpu_volume: &gv,
            tf,
            gpu_tf: &lut,
        };
        // lacuna info's occupancy figures.
        let n = v.data.len();
        let visible = (0..n)
            .filter(|&i| tf.lookup(v.normalize(v.data.texel(i)))[3] > 0.0)
            .count();
        let grid = BrickGrid::new(v, BRICK, 1);
        let active = grid.active(tf).iter().filter(|a| **a).count();
        let (visible_percent, active_brick_percent) = (
            100.0 * visible as f64 / n as f64,
            100.0 * active as f64 / grid.len() as f64,
        );
        // Per-volume ranges, once per cell size in use, of the kinds the
        // structures with that cell size read.
        let mut ranges: HashMap<u32, (Ranges, Timings)> = HashMap::new();
        for s in &structures {
            if let std::collections::hash_map::Entry::Vacant(e) = ranges.entry(s.options.cell) {
                let accels: Vec<Accel> = structures
                    .iter()
                    .filter(|o| o.options.cell == s.options.cell)
                    .map(|o| o.accel)
                    .collect();
                e.insert(builder.ranges_for(&accels, &gv, s.options.cell)?);
            }
        }

        // Builds: warm up each structure, then time them round-robin.
        let mut runs: Vec<Run> = Vec::with_capacity(structures.len());
        for s in &structures {
            progress.at(&format!("{} - {} warm-up", loaded.spec, s.label));
            let r = &ranges[&s.options.cell].0;
            let mut structure = Structure::naive();
            let warmed = warm_up(config.warmup, config.warmup_cap, config.stable, |i| {
                let (st, t) = builder.build(s.accel, &scene, r, &s.options)?;
                structure = st;
                advance(&progress, i, least);
                Ok(t.total())
            })?;
            runs.push(Run {
                structure,
                builds: Vec::new(),
                warmup: Warmup {
                    builds: warmed.runs,
                    frames: 0,
                    capped: warmed.capped,
                },
                times: vec![Vec::new(); config.frames as usize],
                error: None,
                first: None,
            });
        }
        progress.at(&format!("{} - timed builds", loaded.spec));
        for _ in 0..config.builds {
            for (s, run) in structures.iter().zip(&mut runs) {
                let (st, t) = builder.build(s.accel, &scene, &ranges[&s.options.cell].0, &s.options)?;
                run.structure = st;
                run.builds.push(t);
                progress.step(1);
            }
        }

        // Frames: warm up each structure's pipelines, then time every view
        // round-robin.
        for (s, run) in structures.iter().zip(&mut runs) {
            progress.at(&format!("{} - {} warm-up frames", loaded.spec, s.label));
            let structure = &run.structure;
            let warmed = warm_up(config.warmup, config.warmup_cap, config.stable, |i| {
                let (ms, _) = frames.frame(structure, &gv, &lut, &settings(0), false)?;
                advance(&progress, i, least);
                Ok(ms)
            })?;
            run.warmup.frames = warmed.runs;
            run.warmup.capped |= warmed.capped;
        }
        progress.at(&format!("{} - timed frames", loaded.spec));
        // Naive comes first in every round, so its frame 0 is read back
        // before any other structure's and is the reference for them all.
        let mut naive0: Option<Frame> = None;
        for slot in schedule(config.frames, config.rounds, structures.len()) {
            let first = slot.view == 0 && slot.round == 0;
            let run = &mut runs[slot.structure];
            let (ms, frame) = frames.frame(&run.structure, &gv, &lut, &settings(slot.view), first)?;
            run.times[slot.view as usize].push(ms);
            if let Some(frame) = frame {
                let reference = naive0.get_or_insert_with(|| frame.clone());
                run.error = Some(ImageError::from(diff(reference, &frame)?));
                run.first = options.keep_frames.then_some(frame);
            }
            progress.step(1);
        }

        let naive = runs.first().ok_or_else(|| missing("naive frames"))?;
        for (s, run) in structures.iter().zip(&runs) {
            let r = &ranges[&s.options.cell].0;
            let ranges_ms = r.ms(s.accel.method().ranges())?;
            let totals: Vec<f64> = run.builds.iter().map(Timings::total).collect();
            let build = FrameTimes::of(totals.clone());
            let phases = Timings::median(&run.builds);
            let ratios: Vec<f64> = naive
                .times
                .iter()
                .flatten()
                .zip(run.times.iter().flatten())
                .map(|(n, t)| n / t)
                .collect();
            let frame_spread = run.times.iter().map(|t| spread(t)).fold(1.0, f64::max);
            let build_spread = spread(&totals);
            let unstable = frame_spread > UNSTABLE_SPREAD || build_spread > UNSTABLE_SPREAD;
            let frame = FrameTimes::of(run.times.concat());
            if run.warmup.capped {
                out.notes.push(format!(
                    "{} - {}: warm-up stopped at the cap ({} builds, {} frames) before two consecutive times agreed within {}%",
                    loaded.spec,
                    s.label,
                    run.warmup.builds,
                    run.warmup.frames,
                    config.stable * 100.0
                ));
            }
            if run.structure.marched_naively() {
                out.notes.push(format!(
                    "{} - {}: one leaf covering the volume, marched with the naive kernel",
                    loaded.spec, s.label
                ));
            }
            if unstable {
                out.notes.push(format!(
                    "{} - {}: unstable (frame max/min over rounds {:.2}, build max/min {:.2}, above {UNSTABLE_SPREAD})",
                    loaded.spec, s.label, frame_spread, build_spread
                ));
            }
            let stats = run.structure.stats()?.unwrap_or_default();
            out.records.push(Record {
                setup: setup.clone(),
                dataset: loaded.spec.clone(),
                dims: v.dims,
                tf: tf.spec.clone(),
                visible_percent,
                active_brick_percent,
                structure: s.label.clone(),
                accel: s.accel.name().into(),
                params: params_of(s),
                ranges_ms,
                build_ms: build.median_ms,
                build_min_ms: build.min_ms,
                build_max_ms: build.max_ms,
                build_phases_ms: phases.phases.into_iter().collect(),
                nodes: stats.nodes,
                leaves: stats.leaves,
                tree_height: stats.height,
                bytes: stats.bytes,
                fps: 1000.0 / frame.median_ms,
                frame,
                speedup: median(ratios),
                frame_spread,
                build_spread,
                unstable,
                warmed_up: run.warmup,
                error_vs_naive: run.error.clone().ok_or_else(|| missing("frame 0"))?,
                filter: filter.to_string(),
                chosen: run.structure.choice().map(|c| c.describe()),
            });
            if let Some(first) = &run.first {
                out.frames.push((format!("{}-{}", loaded.spec, s.label), first.clone()));
            }
        }
        // Speed against error, on the volume and ranges already uploaded.
        if let Some(e) = config
            .error
            .as_ref()
            .filter(|e| e.datasets.as_ref().is_none_or(|d| d.contains(&loaded.spec)))
        {
            progress.at(&format!("{} - speed against error", loaded.spec));
            let opts = BuildOptions::default();
            let accel: Accel = e.accel.parse()?;
            let (r, _) = builder.ranges_for(&[accel], &gv, opts.cell)?;
            let (structure, _) = builder.build(accel, &scene, &r, &opts)?;
            let mut filters = e.filters(filter)?;
            filters.retain(|&f| {
                let usable = gv.sampler_for(f).is_ok();
                if !usable {
                    let note = format!(
                        "{}: error sweep skips filter {f} (the volume's format does not filter linearly here)",
                        loaded.spec
                    );
                    progress.note(&note);
                    out.notes.push(note);
                }
                usable
            });
            out.errors.extend(error_sweep(
                config,
                e,
                &setup,
                &loaded.spec,
                &structure,
                &gv,
                &lut,
                &filters,
                &mut frames,
                &progress,
            )?);
        }
    }

    progress.finish();
    Ok(out)
}

/// Counts warm-up run `i` on the progress bar, growing it past the least.
fn advance(progress: &Progress, i: u32, least: u64) {
    if i as u64 >= least {
        progress.grow(1);
    }
    progress.step(1);
}

fn missing(what: &str) -> Error {
    Error::invalid("benchmark", what, "was not read back")
}

/// A file name for a run label.
pub fn slug(s: &str) -> PathBuf {
    PathBuf::from(
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                    c
                } else {
                    '_'
                }
            })
            .collect::<String>(),
    )
}
