//! The benchmark runner. Per data set: every structure is built and rendered
//! until its times are stable (a cold shader cache compiles on first use),
//! then builds and frames are timed round-robin across the structures
//! (naive, A, B, ..., naive, A, B, ...) so that machine noise falls on all
//! alike; each record keeps min, median and max, its speed-up over naive
//! from the same rounds, its noise spread, and its image error against
//! naive. Then the speed-against-error sweep of sample filters, step sizes
//! and early-termination thresholds, against a manually filtered reference.

use super::config::{BenchConfig, ErrorConfig, StructureSpec, UNSTABLE_SPREAD};
use super::dataset::load;
use super::files::frame_file;
use super::frame_timer::FrameTimer;
use super::progress::Progress;
use super::record::{ErrorPoint, FrameTimes, ImageError, Record, Setup, Warmup};
use super::schedule::{schedule, spread, warm_up};
use super::series::{StepBench, StepRecord};
use crate::accel::{Accel, BuildInput, Builder, CostModel, MarchedKind, Params, Structure};
use crate::error::{Error, Result};
use crate::frame::{diff, Frame};
use crate::gpu::timings::{median, Timings};
use crate::gpu::Context;
use crate::render::metadata::{describe, Source};
use crate::render::{Filter, FrameBuilder, FrameDesc, Octants, Projection, Renderer, Scene};
use crate::tf::GpuTransferFunction;
use crate::volume::{BrickGrid, GpuVolume, Series, BRICK};
use std::collections::BTreeMap;

/// What a run produced.
pub struct BenchOutput {
    pub records: Vec<Record>,
    pub errors: Vec<ErrorPoint>,
    /// Frame 0 of each run, when asked for, with its file under the
    /// output folder (`frame_file`).
    pub frames: Vec<(String, Frame)>,
    pub notes: Vec<String>,
    /// New-step times of the data sets with a `time` range.
    pub steps: Vec<StepRecord>,
}

/// How `run` reports and what it keeps.
pub struct RunOptions {
    pub quiet: bool,
    pub keep_frames: bool,
    /// Where auto keeps the device's kernel constants (None: in memory).
    pub cost_cache: Option<std::path::PathBuf>,
    /// auto measures its kernel constants again, whatever the cache holds.
    pub recalibrate: bool,
}

/// View `view` of `views` of the orbit the benchmark turns through, in
/// the data set's look (`base`).
fn orbit(
    config: &BenchConfig,
    base: FrameBuilder,
    view: u32,
    views: u32,
    step: f32,
    ert: Option<f32>,
    filter: Filter,
) -> Result<FrameDesc> {
    base.size(config.size[0], config.size[1])
        .orbit(
            360.0 * view as f64 / views as f64,
            config.elevation,
            Projection::Orthographic,
        )
        .step(step)
        .ert(ert)
        .filter(filter)
        .build()
}

fn params_of(s: &StructureSpec) -> BTreeMap<String, String> {
    s.params
        .describe()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

/// The speed-against-error sweep of one data set: what it sweeps.
struct Sweep<'a> {
    config: &'a BenchConfig,
    e: &'a ErrorConfig,
    setup: &'a Setup,
    /// The data set's label.
    spec: &'a str,
    /// Its look (the reference drops jitter).
    base: FrameBuilder,
    /// The structure the sweep is timed with, on the uploaded volume.
    scene: Scene<'a>,
    filters: &'a [Filter],
    jitters: &'a [bool],
}

