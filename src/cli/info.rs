//! `lacuna info`: a volume's dims, type, values, and occupancy under a TF.

use super::{context, tf_for, VolumeArgs};
use clap::Args;
use lacuna::error::number;
use lacuna::volume::{BrickGrid, PoolLayout, Storage, BRICK, POOL_BRICK};
use lacuna::{Result, TransferFunction, Volume};
use std::process::ExitCode;

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Transfer function for occupancy (default: the generator's, if any).
    /// Several channels: one --tf per channel in order, or one for all.
    #[arg(long)]
    tf: Vec<TransferFunction>,
}

pub fn run(args: &InfoArgs) -> Result<ExitCode> {
    let series = args.volume.series()?;
    let v = series.load(args.volume.time, None)?;
    // Checked before the report, so a bad --tf is one error line.
    let tf = tf_for(&args.tf, &v)?;
    say!("volume   {}", v.name);
    if let Some(step) = args.volume.step_line(&series) {
        say!("time     {step}; every step normalised as step 0");
    }
    if let Some(note) = series.norm_note() {
        say_err!("note: {note}");
    }
    say!(
        "dims     {}x{}x{} ({} voxels)",
        v.dims[0],
        v.dims[1],
        v.dims[2],
        v.voxel_count()
    );
    say!("spacing  {} x {} x {}", v.spacing[0], v.spacing[1], v.spacing[2]);
    let many = v.channel_count() > 1;
    if !many {
        describe_values(&v, "");
    }
    // What --storage (auto by default) resolves to on this device (the
    // pool's slot grid follows its 3D image limit); with dense, what bricks
    // of the default edge would keep, where they fit the volume.
    match context(false) {
        Ok(ctx) => {
            let limits = lacuna::volume::PoolLimits::of(ctx.info());
            let asked = args.volume.storage;
            let device = &ctx.info().name;
            match lacuna::volume::resolve_storage(&ctx, &v, asked) {
                Storage::Bricks { edge } => match PoolLayout::of_volume(&v, edge, limits) {
                    Ok(pool) => say!("storage  {} (--storage {asked}, on {device})", pool.stats()),
                    Err(e) => say!("storage  --storage {asked} does not fit {device}: {e}"),
                },
                _ => {
                    // Asked for, dense must fit the device (auto checked it).
                    match lacuna::volume::check_dense(ctx.info(), &v) {
                        Ok(_) => say!("storage  dense (--storage {asked}, on {device})"),
                        Err(e) => say!("storage  --storage {asked} does not fit {device}: {e}"),
                    }
                    if let Ok(pool) = PoolLayout::of_volume(&v, POOL_BRICK, limits) {
                        say!("         {} (with --storage {})", pool.stats(), Storage::BRICKS);
                    }
                }
            }
        }
        Err(e) => say!("storage  not planned: {e}"),
    }
    let total = v.voxel_count() as f64;
    match many {
        false => histogram(&v, ""),
        true => {
            for (c, channel) in v.channels().enumerate() {
                say!("channel {} of {}: {}", c + 1, v.channel_count(), v.channel_name(c));
                describe_values(channel, "  ");
                histogram(channel, "  ");
            }
        }
    }
    if let Some(tf) = tf {
        // Visible where any channel's transfer function shows its value.
        let visible = (0..v.data.len())
            .filter(|&i| {
                v.channels().enumerate().any(|(c, ch)| {
                    let n = ch.normalize(ch.data.texel(i));
                    !n.is_nan() && tf.channel(c).lookup(n)[3] > 0.0
                })
            })
            .count();
        let grid = BrickGrid::new(&v, BRICK, lacuna::volume::APRON);
        let active = grid.active(&tf).iter().filter(|a| **a).count();
        say!("tf       {}", tf.spec);
        say!("visible  {:.3} % of voxels (alpha > 0)", 100.0 * visible as f64 / total);
        say!(
            "active   {:.3} % of {}^3 bricks ({} of {}, value ranges over a one-voxel apron)",
            100.0 * active as f64 / grid.len() as f64,
            BRICK,
            active,
            grid.len()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The type, value range and no-data counts of one channel, each line
/// after `indent`.
fn describe_values(v: &Volume, indent: &str) {
    say!("{indent}type     {}", v.source_type);
    let d = v.no_data;
    match d.total() == v.voxel_count() {
        true => say!("{indent}values   none (every voxel is no data)"),
        false => say!(
            "{indent}values   {} .. {}",
            number(v.value_range[0]),
            number(v.value_range[1])
        ),
    }
    if d.total() > 0 {
        say!(
            "{indent}no data  {} voxels ({:.3} %): {} NaN, {} +inf, {} -inf (transparent; ranges ignore them)",
            d.total(),
            100.0 * d.total() as f64 / v.voxel_count() as f64,
            d.nan,
            d.pos_inf,
            d.neg_inf
        );
    }
}

/// The histogram of one channel's normalised values, after `indent`.
fn histogram(v: &Volume, indent: &str) {
    let mut bins = [0u64; 10];
    for i in 0..v.data.len() {
        let n = v.normalize(v.data.texel(i));
        if !n.is_nan() {
            bins[((n * 10.0) as usize).min(9)] += 1;
        }
    }
    let total = v.voxel_count() as f64;
    say!("{indent}histogram of normalised values (10 bins, % of voxels):");
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
        say!("{indent}  {}", row.join("  "));
    }
}
