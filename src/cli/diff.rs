//! `lacuna diff`: compare two EXR frames (exit 1 past --max-abs).

use clap::Args;
use lacuna::frame::diff::{diff, write_heatmap, DepthDiff};
use lacuna::frame::Frame;
use lacuna::{Error, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct DiffArgs {
    a: PathBuf,
    b: PathBuf,
    /// Fail (exit 1) when the max abs difference of a colour channel, or of
    /// both frames' depth (Z), exceeds this (0: any difference).
    #[arg(long, allow_hyphen_values = true)]
    max_abs: Option<f64>,
    /// Write a PNG heatmap of per-pixel differences.
    #[arg(long)]
    heatmap: Option<PathBuf>,
}

pub fn run(args: &DiffArgs) -> Result<ExitCode> {
    if let Some(m) = args.max_abs {
        if m.is_nan() || m < 0.0 {
            return Err(Error::invalid("max-abs", m.to_string(), "must be a number >= 0"));
        }
    }
    if let Some(path) = &args.heatmap {
        let png = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !png {
            return Err(Error::invalid(
                "heatmap",
                path.display().to_string(),
                "a heatmap is a PNG: name it .png",
            ));
        }
        super::check_parent(path)?;
    }
    let a = Frame::read_exr(&args.a)?;
    let b = Frame::read_exr(&args.b)?;
    let stats = diff(&a, &b)?;
    say!("{stats}");
    if let Some(path) = &args.heatmap {
        write_heatmap(&a, &b, path, None)?;
        say!("wrote {}", path.display());
    }
    if let Some(m) = args.max_abs {
        if stats.max_abs > m {
            say_err!("error: max_abs {:.6e} exceeds --max-abs {m}", stats.max_abs);
            return Ok(ExitCode::from(1));
        }
        // The depth, in its own units, by the same bound (0: bit for bit).
        // A depth in one frame only (a viewer's screenshot against
        // render's iso frame) was named above.
        if let DepthDiff::Both { max_abs, differing } = stats.depth {
            if max_abs > m || (m == 0.0 && differing > 0) {
                say_err!("error: the depth (Z) differs by {max_abs:.6e} at {differing} pixels, past --max-abs {m}");
                return Ok(ExitCode::from(1));
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
