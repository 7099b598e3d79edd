//! The `lacuna` command line: parses, calls the library, prints.

use clap::{Args, Parser, Subcommand};
use lacuna::accel::kd::KdParams;
use lacuna::accel::{BuildOptions, Builder, Classify, Scene, Structure};
use lacuna::gpu::{Context, ContextOptions};
use lacuna::render::{self, Accel, Camera, Frame, Projection, RenderSettings, Renderer};
use lacuna::volume::{BrickGrid, LoadOptions, RawLayout, BRICK};
use lacuna::{Error, Result, Timings, TransferFunction, Volume};
use std::path::PathBuf;
use std::process::ExitCode;

#[path = "cli/surfaces.rs"]
mod surfaces;

#[derive(Parser)]
#[command(
    name = "lacuna",
    version,
    about = "Vulkan direct volume renderer for comparing empty space skipping structures"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render one frame and print GPU time per pass.
    Render(Box<RenderArgs>),
    /// Describe a volume: dims, type, spacing, values; occupancy under a TF.
    Info(InfoArgs),
    /// Compare two EXR frames (exit 1 if --max-abs is exceeded, 2 on bad input).
    Diff(DiffArgs),
    /// List Vulkan devices (select one with LACUNA_DEVICE=<index or name>).
    Devices,
    /// Benchmark every structure (the paper's comparison), speed against error, or the hard-case suite.
    Bench(BenchArgs),
    /// Generate an SPD surface scene; print its primitive counts, optionally write NFF.
    Scene(surfaces::SceneArgs),
    /// Havran's octree comparison on the SPD scenes: build, trace (Whitted), print his statistics.
    Octree(Box<surfaces::OctreeArgs>),
}

#[derive(Args)]
struct BenchArgs {
    /// A benchmark config (TOML), like bench/quick.toml or bench/paper.toml.
    config: Option<PathBuf>,
    /// The built-in quick config (bench/quick.toml): every structure, small data, about 2 minutes on lavapipe.
    #[arg(long)]
    quick: bool,
    /// The built-in paper config (bench/paper.toml): the paper's grid of data sets x structures.
    #[arg(long)]
    paper: bool,
    /// Run a test suite instead: "hard" (the DESIGN hard cases for every structure; exit 1 on failure).
    #[arg(long)]
    suite: Option<String>,
    /// Output folder (default bench/out/<config name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override the config's number of views.
    #[arg(long)]
    frames: Option<u32>,
    /// Override the config's frame size (WxH).
    #[arg(long)]
    size: Option<String>,
    /// Override the config's timed builds per structure.
    #[arg(long)]
    builds: Option<u32>,
    /// Override the config's untimed warm-up frames and builds.
    #[arg(long)]
    warmup: Option<u32>,
    /// Write frame 0 of every run as EXR under OUT/frames.
    #[arg(long)]
    frames_out: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Enable Vulkan validation (the hard-case suite always does).
    #[arg(long)]
    validate: bool,
}

#[derive(Args)]
struct VolumeArgs {
    /// A file (.raw, .nrrd, .nhdr, .nii, .nii.gz) or NAME:SIZE[:PARAM] (menger, nbody, vessels, turbulence, shells).
    volume: String,
    /// Dimensions of a raw file whose name does not give them (WxHxD).
    #[arg(long, requires = "voxel_type")]
    dims: Option<String>,
    /// Voxel type of a raw file: uint8, uint16, int16, float32, float64.
    #[arg(long = "type", id = "voxel_type", requires = "dims")]
    voxel_type: Option<String>,
}

