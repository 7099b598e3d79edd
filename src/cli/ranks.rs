//! `mpirun -np N lacuna render ...` (feature `mpi`): each rank renders its
//! block of the volume, IceT composites the ranks' frames in visibility
//! order (MIP and MinIP frames: each pixel's extreme ray value picks the
//! colour; iso frames: the nearest surface), rank 0 prints and writes the frame (`lacuna::parallel`).

use super::render::{build_and_render, describe, look_notes, peak_host_bytes, RenderArgs, Rendered};
use super::{context, tf_for, validation_verdict};
use lacuna::frame::Frame;
use lacuna::gpu::Context;
use lacuna::parallel::{Decomposition, Failed, World};
use lacuna::render::{FrameDesc, Mode, Scene};
use lacuna::volume::{GpuVolume, PoolLimits, Storage, StreamTo, POOL_BRICK};
use lacuna::{Error, Result, Timings, TransferFunction};
use std::process::ExitCode;
use std::time::Instant;

/// What one rank made: its frame of its block, and what rank 0 reports.
struct Part {
    ctx: Context,
    frame: Frame,
    order: Vec<u32>,
    timings: Timings,
    /// Per rank, gathered on rank 0: load and upload wall ms, build ms, march
    /// GPU ms, bricks stored, host peak bytes.
    stats: [f64; 6],
    report: Vec<String>,
    desc: FrameDesc,
}

/// The frame of this rank's block, on every rank; a failure on any rank
/// stops every rank before IceT (whose collectives would wait for it).
pub fn run(args: &RenderArgs) -> Result<ExitCode> {
    let world = World::init()?;
    let part = render_block(args, &world);
    // Every rank ends its part in the streaming agreement, however its
    // part ended, before any other collective.
    world.end_streams(part.is_err());
    // A rank that failed only because another did leaves the report to it.
    let outcome = match &part {
        Ok(_) => Failed::No,
        Err(Error::Elsewhere(_)) => Failed::Elsewhere,
        Err(_) => Failed::Own,
    };
    match (world.first_failed(outcome), part) {
        (None, Ok(part)) => {
            let composited = composite(&world, &part);
            let outcome = if composited.is_ok() { Failed::No } else { Failed::Own };
            match (world.first_failed(outcome), composited) {
                (None, Ok(c)) => finish(args, &world, part, c),
                (first, c) => fail(&world, first, c.map(|_| ())),
            }
        }
        (first, part) => fail(&world, first, part.map(|_| ())),
    }
}

/// The ranks' frames as one: composite frames blended front to back by
/// IceT, MIP (MinIP) frames by the colour of each pixel's largest
/// (smallest) ray value, iso frames by the nearest surface's.
fn composite(world: &World, part: &Part) -> Result<(Option<Vec<[f32; 4]>>, f64)> {
    let size = part.desc.size();
    match (part.desc.mode(), &part.frame.depth) {
        (Mode::Composite, _) => world.composite(size, &part.frame.pixels, &part.order),
        (mode, Some(values)) => world.pick(size, &part.frame.pixels, values, *mode == Mode::Mip),
        (mode, None) => Err(Error::invalid(
            "mode",
            mode.name(),
            "the rank's frame came back without its ray values",
        )),
    }
}

/// How `composite` joined the frames, for the report.
fn composited_how(mode: &Mode, order: &[u32]) -> String {
    match mode {
        Mode::Composite => {
            let order: Vec<String> = order.iter().map(u32::to_string).collect();
            format!("IceT ordered blend, ranks front to back {}", order.join(" "))
        }
        Mode::Mip => "each pixel's largest ray value and its colour, by an MPI MAXLOC reduction".into(),
        Mode::Iso(_) => "each pixel's nearest surface and its colour, by an MPI MINLOC reduction".into(),
        _ => "each pixel's smallest ray value and its colour, by an MPI MINLOC reduction".into(),
    }
}

/// Ends this rank after the ranks agreed that `first` failed: that rank
/// says why, before any rank exits (mpirun ends the others at the first
/// non-zero exit).
fn fail(world: &World, first: Option<u32>, outcome: Result<()>) -> Result<ExitCode> {
    if let (Some(r), Err(e)) = (first, outcome) {
        if r == world.rank {
            say_err!("error: {e} (rank {} of {})", world.rank, world.size);
        }
    }
    world.barrier();
    Ok(ExitCode::from(2))
}

