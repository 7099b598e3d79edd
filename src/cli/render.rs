//! `lacuna render`: one frame with any structure, GPU time per pass, EXR or PNG out.

use super::args::{AccelParser, FrameArgs, ModelArgs, StructureArgs};
use super::stdout;
use super::{check_parent, context, tf_for, validation_verdict, VolumeArgs};
use clap::Args;
use lacuna::accel::{Accel, BuildInput, Builder, MarchedKind, Params, Structure};
use lacuna::frame::{Background, Frame, FrameFormat};
use lacuna::gpu::Context;
use lacuna::limits::MAX_RUNS;
use lacuna::render::metadata::Source;
use lacuna::render::{self, FrameDesc, Mode, Octants, Renderer, Scene};
use lacuna::tf::GpuTransferFunction;
use lacuna::volume::GpuVolume;
use lacuna::{Error, Result, Timings, TransferFunction, Volume};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub(super) volume: VolumeArgs,
    /// Transfer function: ramp:LO:HI[:A], band:LO:HI[:A], spike:C:W[:A] or a ParaView .json (default: the generator's).
    /// Several channels: one --tf per channel in order, or one for all.
    #[arg(long)]
    pub(super) tf: Vec<TransferFunction>,
    /// Empty space skipping structure (default auto: chosen per volume and TF).
    #[arg(long, default_value = "auto", value_parser = AccelParser)]
    pub(super) accel: Accel,
    #[command(flatten)]
    pub(super) structure: StructureArgs,
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// Image size WxH.
    #[arg(long, default_value = "1024x1024", value_parser = render::parse_size, allow_hyphen_values = true)]
    pub(super) size: (u32, u32),
    #[command(flatten)]
    pub(super) frame: FrameArgs,
    /// Time this many builds and frames (at most 100000) and report per-phase medians.
    #[arg(long, default_value_t = 1)]
    pub(super) repeat: u32,
    /// Untimed builds and frames first, at most 100000 (lavapipe compiles shaders on first use).
    #[arg(long, default_value_t = 0)]
    pub(super) warmup: u32,
    /// Write the frame: .exr (OpenEXR, RGBA f32, linear, premultiplied) or .png (8-bit sRGB, straight alpha).
    #[arg(long)]
    pub(super) out: Option<PathBuf>,
    /// PNG only: composite the frame over this sRGB colour (hex RRGGBB) and write it opaque.
    #[arg(long, requires = "out")]
    pub(super) background: Option<Background>,
    /// Enable Vulkan validation with synchronization validation; fail on any message.
    #[arg(long)]
    pub(super) validate: bool,
}