impl VolumeArgs {
    fn load(&self) -> Result<Volume> {
        let raw = match (&self.dims, &self.voxel_type) {
            (Some(d), Some(t)) => Some(RawLayout {
                dims: lacuna::volume::parse_dims(d)?,
                ty: lacuna::volume::parse_type(t)?,
            }),
            _ => None,
        };
        Volume::load(&self.volume, &LoadOptions { raw })
    }
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Transfer function: ramp:LO:HI[:A], band:LO:HI[:A], spike:C:W[:A] or a ParaView .json (default: the generator's).
    #[arg(long)]
    tf: Option<String>,
    /// Empty space skipping structure: naive, lbvh, grid, kd-cpu, kd-gpu, hybrid, octree-84, octree-89, octree-93, octree-rev.
    #[arg(long, default_value = "naive")]
    accel: String,
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
    /// Macro-cell edge of the grid and the hybrid (a power of two).
    #[arg(long, default_value_t = 16)]
    cell: u32,
    /// Image size WxH.
    #[arg(long, default_value = "1024x1024")]
    size: String,
    /// Orbit camera AZIMUTH,ELEVATION in degrees.
    #[arg(long, default_value = "30,20", allow_hyphen_values = true)]
    camera: String,
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
    /// Time this many builds and frames and report per-phase medians.
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Untimed builds and frames first (lavapipe compiles shaders on first use).
    #[arg(long, default_value_t = 0)]
    warmup: u32,
    /// Write the frame as OpenEXR (RGBA f32, premultiplied).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Enable Vulkan validation with synchronization validation; fail on any message.
    #[arg(long)]
    validate: bool,
}

#[derive(Args)]
struct InfoArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Transfer function for occupancy (default: the generator's, if any).
    #[arg(long)]
    tf: Option<String>,
}

#[derive(Args)]
struct DiffArgs {
    a: PathBuf,
    b: PathBuf,
    /// Fail (exit 1) when the max abs difference exceeds this.
    #[arg(long, allow_hyphen_values = true)]
    max_abs: Option<f64>,
    /// Write a PNG heatmap of per-pixel differences.
    #[arg(long)]
    heatmap: Option<PathBuf>,
}

fn context(validate: bool) -> Result<Context> {
    let mut options = ContextOptions::from_env();
    options.validation |= validate;
    Context::new(&options)
}

/// Exit 1 after printing every collected validation message, else success.
fn validation_verdict(ctx: &Context) -> ExitCode {
    let messages = ctx.take_validation_messages();
    if messages.is_empty() {
        return ExitCode::SUCCESS;
    }
    for m in &messages {
        eprintln!("validation: {m}");
    }
    eprintln!("error: {} Vulkan validation message(s)", messages.len());
    ExitCode::from(1)
}

fn tf_for(spec: Option<&str>, volume: &Volume) -> Result<Option<TransferFunction>> {
    match spec.map(str::to_string).or_else(|| volume.default_tf.clone()) {
        Some(s) => Ok(Some(TransferFunction::parse(&s)?)),
        None => Ok(None),
    }
}

fn render(args: &RenderArgs) -> Result<ExitCode> {
    // Validate every argument before any expensive work.
    let accel: Accel = args.accel.parse()?;
    let classify = Classify::parse(&args.classify, &args.apron)?;
    lacuna::accel::grid::check_cell(args.cell)?;
    let options = BuildOptions {
        classify,
        kd: KdParams::parse(&args.kd, args.max_leaf, args.bins)?,
        cell: args.cell,
    };
    let (width, height) = render::parse_size(&args.size)?;
    let (azimuth_deg, elevation_deg) = Camera::parse_orbit(&args.camera)?;
    let projection = match args.perspective {
        Some(fov_deg) => Projection::Perspective {
            fov_deg,
            distance: args.distance,
        },
        None => Projection::Orthographic,
    };
    let settings = RenderSettings {
        width,
        height,
        camera: Camera {
            azimuth_deg,
            elevation_deg,
            projection,
        },
        step: args.step,
        ert: args.ert,
    };
    settings.validate()?;
    if let Some(tf) = &args.tf {
        TransferFunction::parse(tf)?;
    }
    let volume = args.volume.load()?;
    let tf = tf_for(args.tf.as_deref(), &volume)?.unwrap_or(TransferFunction::parse("ramp:0:1")?);
    settings.params(volume.dims, volume.spacing, volume.norm)?;

    let ctx = context(args.validate)?;
    let renderer = Renderer::new(&ctx)?;
    let gpu_volume = lacuna::volume::GpuVolume::upload(&ctx, &volume)?;
    let lut = tf.upload(&ctx)?;
    if args.repeat == 0 {
        return Err(Error::invalid("repeat", "0", "must be at least 1"));
    }
    let runs = args.warmup + args.repeat;
    let scene = Scene {
        volume: &volume,
        gpu_volume: &gpu_volume,
        tf: &tf,
        gpu_tf: &lut,
    };
    let (structure, build) = match accel {
        Accel::Naive => (Structure::Naive, None),
        _ => {
            let builder = Builder::new(&ctx)?;
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..runs {
                // Ranges (only those this accel uses) are per volume; timed with every
                // run so warm-up covers them.
                let (ranges, mut timings) = builder.ranges_for(&[accel], &gpu_volume, options.cell)?;
                let (structure, t) = builder.build(accel, &scene, &ranges, &options)?;
                timings.extend(t);
                times.push(timings);
                last = Some(structure);
            }
            (
                last.expect("at least one run"),
                Some(Timings::median(&times[args.warmup as usize..])),
            )
        }
    };
    let mut frames = Vec::new();
    for _ in 0..runs {
        frames.push(renderer.render(&structure, &gpu_volume, &lut, &settings)?);
    }
    let timings = Timings::median(
        &frames[args.warmup as usize..]
            .iter()
            .map(|f| f.1.clone())
            .collect::<Vec<_>>(),
    );
    let mut frame = frames.pop().expect("at least one frame").0;

    let info = ctx.info();
    println!("device  {} ({})", info.name, info.driver);
    println!(
        "volume  {} ({}x{}x{} {})",
        volume.name, volume.dims[0], volume.dims[1], volume.dims[2], volume.source_type
    );
    println!("tf      {}", tf.spec);
    println!(
        "frame   {width}x{height}, {}, step {}, accel {accel}",
        settings.camera.describe(),
        settings.step
    );
    if args.repeat > 1 || args.warmup > 0 {
        println!(
            "timings are medians of {} runs after {} untimed warm-up runs",
            args.repeat, args.warmup
        );
    }
    if let Some(build) = &build {
        match accel {
            Accel::Lbvh => println!("classify {}", classify.describe()),
            Accel::KdCpu | Accel::KdGpu => println!("k-d tree {}", options.kd.describe()),
            Accel::Grid => println!("cells {}^3", options.cell),
            Accel::Hybrid => println!("shallow k-d tree over {}^3 cells", options.cell),
            Accel::Octree84 | Accel::Octree89 | Accel::Octree93 | Accel::OctreeRev => {
                println!("octree over 8^3 bricks, classify {}", classify.describe())
            }
            Accel::Naive => {}
        }
        println!("build time per phase (GPU timestamps; CPU phases in wall time; ranges once per volume, the rest per TF change):\n{build}");
    }
    if let Some(stats) = structure.stats()? {
        println!("structure {stats}");
    }
    println!("render GPU time per pass:\n{timings}");
    if let Some(out) = &args.out {
        let meta = &mut frame.metadata;
        meta.insert("volume".into(), volume.name.clone());
        meta.insert("tf".into(), tf.spec.clone());
        meta.insert("accel".into(), accel.to_string());
        match accel {
            Accel::Naive => {}
            Accel::KdCpu | Accel::KdGpu => {
                meta.insert("kd".into(), options.kd.describe());
            }
            Accel::Grid | Accel::Hybrid => {
                meta.insert("cell".into(), options.cell.to_string());
            }
            Accel::Lbvh | Accel::Octree84 | Accel::Octree89 | Accel::Octree93 | Accel::OctreeRev => {
                meta.insert("classify".into(), classify.describe().to_string());
            }
        }
        meta.insert("camera".into(), settings.camera.describe());
        meta.insert("step".into(), settings.step.to_string());
        meta.insert("ert".into(), settings.ert.map_or("off".into(), |e| e.to_string()));
        meta.insert("device".into(), format!("{} ({})", info.name, info.driver));
        meta.insert(
            "gpu_ms".into(),
            format!("{:.4}", timings.get("march").unwrap_or(f64::NAN)),
        );
        frame.write_exr(out)?;
        println!("wrote {}", out.display());
    }
    Ok(validation_verdict(&ctx))
}

fn info(args: &InfoArgs) -> Result<ExitCode> {
    if let Some(tf) = &args.tf {
        TransferFunction::parse(tf)?;
    }
    let v = args.volume.load()?;
    println!("volume   {}", v.name);
    println!(
        "dims     {}x{}x{} ({} voxels)",
        v.dims[0],
        v.dims[1],
        v.dims[2],
        v.voxel_count()
    );
    println!("type     {}", v.source_type);
    println!("spacing  {} x {} x {}", v.spacing[0], v.spacing[1], v.spacing[2]);
    println!("values   {} .. {}", v.value_range[0], v.value_range[1]);
    let mut bins = [0u64; 10];
    for i in 0..v.data.len() {
        let n = v.normalize(v.data.texel(i));
        bins[((n * 10.0) as usize).min(9)] += 1;
    }
    let total = v.voxel_count() as f64;
    println!("histogram of normalised values (10 bins, % of voxels):");
    let cells: Vec<String> = bins
        .iter()
        .enumerate()
        .map(|(i, c)| {
            format!(
                "[{:.1},{:.1}{} {:.2}",
                i as f32 / 10.0,
                (i + 1) as f32 / 10.0,
                if i == 9 { "]" } else { ")" },
                100.0 * *c as f64 / total
            )
        })
        .collect();
    for row in cells.chunks(5) {
        println!("  {}", row.join("  "));
    }
    if let Some(tf) = tf_for(args.tf.as_deref(), &v)? {
        let visible = (0..v.data.len())
            .filter(|&i| tf.lookup(v.normalize(v.data.texel(i)))[3] > 0.0)
            .count();
        let grid = BrickGrid::new(&v, BRICK, 1);
        let active = grid.active(&tf).iter().filter(|a| **a).count();
        println!("tf       {}", tf.spec);
        println!("visible  {:.3} % of voxels (alpha > 0)", 100.0 * visible as f64 / total);
        println!(
            "active   {:.3} % of {}^3 bricks ({} of {}, value ranges over a one-voxel apron)",
            100.0 * active as f64 / grid.len() as f64,
            BRICK,
            active,
            grid.len()
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn diff(args: &DiffArgs) -> Result<ExitCode> {
    if let Some(m) = args.max_abs {
        if m.is_nan() || m < 0.0 {
            return Err(Error::invalid("max-abs", m.to_string(), "must be a number >= 0"));
        }
    }
    let a = Frame::read_exr(&args.a)?;
    let b = Frame::read_exr(&args.b)?;
    let stats = render::diff(&a, &b)?;
    println!("{stats}");
    if let Some(path) = &args.heatmap {
        render::diff::write_heatmap(&a, &b, path, None)?;
        println!("wrote {}", path.display());
    }
    if let Some(m) = args.max_abs {
        if stats.max_abs > m {
            eprintln!("error: max_abs {:.6e} exceeds --max-abs {m}", stats.max_abs);
            return Ok(ExitCode::from(1));
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn bench(args: &BenchArgs) -> Result<ExitCode> {
    use lacuna::bench::{self, BenchConfig};
    let sources = args.config.is_some() as u32 + args.quick as u32 + args.paper as u32 + args.suite.is_some() as u32;
    if sources != 1 {
        return Err(Error::invalid(
            "bench",
            format!("{sources} sources"),
            "give exactly one of: a config file, --quick, --paper, --suite hard",
        ));
    }
    if let Some(suite) = &args.suite {
        if suite != "hard" {
            return Err(Error::invalid("suite", suite, "expected hard"));
        }
        let ctx = context(true)?;
        let progress = !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
        let outcomes = bench::hard::run(&ctx, |case| {
            if progress {
                eprintln!("hard case: {case}");
            }
        })?;
        println!("device {} ({})", ctx.info().name, ctx.info().driver);
        println!("{}", bench::hard::table(&outcomes));
        let failed: Vec<_> = outcomes.iter().filter(|o| !o.passed()).collect();
        for o in &failed {
            println!(
                "FAIL {} / {}: identical {}, validation messages {}, finite {}; {}",
                o.case, o.structure, o.identical, o.validation_messages, o.finite, o.detail
            );
        }
        println!(
            "hard cases: {} of {} structure runs passed",
            outcomes.len() - failed.len(),
            outcomes.len()
        );
        return Ok(if failed.is_empty() {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(1)
        });
    }
    let mut config = match (&args.config, args.quick) {
        (Some(path), _) => BenchConfig::load(path)?,
        (None, true) => BenchConfig::parse(bench::config::QUICK, "bench/quick.toml (built in)")?,
        (None, false) => BenchConfig::parse(bench::config::PAPER, "bench/paper.toml (built in)")?,
    };
    if let Some(f) = args.frames {
        if f == 0 {
            return Err(Error::invalid("frames", "0", "must be at least 1"));
        }
        config.frames = f;
    }
    if let Some(size) = &args.size {
        let (w, h) = render::parse_size(size)?;
        config.size = [w, h];
    }
    if let Some(b) = args.builds {
        if b == 0 {
            return Err(Error::invalid("builds", "0", "must be at least 1"));
        }
        config.builds = b;
    }
    if let Some(w) = args.warmup {
        config.warmup = w;
    }
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("bench/out").join(&config.name));
    let ctx = context(args.validate)?;
    let output = bench::run::run(
        &ctx,
        &config,
        &bench::RunOptions {
            quiet: args.quiet,
            keep_frames: args.frames_out,
        },
    )?;
    let written = bench::write_outputs(&out_dir, &output)?;
    println!("device {} ({})", ctx.info().name, ctx.info().driver);
    println!(
        "config {}: {}x{}, {} views after {} warm-up, step {}, {} builds per structure",
        config.name, config.size[0], config.size[1], config.frames, config.warmup, config.step, config.builds
    );
    println!();
    println!("{}", bench::tables::table2_md(&output.records));
    println!("{}", bench::tables::table1_md(&output.records));
    println!("{}", bench::tables::exactness_md(&output.records));
    for note in &output.notes {
        println!("note: {note}");
    }
    println!("wrote {} files to {}", written.len(), out_dir.display());
    Ok(validation_verdict(&ctx))
}

fn devices() -> Result<ExitCode> {
    let list = lacuna::gpu::list_devices()?;
    if list.is_empty() {
        return Err(Error::NoDevice(
            "no Vulkan device found; install a driver (Debian: apt install mesa-vulkan-drivers libvulkan1)".into(),
        ));
    }
    for d in list {
        println!(
            "{}: {} ({}, Vulkan {}, {}){}",
            d.index,
            d.name,
            d.device_type,
            d.api,
            d.driver,
            if d.usable {
                ""
            } else {
                " [unusable: needs Vulkan 1.3, compute, VK_KHR_push_descriptor]"
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return ExitCode::from(if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                    2
                } else {
                    0
                });
            }
            // One line: clap's first line names the bad argument.
            let text = e.render().to_string();
            eprintln!("{}", text.lines().next().unwrap_or("error: invalid arguments"));
            return ExitCode::from(2);
        }
    };
    let result = match &cli.command {
        Command::Render(a) => render(a),
        Command::Info(a) => info(a),
        Command::Diff(a) => diff(a),
        Command::Devices => devices(),
        Command::Bench(a) => bench(a),
        Command::Scene(a) => surfaces::scene(a),
        Command::Octree(a) => surfaces::octree(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