fn render_block(args: &RenderArgs, world: &World) -> Result<Part> {
    let (params, desc, _) = args.options()?;
    let edge = match args.volume.storage {
        Storage::Bricks { edge } => edge,
        Storage::Auto => POOL_BRICK,
        Storage::Dense => {
            return Err(Error::invalid(
                "storage",
                "dense",
                "ranks store their blocks in bricks: use --storage auto or bricks[:N]",
            ))
        }
    };
    match desc.mode() {
        Mode::Composite | Mode::Mip | Mode::MinIp => {}
        Mode::Average => {
            return Err(Error::invalid(
                "mode",
                "average",
                "does not composite across ranks: the mean of the ray's samples goes through the transfer function after every rank's sum and count would be joined; render it in one process",
            ))
        }
        // The sample before a rank's first (an iso bracket's start) and the
        // gradient around it must lie in the ghost bricks.
        Mode::Iso(_) if desc.step() > edge.saturating_sub(2) as f32 => {
            return Err(Error::invalid(
                "step",
                desc.step().to_string(),
                format!(
                    "iso across ranks reads the sample one step before a block in its ghost bricks of {edge}^3: use --step {} or less, or larger bricks",
                    edge.saturating_sub(2)
                ),
            ))
        }
        Mode::Iso(_) => {}
    }
    let ctx = context(args.validate)?;
    let series = args.volume.series()?;
    let clock = Instant::now();
    // A source that comes in slabs is streamed, reading or generating only
    // the layers of this rank's bricks and ghosts (the ranks agree on the
    // value range); others load whole (the upload keeps the bricks).
    let volume = match series.streamed_layout() {
        Some((dims, _)) => {
            let split = Decomposition::new(dims, edge, world.size)?;
            let keep = split.blocks[world.rank as usize].with_ghosts(split.counts);
            let to = StreamTo::new(edge, PoolLimits::of(ctx.info()))
                .keep(Some(keep))
                .across(world.range_across());
            series.load_bricks(args.volume.time, &to)?
        }
        None => series.load(args.volume.time, None)?,
    };
    let load_ms = clock.elapsed().as_secs_f64() * 1e3;
    let tf = tf_for(&args.tf, &volume)?.unwrap_or(TransferFunction::parse("ramp:0:1")?);
    desc.check_for(volume.dims, volume.spacing)?;
    let split = Decomposition::new(volume.dims, edge, world.size)?;
    let block = split.blocks[world.rank as usize];

    // The frame's samples inside the block.
    let (lo, hi) = block.bounds();
    let block_desc = desc.to_builder().segment(Some([lo, hi])).build()?;

    let keep = block.with_ghosts(split.counts);
    let Rendered {
        gpu_volume,
        upload_ms,
        lut,
        structure,
        build,
        mut frame,
        timings,
        fallback,
    } = build_and_render(&ctx, args, &params, (&volume, &tf), &block_desc, || {
        GpuVolume::upload_bricks_kept(&ctx, &volume, edge, keep)
    })?;
    // Per build: ranges and the structure (GPU timestamps; CPU phases in wall time).
    let build_ms = build.as_ref().map_or(0.0, Timings::total);
    let scene = Scene {
        structure: &structure,
        volume: &gpu_volume,
        tf: &lut,
    };
    let source = lacuna::render::metadata::Source {
        volume: &volume,
        time: (series.steps() > 1).then_some(args.volume.time),
        tf: &tf,
    };
    describe(&mut frame, source, scene, &desc, &ctx, &timings)?;

    let (width, height) = desc.size();
    let rays = desc.camera().rays(volume.dims, volume.spacing, width, height)?;
    let pool = gpu_volume.pool();
    let mut report = vec![
        format!(
            "volume  {} ({}x{}x{} {})",
            volume.name, volume.dims[0], volume.dims[1], volume.dims[2], volume.source_type
        ),
        format!(
            "ranks   {} blocks of bricks of {edge}^3 (k-d split), each stored with one layer of ghost bricks",
            world.size
        ),
        format!("tf      {}", tf.spec),
        format!(
            "frame   {width}x{height}, {}, step {}, filter {}, accel {}",
            desc.camera().describe(),
            desc.step(),
            block_desc.filter_for(&gpu_volume),
            args.accel
        ),
    ];
    if let Some(m) = structure.marched_as_reason() {
        report.push(format!("{} -> {} on rank 0", args.accel, m.label));
    }
    if let Some(fallback) = fallback {
        report.push(format!("note: on rank 0, {fallback}"));
    }
    report.extend(look_notes(&desc).into_iter().map(|n| format!("note: {n}")));
    if let Some(ert) = desc.ert() {
        report.push(format!(
            "note: each rank ends its own segment at alpha {ert}: the frame differs from one process's by up to {}",
            1.0 - ert
        ));
    }
    Ok(Part {
        stats: [
            load_ms,
            upload_ms,
            build_ms,
            timings.phase("march")?,
            pool.map_or(0.0, |p| p.stored as f64),
            peak_host_bytes().unwrap_or(0) as f64,
        ],
        frame,
        order: split.order(&rays),
        timings,
        report,
        desc,
        ctx,
    })
}

/// Rank 0 prints the report and writes the composited frame.
fn finish(
    args: &RenderArgs,
    world: &World,
    part: Part,
    (pixels, composite_ms): (Option<Vec<[f32; 4]>>, f64),
) -> Result<ExitCode> {
    let stats = world.gather(&part.stats);
    let Some(pixels) = pixels else {
        return Ok(validation_verdict(&part.ctx));
    };
    let info = part.ctx.info();
    say!(
        "device  {} ({}), subTexelPrecisionBits {}",
        info.name,
        info.driver,
        info.sub_texel_precision_bits
    );
    for line in &part.report {
        say!("{line}");
    }
    say!("per rank (wall ms for load and upload; build ms of its phases, GPU timestamps and CPU wall; GPU ms for march):");
    for (rank, s) in stats.chunks_exact(6).enumerate() {
        say!(
            "  rank {rank}: load {:.0}, upload {:.0}, build {:.1}, march {:.3}, bricks stored {}, host peak {:.1} MiB",
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5] / (1u64 << 20) as f64
        );
    }
    say!(
        "composite {composite_ms:.3} ms wall ({})",
        composited_how(part.desc.mode(), &part.order)
    );
    say!("render GPU time per pass on rank 0:\n{}", part.timings);
    if let Some(out) = &args.out {
        let mut frame = Frame::new(part.frame.width, part.frame.height, pixels);
        frame.metadata = part.frame.metadata;
        frame.metadata.insert("ranks".into(), world.size.to_string());
        frame
            .metadata
            .insert("composite_ms".into(), format!("{composite_ms:.4}"));
        match &args.background {
            Some(background) => frame.write_png_over(out, background)?,
            None => frame.write(out, lacuna::frame::FrameFormat::from_path(out)?)?,
        }
        say!("wrote {}", out.display());
    }
    Ok(validation_verdict(&part.ctx))
}