impl RenderArgs {
    /// Every option checked, before any file is read or GPU work is done.
    pub(super) fn options(&self) -> Result<(Params, FrameDesc, Option<FrameFormat>)> {
        let params = self.structure.params(self.accel)?;
        let desc = self.frame.desc(self.size)?;
        if self.repeat == 0 {
            return Err(Error::invalid("repeat", "0", "must be at least 1"));
        }
        for (what, n) in [("repeat", self.repeat), ("warmup", self.warmup)] {
            if n > MAX_RUNS {
                return Err(Error::invalid(what, n.to_string(), format!("at most {MAX_RUNS}")));
            }
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
        Ok((params, desc, format))
    }
}

/// Builds the structure `warmup + repeat` times; returns the last and the
/// per-phase medians of the timed builds (None for naive).
pub(super) fn build(
    builder: &Builder,
    args: &RenderArgs,
    input: &BuildInput,
    params: &Params,
) -> Result<(Structure, Option<Timings>)> {
    if args.accel.is_naive() {
        return Ok((Structure::naive(), None));
    }
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..args.warmup + args.repeat {
        // Ranges (only those this structure reads) are per volume; timed
        // with every run so the warm-up covers them.
        let (ranges, mut timings) = builder.ranges_for(&[(args.accel, params)], input.gpu_volume)?;
        let (structure, t) = builder.build(args.accel, input, &ranges, params)?;
        timings.extend(t);
        times.push(timings);
        last = Some(structure);
    }
    let structure = last.ok_or_else(|| Error::invalid("repeat", "0", "must be at least 1"))?;
    Ok((structure, Some(Timings::median(&times[args.warmup as usize..]))))
}

/// A structure built for a prepared volume, and the frames it rendered.
pub(super) struct Rendered {
    /// The volume as `upload` made it, with what the frames read.
    pub gpu_volume: GpuVolume,
    /// Wall ms of the upload and what `GpuVolume::prepare` added.
    pub upload_ms: f64,
    pub lut: GpuTransferFunction,
    pub structure: Structure,
    /// Per-phase medians of the timed builds (None for naive).
    pub build: Option<Timings>,
    /// The last frame, and the medians of the timed ones.
    pub frame: Frame,
    pub timings: Timings,
    /// Why auto's choice gave way to naive marching, when it did.
    pub fallback: Option<String>,
}

/// What `render` and each rank do with a loaded volume: `upload` it and
/// add what `desc`'s frames read (timed), its sampler for `desc`, the TF,
/// the structure (`warmup + repeat` builds) and the frames.
pub(super) fn build_and_render(
    ctx: &Context,
    args: &RenderArgs,
    params: &Params,
    (volume, tf): (&Volume, &TransferFunction),
    desc: &FrameDesc,
    upload: impl FnOnce() -> Result<GpuVolume>,
) -> Result<Rendered> {
    let builder = args.model.builder(ctx)?;
    let renderer = Renderer::new(builder.context())?;
    let clock = std::time::Instant::now();
    let mut gpu_volume = upload()?;
    gpu_volume.prepare(volume, desc.lighting().is_some(), desc.filter())?;
    let upload_ms = clock.elapsed().as_secs_f64() * 1e3;
    gpu_volume.sampler_for(desc.filter_for(&gpu_volume))?;
    let lut = tf.upload(ctx)?;
    let input = BuildInput {
        volume,
        gpu_volume: &gpu_volume,
        tf,
        gpu_tf: &lut,
        mode: *desc.mode(),
        frames: std::slice::from_ref(desc),
        octants: desc.octants(volume.dims, volume.spacing)?,
    };
    let (mut structure, build) = build(&builder, args, &input, params)?;
    let scene = Scene {
        structure: &structure,
        volume: &gpu_volume,
        tf: &lut,
    };
    let mut fallback = None;
    let (frame, timings) = match frames(&renderer, scene, desc, args) {
        // auto's choice ran into the device's loop cap (lavapipe) where
        // naive marching, which the frame was checked to fit, does not.
        Err(Error::LoopCap {
            structure: chosen,
            device,
            groups,
            ..
        }) if chose(&structure) => {
            fallback = Some(format!(
                "auto's choice ({chosen}) ran into {device}'s loop cap in {groups} SIMD group(s), so this frame was marched naively"
            ));
            structure = Structure::naive();
            let scene = Scene {
                structure: &structure,
                volume: &gpu_volume,
                tf: &lut,
            };
            frames(&renderer, scene, desc, args)?
        }
        result => result?,
    };
    Ok(Rendered {
        gpu_volume,
        upload_ms,
        lut,
        structure,
        build,
        frame,
        timings,
        fallback,
    })
}

/// `structure` is auto's choice.
fn chose(structure: &Structure) -> bool {
    structure
        .marched_as_reason()
        .is_some_and(|m| m.kind == MarchedKind::Choice)
}

/// Renders `warmup + repeat` frames; the last, and the medians of the timed ones.
pub(super) fn frames(
    renderer: &Renderer,
    scene: Scene,
    desc: &FrameDesc,
    args: &RenderArgs,
) -> Result<(Frame, Timings)> {
    // Only the last frame's pixels are kept: a long --repeat holds one
    // frame and each run's timings.
    let mut last = None;
    let mut times = Vec::with_capacity(args.repeat as usize);
    for run in 0..args.warmup + args.repeat {
        let (frame, t) = renderer.render(scene, desc)?;
        if run >= args.warmup {
            times.push(t);
        }
        last = Some(frame);
    }
    let timings = Timings::median(&times);
    let frame = last.ok_or_else(|| Error::invalid("repeat", "0", "must be at least 1"))?;
    Ok((frame, timings))
}

pub fn run(args: &RenderArgs) -> Result<ExitCode> {
    if args.out.is_some() {
        // The frame is the product: `render --out f.exr | grep -m1 ...`
        // still writes it after grep has gone.
        stdout::outlive_a_closed_pipe();
    }
    let (params, desc, format) = args.options()?;
    // The device first: the volume's size is checked against its limits
    // from the spec or header, before any voxel is read or made.
    let ctx = context(args.validate)?;
    // The frame's size too: auto's probes and the load come before its target.
    let (width, height) = desc.size();
    lacuna::render::RenderTarget::check_size(ctx.info(), width, height)?;
    let series = args.volume.series()?;
    let clock = std::time::Instant::now();
    let volume = series.load_stored(
        args.volume.time,
        args.volume.storage,
        ctx.info(),
        Some(stream_bar(&args.volume.volume)),
    )?;
    let load_ms = clock.elapsed().as_secs_f64() * 1e3;
    let tf = tf_for(&args.tf, &volume)?.unwrap_or(TransferFunction::parse("ramp:0:1")?);
    desc.check_for(volume.dims, volume.spacing)?;

    let Rendered {
        gpu_volume,
        upload_ms,
        lut,
        structure,
        build,
        mut frame,
        timings,
        fallback,
    } = build_and_render(&ctx, args, &params, (&volume, &tf), &desc, || {
        GpuVolume::upload_as(&ctx, &volume, args.volume.storage)
    })?;
    let scene = Scene {
        structure: &structure,
        volume: &gpu_volume,
        tf: &lut,
    };

    let info = ctx.info();
    say!(
        "device  {} ({}), subTexelPrecisionBits {}",
        info.name,
        info.driver,
        info.sub_texel_precision_bits
    );
    say!(
        "volume  {} ({}x{}x{} {})",
        volume.name,
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        volume.source_type
    );
    if let Some(step) = args.volume.step_line(&series) {
        say!("time    {step}");
    }
    if let Some(note) = series.norm_note() {
        say_err!("note: {note}");
    }
    say!("storage {}", gpu_volume.describe_storage());
    say!("loaded  in {load_ms:.0} ms, uploaded in {upload_ms:.0} ms (wall time; the upload with the pool's sorting, or the cells copy)");
    if let lacuna::volume::VoxelData::Bricks(host) = &volume.data {
        say!(
            "        streamed into bricks: the host holds {:.1} MiB of slots and table, not the dense volume",
            host.host_bytes() as f64 / (1u64 << 20) as f64
        );
    }
    say!("tf      {}", tf.spec);
    say!(
        "frame   {width}x{height}, {}, step {}, filter {}{}, accel {}",
        desc.camera().describe(),
        desc.step(),
        desc.filter_for(&gpu_volume),
        if desc.filter().is_none() {
            " (device default)"
        } else {
            ""
        },
        args.accel
    );
    let look: Vec<String> = desc
        .describe_look()
        .into_iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    if !look.is_empty() {
        say!("look    {}", look.join("; "));
    }
    for note in look_notes(&desc) {
        say!("note: {note}");
    }
    if args.repeat > 1 || args.warmup > 0 {
        say!(
            "timings are medians of {} runs after {} untimed warm-up runs",
            args.repeat,
            args.warmup
        );
    }
    if let Some(build) = &build {
        say!("structure {}", args.accel.method().description());
        for (k, v) in params.describe() {
            say!("  {k} {v}");
        }
        say!("build time per phase (GPU timestamps; CPU phases in wall time; ranges once per volume, the rest per TF change):\n{build}");
    }
    if let Some(m) = structure.marched_as_reason() {
        say!("{} -> {}", args.accel, m.label);
        say!("  {}", m.reason);
    }
    if let Some(fallback) = fallback {
        say!("note: {fallback}");
    }
    if let Some(stats) = structure.stats()? {
        say!("structure {stats}");
    }
    let octants = structure.octants();
    if octants != Octants::ALL {
        say!(
            "  octants {} of 8 ({octants}): the frame's ray directions; other directions walk cell by cell",
            octants.len()
        );
    }
    say!("render GPU time per pass:\n{timings}");
    if let Some(peak) = peak_host_bytes() {
        say!(
            "host peak {:.1} MiB (VmHWM: the most resident memory so far; on a CPU device it includes device memory)",
            peak as f64 / (1u64 << 20) as f64
        );
    }
    if let (Some(out), Some(format)) = (&args.out, format) {
        let source = Source {
            volume: &volume,
            time: (series.steps() > 1).then_some(args.volume.time),
            tf: &tf,
        };
        describe(&mut frame, source, scene, &desc, &ctx, &timings)?;
        match &args.background {
            Some(background) => frame.write_png_over(out, background)?,
            None => frame.write(out, format)?,
        }
        say!("wrote {}", out.display());
    }
    Ok(validation_verdict(&ctx))
}

/// What a user may not expect of this frame's look.
pub(super) fn look_notes(desc: &FrameDesc) -> Vec<String> {
    let mut notes = Vec::new();
    if let Mode::Iso(iso) = desc.mode() {
        for v in iso.values().iter().filter(|v| !(**v > 0.0 && **v <= 1.0)) {
            notes.push(format!(
                "iso value {v} lies outside the normalised data range (0, 1]: it shows no surface"
            ));
        }
    }
    if matches!(desc.mode(), Mode::Average) {
        notes.push("average visits every sample in the box: no structure skips in it, each marches naively".into());
    }
    notes
}

/// The frame's metadata (`render::metadata`), with its march pass's time.
pub(super) fn describe(
    frame: &mut Frame,
    data: Source,
    scene: Scene,
    desc: &FrameDesc,
    ctx: &Context,
    timings: &Timings,
) -> Result<()> {
    let march = Some(timings.phase("march")?);
    render::metadata::describe(frame, data, scene, desc, ctx.info(), march)
}

/// The process's peak resident memory (Linux `VmHWM`), where known.
pub(super) fn peak_host_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// A progress bar for a stream into bricks (on a terminal, once it has
/// taken a second).
pub(super) fn stream_bar(what: &str) -> lacuna::volume::StreamProgress {
    // Hidden until the stream has taken a second (and only on a terminal):
    // drawn from the start, it flashed on every load, streamed or not.
    // Cleared on drop too: a stream that fails leaves no bar above its error.
    let bar = indicatif::ProgressBar::hidden().with_finish(indicatif::ProgressFinish::AndClear);
    let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    bar.set_length(1);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} layers, ETA {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(format!("streaming {what} into bricks"));
    let start = std::time::Instant::now();
    std::sync::Arc::new(move |done: u32, total: u32| {
        if start.elapsed().as_secs_f64() > 1.0 {
            bar.set_length(total as u64);
            // Shown before the position is set, which draws it at once.
            if terminal && bar.is_hidden() && done < total {
                bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            }
            bar.set_position(done as u64);
        }
        if done == total {
            bar.finish_and_clear();
        }
    })
}
