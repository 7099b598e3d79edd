//! `lacuna render`: one frame with any structure, GPU time per pass, EXR or PNG out.

use super::{check_parent, context, frame_settings, tf_for, validation_verdict, VolumeArgs};
use clap::Args;
use lacuna::accel::kd::KdParams;
use lacuna::accel::{parse_collapse, Accel, BuildInput, BuildOptions, Builder, Classify, Structure};
use lacuna::frame::{Background, Frame, FrameFormat};
use lacuna::gpu::Context;
use lacuna::render::{self, Camera, Filter, RenderSettings, Renderer};
use lacuna::volume::GpuVolume;
use lacuna::{Error, Result, Timings, TransferFunction, Volume};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Transfer function: ramp:LO:HI[:A], band:LO:HI[:A], spike:C:W[:A] or a ParaView .json (default: the generator's).
    #[arg(long)]
    tf: Option<TransferFunction>,
    /// Empty space skipping structure: auto (default: chosen per volume and TF), naive, lbvh, grid, distance, distance-octant, kd-cpu, kd-gpu, hybrid, octree-84, octree-89, octree-93, octree-rev.
    #[arg(long, default_value = "auto")]
    accel: Accel,
    /// Brick classification of skipping structures: range (default, O(bricks) per TF change) or voxel.
    #[arg(long, default_value = "range")]
    classify: String,
    /// With --classify voxel: keep the one-voxel apron (on), or drop it as the paper does (off; not conservative).
    #[arg(long, default_value = "on")]
    apron: String,
    /// k-d trees: shallow (leaf below 10 % of the root volume) or deep (leaf at 8^3).
    #[arg(long, default_value = "deep")]
    kd: String,
    /// Deep k-d trees: split leaves longer than this many voxels in the middle.
    #[arg(long, default_value_t = 32)]
    max_leaf: u32,
    /// GPU k-d tree: candidate bins per node.
    #[arg(long, default_value_t = 4)]
    bins: u32,
    /// Macro-cell edge in voxels, a power of two (default: the structure's; grid and hybrid 16, distance maps 8).
    #[arg(long)]
    cell: Option<u32>,
    /// Trees (lbvh, kd-cpu, kd-gpu): cost-driven leaves, a subtree cheaper as one leaf by the measured cost model becomes one (on), or the paper's trees (off).
    #[arg(long, default_value = "off")]
    collapse: String,
    /// Image size WxH.
    #[arg(long, default_value = "1024x1024", value_parser = render::parse_size)]
    size: (u32, u32),
    /// Orbit camera AZIMUTH,ELEVATION in degrees.
    #[arg(long, default_value = "30,20", allow_hyphen_values = true, value_parser = Camera::parse_orbit)]
    camera: (f64, f64),
    /// Perspective projection with this vertical field of view (degrees); default orthographic.
    #[arg(long)]
    perspective: Option<f64>,
    /// Perspective eye distance from the centre, in bounding-sphere radii (default: fit).
    #[arg(long, requires = "perspective")]
    distance: Option<f64>,
    /// Sample step in voxels.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    step: f32,
    /// Early ray termination at this accumulated alpha (default off).
    #[arg(long, allow_hyphen_values = true)]
    ert: Option<f32>,
    /// Sample filter: manual (eight texel fetches, f32 weights) or hardware (the sampler's linear filtering; default where the volume's format supports it).
    #[arg(long)]
    filter: Option<Filter>,
    /// Time this many builds and frames and report per-phase medians.
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Untimed builds and frames first (lavapipe compiles shaders on first use).
    #[arg(long, default_value_t = 0)]
    warmup: u32,
    /// Write the frame: .exr (OpenEXR, RGBA f32, linear, premultiplied) or .png (8-bit sRGB, straight alpha).
    #[arg(long)]
    out: Option<PathBuf>,
    /// PNG only: composite the frame over this sRGB colour (hex RRGGBB) and write it opaque.
    #[arg(long, requires = "out")]
    background: Option<Background>,
    /// Enable Vulkan validation with synchronization validation; fail on any message.
    #[arg(long)]
    validate: bool,
}

impl RenderArgs {
    /// Every option checked, before any file is read or GPU work is done.
    fn options(&self) -> Result<(BuildOptions, RenderSettings, Option<FrameFormat>)> {
        let options = BuildOptions {
            classify: Classify::parse(&self.classify, &self.apron)?,
            kd: KdParams::parse(&self.kd, self.max_leaf, self.bins)?,
            cell: self.cell.unwrap_or(self.accel.method().default_cell()),
            collapse: parse_collapse(&self.collapse)?,
        };
        options.validate()?;
        let settings = frame_settings(
            self.size,
            self.camera,
            self.perspective,
            self.distance,
            self.step,
            self.ert,
            self.filter,
        )?;
        if self.repeat == 0 {
            return Err(Error::invalid("repeat", "0", "must be at least 1"));
        }
        let format = self.out.as_deref().map(FrameFormat::from_path).transpose()?;
        if let (Some(background), Some(FrameFormat::Exr)) = (&self.background, format) {
            return Err(Error::invalid(
                "background",
                background.spec.clone(),
                "only a .png frame is composited; an .exr frame keeps its alpha",
            ));
        }
        if let Some(out) = &self.out {
            check_parent(out)?;
        }
        Ok((options, settings, format))
    }
}