/// The speed-against-error sweep of one data set, on its uploaded volume.
fn error_sweep(sweep: &Sweep, frames: &mut FrameTimer, progress: &Progress) -> Result<Vec<ErrorPoint>> {
    let Sweep {
        config,
        e,
        setup,
        spec,
        base,
        scene,
        filters,
        jitters,
    } = *sweep;
    let mut points = Vec::new();
    let mut reference = Vec::new();
    let naive = Structure::naive();
    let reference_scene = Scene {
        structure: &naive,
        ..scene
    };
    for view in 0..e.frames {
        let desc = orbit(
            config,
            base.jitter(false),
            view,
            e.frames,
            e.reference_step,
            None,
            Filter::Manual,
        )?;
        reference.push(
            frames
                .frame(reference_scene, &desc, true)?
                .1
                .ok_or_else(|| missing("reference frame"))?,
        );
        progress.step(1);
    }
    let settings = jitters.iter().flat_map(|&j| {
        filters.iter().flat_map(move |&f| {
            e.steps
                .iter()
                .flat_map(move |&s| e.ert.iter().map(move |&t| (j, f, s, t)))
        })
    });
    for (jitter, filter, step, ert) in settings {
        let ert = (ert > 0.0).then_some(ert);
        let base = base.jitter(jitter);
        // A new step is a new workload: warm up again.
        let first = orbit(config, base, 0, e.frames, step, ert, filter)?;
        warm_up(config.warmup, config.warmup_cap, config.stable, |_| {
            Ok(frames.frame(scene, &first, false)?.0)
        })?;
        let (mut times, mut sq, mut max_abs, mut differing, mut pixels) = (Vec::new(), 0.0, 0.0f64, 0, 0u64);
        for view in 0..e.frames {
            let (ms, f) = frames.frame(scene, &orbit(config, base, view, e.frames, step, ert, filter)?, true)?;
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
            accel: scene.structure.accel.name().into(),
            sweep_step: step,
            ert,
            filter: filter.to_string(),
            jitter,
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

/// The structures in timing order: naive first (added when the config has
/// none), the rest in config order.
fn timing_order(structures: Vec<StructureSpec>) -> Vec<StructureSpec> {
    let is_naive = |s: &StructureSpec| s.accel == Accel::naive();
    let mut out: Vec<StructureSpec> = structures.iter().filter(|s| is_naive(s)).take(1).cloned().collect();
    if out.is_empty() {
        out.push(StructureSpec {
            label: "naive".into(),
            accel: Accel::naive(),
            params: Params::default(),
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

/// Runs a bench config on `ctx`'s device: every structure on every data
/// set, timed interleaved, each frame diffed against naive's.
pub fn run(ctx: &Context, config: &BenchConfig, options: &RunOptions) -> Result<BenchOutput> {
    let structures = timing_order(
        config
            .structures
            .iter()
            .map(|s| s.resolve())
            .collect::<Result<Vec<_>>>()?,
    );
    let builder = Builder::new(ctx)?;
    builder.use_cost_cache(options.cost_cache.clone())?;
    if options.recalibrate {
        builder.recalibrate()?;
    }
    let renderer = Renderer::new(builder.context())?;
    let info = ctx.info();
    let mut setup = Setup {
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
        // Set once a build has measured it (cost-driven leaves).
        cost_model: None,
    };
    let least = config.warmup.max(2) as u64;
    let per_structure = 2 * least + config.builds as u64 + config.frames as u64 * config.rounds as u64;
    let sweep = config.error.as_ref().map_or(0, |e| {
        let n = e.datasets.as_ref().map_or(config.datasets.len(), |d| d.len()) as u64;
        let filters = e.filters.len().max(1);
        n * e.frames as u64 * (1 + (filters * e.steps.len() * e.ert.len()) as u64)
    });
    let timed_filter = config.timed_filter()?;
    let new_steps: u64 = config.datasets.iter().map(|d| d.new_steps()).sum();
    let progress = Progress::new(
        (config.datasets.len() as u64 * per_structure + new_steps) * structures.len() as u64 + sweep,
        options.quiet,
    );
    let mut out = BenchOutput {
        records: Vec::new(),
        errors: Vec::new(),
        frames: Vec::new(),
        notes: Vec::new(),
        steps: Vec::new(),
    };
    let mut frames = FrameTimer::new(ctx, &renderer, config.size[0], config.size[1])?;

    for ds in &config.datasets {
        progress.at(&format!("{} loading", ds.volume));
        let series = ds.options().and_then(|o| Series::open(&ds.volume, &o));
        let loaded = match series.and_then(|s| {
            load(
                (ds.storage()?, ctx.info()),
                &s,
                ds.time,
                ds.label(config)?,
                ds.tf.as_deref(),
            )
            .map(|l| (s, l))
        }) {
            Ok(l) => l,
            Err(Error::Io { path, .. }) if ds.optional => {
                let note = format!("skipped optional data set {} (missing {})", ds.volume, path.display());
                progress.note(&note);
                out.notes.push(note);
                progress.step(structures.len() as u64 * (per_structure + ds.new_steps()));
                continue;
            }
            Err(e) => return Err(e),
        };
        let (series, loaded) = loaded;
        let (v, tf) = (&loaded.volume, &loaded.tf);
        let mut gv = GpuVolume::upload_as(ctx, v, ds.storage()?)?;
        if let Some(pool) = gv.pool() {
            let note = format!("{}: {pool}", ds.volume);
            progress.note(&note);
            out.notes.push(note);
        }
        let lut = tf.upload(ctx)?;
        let base = ds.look(config).apply(FrameDesc::builder(1, 1))?;
        gv.prepare(v, base.build()?.lighting().is_some(), timed_filter)?;
        let filter = timed_filter.unwrap_or_else(|| gv.default_filter());
        let ert = ds.ert.or(config.ert);
        setup.timed_ert = ert;
        let settings = |view: u32| orbit(config, base, view, config.frames, config.step, ert, filter);
        let views = (0..config.frames).map(settings).collect::<Result<Vec<FrameDesc>>>()?;
        let first = settings(0)?;
        let mode = *first.mode();

        // auto prices its candidates on up to four of the views.
        let scene = BuildInput {
            volume: v,
            gpu_volume: &gv,
            tf,
            gpu_tf: &lut,
            mode,
            frames: &views,
            // Every view of the orbit marches the structures built once.
            octants: FrameDesc::octants_of(&views, v.dims, v.spacing)?,
        };
        // lacuna info's occupancy figures.
        let n = v.data.len();
        let visible = (0..n)
            .filter(|&i| tf.lookup(v.normalize(v.data.texel(i)))[3] > 0.0)
            .count();
        let grid = BrickGrid::new(v, BRICK, crate::volume::APRON);
        let active = grid.active(tf).iter().filter(|a| **a).count();
        let (visible_percent, active_brick_percent) = (
            100.0 * visible as f64 / n as f64,
            100.0 * active as f64 / grid.len() as f64,
        );
        // Per-volume ranges, each kind the structures read once.
        let reads: Vec<(Accel, &Params)> = structures.iter().map(|s| (s.accel, &s.params)).collect();
        let (ranges, _) = builder.ranges_for(&reads, &gv)?;

        // Builds: warm up each structure, then time them round-robin.
        let mut runs: Vec<Run> = Vec::with_capacity(structures.len());
        for s in &structures {
            progress.at(&format!("{} - {} warm-up", loaded.spec, s.label));
            let mut structure = Structure::naive();
            let warmed = warm_up(config.warmup, config.warmup_cap, config.stable, |i| {
                let (st, t) = builder.build(s.accel, &scene, &ranges, &s.params)?;
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
                let (st, t) = builder.build(s.accel, &scene, &ranges, &s.params)?;
                run.structure = st;
                run.builds.push(t);
                progress.step(1);
            }
        }

        // Frames: warm up each structure's pipelines, then time every view
        // round-robin.
        for (s, run) in structures.iter().zip(&mut runs) {
            progress.at(&format!("{} - {} warm-up frames", loaded.spec, s.label));
            let scene = scene_of(&run.structure, &gv, &lut);
            let first = settings(0)?;
            let warmed = warm_up(config.warmup, config.warmup_cap, config.stable, |i| {
                let (ms, _) = frames.frame(scene, &first, false)?;
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
            let (ms, frame) = frames.frame(scene_of(&run.structure, &gv, &lut), &settings(slot.view)?, first)?;
            run.times[slot.view as usize].push(ms);
            if let Some(frame) = frame {
                let reference = naive0.get_or_insert_with(|| frame.clone());
                run.error = Some(ImageError::from(diff(reference, &frame)?));
                run.first = options.keep_frames.then_some(frame);
            }
            progress.step(1);
        }

        setup.cost_model = builder.made::<CostModel>().map(|m| *m);
        let naive = runs.first().ok_or_else(|| missing("naive frames"))?;
        for (s, run) in structures.iter().zip(&runs) {
            let ranges_ms = s
                .accel
                .method()
                .range_kinds(&s.params, &gv, info)?
                .into_iter()
                .map(|k| ranges.ms(k))
                .sum::<Result<f64>>()?;
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
            // A structure that found nothing to skip, or does not skip in
            // the frames' mode, says so; auto says what it chose and why.
            if let Some(m) = run.structure.marched_as_reason() {
                let note = match m.kind {
                    MarchedKind::NothingToSkip | MarchedKind::ModeFallback => {
                        format!("marched with the naive kernel ({})", m.reason)
                    }
                    MarchedKind::Choice => format!("chose {} ({})", m.label, m.reason),
                };
                out.notes.push(format!("{} - {}: {note}", loaded.spec, s.label));
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
                chosen: run
                    .structure
                    .marched_as_reason()
                    .filter(|m| m.kind == MarchedKind::Choice)
                    .map(|m| m.label),
            });
            if let Some(first) = &run.first {
                // As `render` describes its frame: view 0, its median march.
                let (mut kept, scene) = (first.clone(), scene_of(&run.structure, &gv, &lut));
                let march = run.times.first().map(|t| median(t.clone()));
                let source = Source {
                    volume: v,
                    time: ds.time.map(|[first, _]| first),
                    tf,
                };
                describe(&mut kept, source, scene, &views[0], ctx.info(), march)?;
                out.frames.push((frame_file(&loaded.spec, &s.label), kept));
            }
        }
        // New time steps: the first exact frame of each, per structure.
        if let Some(range) = ds.time {
            let first = settings(0)?;
            let bench = StepBench {
                ctx,
                builder: &builder,
                structures: &structures,
                tf,
                lut: &lut,
                desc: &first,
                filter: timed_filter,
                storage: ds.storage()?,
            };
            let step_frame = |scene: Scene, desc: &FrameDesc, read: bool| frames.frame(scene, desc, read);
            let steps = bench.run(&loaded.spec, &series, range, step_frame, &progress)?;
            // An inexact structure's steps (the paper's classification).
            for r in steps.iter().filter(|r| r.differing_pixels > 0) {
                let note = format!(
                    "{} - {}: {} pixels of its new-step frames differ from naive's",
                    r.dataset, r.structure, r.differing_pixels
                );
                progress.note(&note);
                out.notes.push(note);
            }
            out.steps.extend(steps);
        }
        // Speed against error, on the volume and ranges already uploaded.
        if let Some(e) = config
            .error
            .as_ref()
            .filter(|e| e.datasets.as_ref().is_none_or(|d| d.contains(&loaded.spec)))
        {
            progress.at(&format!("{} - speed against error", loaded.spec));
            let accel: Accel = e.accel.parse()?;
            let params = accel.defaults();
            let (r, _) = builder.ranges_for(&[(accel, &params)], &gv)?;
            // The sweep's views are its own orbit: build for every direction.
            let every = BuildInput {
                octants: Octants::ALL,
                ..scene
            };
            let (structure, _) = builder.build(accel, &every, &r, &params)?;
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
            let jitters = match e.jitter.is_empty() {
                true => vec![settings(0)?.jitter()],
                false => e.jitter.clone(),
            };
            let sweep = Sweep {
                config,
                e,
                setup: &setup,
                spec: &loaded.spec,
                base,
                scene: scene_of(&structure, &gv, &lut),
                filters: &filters,
                jitters: &jitters,
            };
            out.errors.extend(error_sweep(&sweep, &mut frames, &progress)?);
        }
    }

    progress.finish();
    Ok(out)
}

fn scene_of<'a>(structure: &'a Structure, volume: &'a GpuVolume, tf: &'a GpuTransferFunction) -> Scene<'a> {
    Scene { structure, volume, tf }
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
