//! The benchmark runner: per data set, per structure, the TF-change build
//! (median over timed builds after warm-up) and the frame time of the
//! rotating orthographic camera (median, min, max after warm-up frames), plus
//! each structure's image error against naive marching; then the
//! speed-against-error sweep of step sizes and early-termination thresholds.

use super::config::{BenchConfig, ErrorConfig, StructureSpec};
use super::progress::Progress;
use super::record::{ErrorPoint, FrameTimes, ImageError, Record, Setup};
use crate::accel::{Accel, BuildInput, BuildOptions, Builder, Ranges, Structure};
use crate::error::{Error, Result};
use crate::frame::{diff, Frame};
use crate::gpu::{Context, Timer};
use crate::render::{Camera, Projection, RenderSettings, RenderTarget, Renderer};
use crate::tf::{GpuTransferFunction, TransferFunction};
use crate::timings::Timings;
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
                renderer.record_readback(cmd, target);
            }
            Ok(())
        })?;
        let ms = self.timer.results()?.phase("march")?;
        Ok((ms, read.then(|| self.target.read())))
    }
}

fn orbit(config: &BenchConfig, view: u32, views: u32, step: f32, ert: Option<f32>) -> RenderSettings {
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

fn load(spec: &str, tf: Option<&str>) -> Result<Loaded> {
    let volume = Volume::load(spec, &LoadOptions::default())?;
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
    frames: &mut FrameTimer,
    progress: &Progress,
) -> Result<Vec<ErrorPoint>> {
    let mut points = Vec::new();
    let mut reference = Vec::new();
    for view in 0..e.frames {
        let settings = orbit(config, view, e.frames, e.reference_step, None);
        reference.push(
            frames
                .frame(&Structure::naive(), gv, lut, &settings, true)?
                .1
                .expect("read back"),
        );
        progress.step(1);
    }
    for &step in &e.steps {
        for &ert in &e.ert {
            let ert = (ert > 0.0).then_some(ert);
            // One untimed frame first: a new step is a new workload.
            frames.frame(structure, gv, lut, &orbit(config, 0, e.frames, step, ert), false)?;
            let (mut times, mut sq, mut max_abs, mut differing, mut pixels) = (Vec::new(), 0.0, 0.0f64, 0, 0u64);
            for view in 0..e.frames {
                let (ms, f) = frames.frame(structure, gv, lut, &orbit(config, view, e.frames, step, ert), true)?;
                let d = diff(&reference[view as usize], &f.expect("read back"))?;
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
    }
    Ok(points)
}

pub fn run(ctx: &Context, config: &BenchConfig, options: &RunOptions) -> Result<BenchOutput> {
    let structures: Vec<StructureSpec> = config.structures.iter().map(|s| s.resolve()).collect::<Result<_>>()?;
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
        step: config.step,
        camera: format!(
            "orthographic orbit, elevation {}, {} views",
            config.elevation, config.frames
        ),
    };
    let per_structure = (config.builds + config.warmup + config.frames + config.warmup) as u64;
    let sweep = config.error.as_ref().map_or(0, |e| {
        let n = e.datasets.as_ref().map_or(config.datasets.len(), |d| d.len()) as u64;
        n * e.frames as u64 * (1 + (e.steps.len() * e.ert.len()) as u64)
    });
    let progress = Progress::new(
        config.datasets.len() as u64 * (structures.len() as u64 * per_structure + 1) + sweep,
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
        let loaded = match load(&ds.volume, ds.tf.as_deref()) {
            Ok(l) => l,
            Err(Error::Io { path, .. }) if ds.optional => {
                let note = format!("skipped optional data set {} (missing {})", ds.volume, path.display());
                progress.note(&note);
                out.notes.push(note);
                progress.step(structures.len() as u64 * per_structure + 1);
                continue;
            }
            Err(e) => return Err(e),
        };
        let (v, tf) = (&loaded.volume, &loaded.tf);
        let gv = GpuVolume::upload(ctx, v)?;
        let lut = tf.upload(ctx)?;
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
        let (_, naive0) = frames.frame(
            &Structure::naive(),
            &gv,
            &lut,
            &orbit(config, 0, config.frames, config.step, None),
            true,
        )?;
        let naive0 = naive0.expect("read back");
        progress.step(1);
        for s in &structures {
            progress.at(&format!("{} - {}", loaded.spec, s.label));
            let (r, _) = &ranges[&s.options.cell];
            // The per-volume cost this structure depends on.
            let ranges_ms = r.ms(s.accel.method().ranges())?;
            let mut builds = Vec::new();
            let mut structure = Structure::naive();
            for i in 0..config.warmup + config.builds {
                let (st, t) = builder.build(s.accel, &scene, r, &s.options)?;
                if i >= config.warmup {
                    builds.push(t);
                }
                structure = st;
                progress.step(1);
            }
            let build = Timings::median(&builds);
            for w in 0..config.warmup {
                frames.frame(
                    &structure,
                    &gv,
                    &lut,
                    &orbit(config, w, config.frames, config.step, None),
                    false,
                )?;
                progress.step(1);
            }
            let mut times = Vec::new();
            let mut first = None;
            for view in 0..config.frames {
                let (ms, f) = frames.frame(
                    &structure,
                    &gv,
                    &lut,
                    &orbit(config, view, config.frames, config.step, None),
                    view == 0,
                )?;
                times.push(ms);
                if view == 0 {
                    first = f;
                }
                progress.step(1);
            }
            let first = first.expect("frame 0 read back");
            let error = diff(&naive0, &first)?;
            let stats = structure.stats()?.unwrap_or_default();
            let frame = FrameTimes::of(times);
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
                build_ms: build.total(),
                build_phases_ms: build.phases.into_iter().collect(),
                nodes: stats.nodes,
                leaves: stats.leaves,
                tree_height: stats.height,
                bytes: stats.bytes,
                fps: 1000.0 / frame.median_ms,
                frame,
                error_vs_naive: ImageError::from(error),
            });
            if options.keep_frames {
                out.frames.push((format!("{}-{}", loaded.spec, s.label), first));
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
            out.errors.extend(error_sweep(
                config,
                e,
                &setup,
                &loaded.spec,
                &structure,
                &gv,
                &lut,
                &mut frames,
                &progress,
            )?);
        }
    }

    progress.finish();
    Ok(out)
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