/// Builds the structure `warmup + repeat` times; returns the last and the
/// per-phase medians of the timed builds (None for naive).
fn build(
    ctx: &Context,
    args: &RenderArgs,
    input: &BuildInput,
    options: &BuildOptions,
) -> Result<(Structure, Option<Timings>)> {
    if args.accel.is_naive() {
        return Ok((Structure::naive(), None));
    }
    let builder = Builder::new(ctx)?;
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..args.warmup + args.repeat {
        // Ranges (only those this accel reads) are per volume; timed with
        // every run so the warm-up covers them.
        let (ranges, mut timings) = builder.ranges_for(&[args.accel], input.gpu_volume, options.cell)?;
        let (structure, t) = builder.build(args.accel, input, &ranges, options)?;
        timings.extend(t);
        times.push(timings);
        last = Some(structure);
    }
    let structure = last.ok_or_else(|| Error::invalid("repeat", "0", "must be at least 1"))?;
    Ok((structure, Some(Timings::median(&times[args.warmup as usize..]))))
}

pub fn run(args: &RenderArgs) -> Result<ExitCode> {
    let (options, mut settings, format) = args.options()?;
    // The device first: the volume's size is checked against its limits
    // from the spec or header, before any voxel is read or made.
    let ctx = context(args.validate)?;
    let volume = args.volume.load_for(&ctx)?;
    let tf = tf_for(args.tf.as_ref(), &volume)?.unwrap_or(TransferFunction::parse("ramp:0:1")?);
    settings.params(volume.dims, volume.spacing, volume.norm)?;

    let renderer = Renderer::new(&ctx)?;
    let gpu_volume = GpuVolume::upload(&ctx, &volume)?;
    settings.filter = args.filter.unwrap_or_else(|| gpu_volume.default_filter());
    gpu_volume.sampler_for(settings.filter)?;
    let lut = tf.upload(&ctx)?;
    let input = BuildInput {
        volume: &volume,
        gpu_volume: &gpu_volume,
        tf: &tf,
        gpu_tf: &lut,
    };
    let (structure, build) = build(&ctx, args, &input, &options)?;
    let mut frames = Vec::new();
    for _ in 0..args.warmup + args.repeat {
        frames.push(renderer.render(&structure, &gpu_volume, &lut, &settings)?);
    }
    let timings = Timings::median(
        &frames[args.warmup as usize..]
            .iter()
            .map(|f| f.1.clone())
            .collect::<Vec<_>>(),
    );
    let mut frame = frames
        .pop()
        .map(|f| f.0)
        .ok_or_else(|| Error::invalid("repeat", "0", "must be at least 1"))?;

    let info = ctx.info();
    let params = args.accel.method().params(&options);
    println!(
        "device  {} ({}), subTexelPrecisionBits {}",
        info.name, info.driver, info.sub_texel_precision_bits
    );
    println!(
        "volume  {} ({}x{}x{} {})",
        volume.name, volume.dims[0], volume.dims[1], volume.dims[2], volume.source_type
    );
    println!("tf      {}", tf.spec);
    println!(
        "frame   {}x{}, {}, step {}, filter {}{}, accel {}",
        settings.width,
        settings.height,
        settings.camera.describe(),
        settings.step,
        settings.filter,
        if args.filter.is_none() { " (device default)" } else { "" },
        args.accel
    );
    if args.repeat > 1 || args.warmup > 0 {
        println!(
            "timings are medians of {} runs after {} untimed warm-up runs",
            args.repeat, args.warmup
        );
    }
    if let Some(build) = &build {
        println!("structure {}", args.accel.method().description());
        for (k, v) in &params {
            println!("  {k} {v}");
        }
        println!("build time per phase (GPU timestamps; CPU phases in wall time; ranges once per volume, the rest per TF change):\n{build}");
    }
    if let Some(choice) = structure.choice() {
        println!("auto -> {}", choice.describe());
        println!("  {}", choice.reason());
    } else if structure.accel.is_naive() && !args.accel.is_naive() {
        println!("marched with the naive kernel: the tree is one leaf covering the volume");
    }
    if let Some(stats) = structure.stats()? {
        println!("structure {stats}");
    }
    println!("render GPU time per pass:\n{timings}");
    if let (Some(out), Some(format)) = (&args.out, format) {
        describe(
            &mut frame, &volume, &tf, &structure, args.accel, &params, &settings, &ctx, &timings,
        )?;
        match &args.background {
            Some(background) => frame.write_png_over(out, background)?,
            None => frame.write(out, format)?,
        }
        println!("wrote {}", out.display());
    }
    Ok(validation_verdict(&ctx))
}

/// The frame's metadata: what made it.
#[allow(clippy::too_many_arguments)]
pub(super) fn describe(
    frame: &mut Frame,
    volume: &Volume,
    tf: &TransferFunction,
    structure: &Structure,
    accel: Accel,
    params: &[(&'static str, String)],
    settings: &RenderSettings,
    ctx: &Context,
    timings: &Timings,
) -> Result<()> {
    let info = ctx.info();
    let meta = &mut frame.metadata;
    meta.insert("volume".into(), volume.name.clone());
    meta.insert("tf".into(), tf.spec.clone());
    meta.insert("accel".into(), accel.to_string());
    if let Some(choice) = structure.choice() {
        meta.insert("auto".into(), choice.describe());
    }
    for (k, v) in params {
        meta.insert(k.to_string(), v.clone());
    }
    meta.insert("camera".into(), settings.camera.describe());
    meta.insert("step".into(), settings.step.to_string());
    meta.insert("ert".into(), settings.ert.map_or("off".into(), |e| e.to_string()));
    meta.insert("filter".into(), settings.filter.to_string());
    meta.insert("device".into(), format!("{} ({})", info.name, info.driver));
    meta.insert("gpu_ms".into(), format!("{:.4}", timings.phase("march")?));
    Ok(())
}
