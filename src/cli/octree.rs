//! `lacuna octree`: Havran's octree traversal comparison on the SPD scenes.

use super::{check_parent, context, validation_verdict};
use clap::Args;
use lacuna::frame::FrameFormat;
use lacuna::octree::report::{self, Backend, Row};
use lacuna::octree::whitted::WhittedOptions;
use lacuna::octree::{Mode, TraceKernels, TraceScene, Traversal, MAX_DEPTH_LIMIT};
use lacuna::scene::{Scene, SpdScene};
use lacuna::{Error, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct OctreeArgs {
    /// The SPD scene (omit with --all).
    scene: Option<SpdScene>,
    /// Subdivision: C (centre) or A (adaptive).
    #[arg(long, default_value = "C")]
    mode: Mode,
    /// Maximum depth (root at depth 0); Havran's range is 4..7.
    #[arg(long, default_value_t = 6)]
    max_depth: u32,
    /// Traversal: 84, 89, 93, rev, or all (every one on the same rays).
    #[arg(long, default_value = "rev")]
    traversal: String,
    /// SPD size factor (default: the SPD's default size).
    #[arg(long)]
    size: Option<u32>,
    /// Image edge in pixels (the SPD's 512; one eye ray per pixel corner).
    #[arg(long, default_value_t = 512)]
    resolution: u32,
    /// Write the image: .exr (RGBA f32) or .png (8-bit sRGB), by extension.
    #[arg(long)]
    out: Option<PathBuf>,
    /// The full comparison: 8 scenes x modes C, A x depths 4..7 x all traversals.
    #[arg(long, conflicts_with_all = ["scene", "out", "mode", "max_depth", "traversal"])]
    all: bool,
    /// With --all: also write the tables as Markdown to this file.
    #[arg(long, requires = "all")]
    report: Option<PathBuf>,
    /// Trace with the CPU reference instead of the GPU.
    #[arg(long)]
    cpu: bool,
    /// Enable Vulkan validation with synchronization validation; fail on any message.
    #[arg(long)]
    validate: bool,
}

fn traversals(spec: &str) -> Result<Vec<Traversal>> {
    if spec == "all" {
        return Ok(Traversal::ALL.to_vec());
    }
    Ok(vec![spec.parse()?])
}

/// Deeper surface octrees with one object per leaf grow like 4^depth along
/// every surface; Havran's range is 4..7.
const CLI_MAX_DEPTH: u32 = if MAX_DEPTH_LIMIT < 10 { MAX_DEPTH_LIMIT } else { 10 };

fn check_depth(depth: u32) -> Result<()> {
    if depth > CLI_MAX_DEPTH {
        return Err(Error::invalid(
            "max depth",
            depth.to_string(),
            format!("at most {CLI_MAX_DEPTH} (Havran's range is 4..7; deeper trees grow like 4^depth)"),
        ));
    }
    Ok(())
}

pub fn run(args: &OctreeArgs) -> Result<ExitCode> {
    let mode = args.mode;
    check_depth(args.max_depth)?;
    let kinds = traversals(&args.traversal)?;
    // clap's `requires` counts --all's default as given: check it here.
    if let (Some(path), false) = (&args.report, args.all) {
        return Err(Error::invalid(
            "report",
            path.display().to_string(),
            "is the --all comparison's tables: give --all with it",
        ));
    }
    for path in args.out.iter().chain(&args.report) {
        check_parent(path)?;
    }
    let format = args.out.as_deref().map(FrameFormat::from_path).transpose()?;
    if args.resolution == 0 || args.resolution > 8192 {
        return Err(Error::invalid(
            "resolution",
            args.resolution.to_string(),
            "must be 1..=8192",
        ));
    }
    let scenes: Vec<SpdScene> = match (&args.scene, args.all) {
        (_, true) => SpdScene::ALL.to_vec(),
        (Some(s), false) => vec![*s],
        (None, false) => return Err(Error::invalid("scene", "", "name a scene, or use --all")),
    };
    let generated = scenes
        .iter()
        .map(|&k| Scene::generate(k, args.size))
        .collect::<Result<Vec<_>>>()?;
    let ctx = if args.cpu { None } else { Some(context(args.validate)?) };
    let kernels = ctx.as_ref().map(TraceKernels::new).transpose()?;
    let backend = match &kernels {
        Some(k) => Backend::Gpu(k),
        None => Backend::Cpu,
    };
    // The tree's byte budget: it is built in host memory, a quarter of it
    // at most 4 GiB (16 times what 128 MiB buffers hold); the GPU holds
    // nodes and references in a storage buffer each.
    let host = (lacuna::limits::available_memory() / 4).min(4 << 30);
    let max_bytes = match &ctx {
        Some(ctx) => host.min(2 * ctx.info().max_storage_buffer_range),
        None => host,
    };
    let options = WhittedOptions {
        resolution: args.resolution,
        max_depth: 5,
        image: args.out.is_some(),
    };
    let mut rows: Vec<Row> = Vec::new();
    for scene in &generated {
        let traced = TraceScene::new(scene);
        let default_size = args.size.is_none() && args.resolution == 512;
        let configs: Vec<(Mode, u32)> = if args.all {
            [Mode::Center, Mode::Adaptive]
                .into_iter()
                .flat_map(|m| (4..=7).map(move |d| (m, d)))
                .collect()
        } else {
            vec![(mode, args.max_depth)]
        };
        let all_kinds = if args.all {
            Traversal::ALL.to_vec()
        } else {
            kinds.clone()
        };
        for (m, d) in configs {
            let (row, image) = report::run(&backend, max_bytes, scene, &traced, m, d, &all_kinds, &options)?;
            if !args.all {
                say!("{}", report::format_counts(scene.kind, &row.counts, default_size));
                say_text!("{}", report::format_row(&row));
                if all_kinds.len() > 1 {
                    say!("rays whose hit differs between traversals: {}", row.disagreements);
                }
            } else {
                say_err!(
                    "{} {}{}: T_B {:.3} s, hit disagreements {}",
                    row.scene,
                    row.mode,
                    row.max_depth,
                    row.build.build_s,
                    row.disagreements
                );
            }
            if let (Some(path), Some(format), Some(frame)) = (&args.out, format, image) {
                frame.write(path, format)?;
                say!("wrote {}", path.display());
            }
            rows.push(row);
        }
    }
    if args.all {
        let md = report::format_all(&rows);
        say_text!("{md}");
        if let Some(path) = &args.report {
            lacuna::frame::write_atomically(path, |tmp| {
                std::fs::write(tmp, md.as_bytes()).map_err(|e| Error::io(path, e))
            })?;
        }
    }
    drop(kernels);
    Ok(ctx.as_ref().map_or(ExitCode::SUCCESS, validation_verdict))
}
