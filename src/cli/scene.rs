//! `lacuna scene`: generate an SPD surface scene, print its counts, write NFF.

use super::check_parent;
use clap::Args;
use lacuna::scene::{Scene, SpdScene};
use lacuna::Result;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct SceneArgs {
    /// balls, gears, lattice, mount, rings, teapot, tetra or tree.
    name: SpdScene,
    /// SPD size factor (default: the SPD's default size).
    #[arg(long)]
    size: Option<u32>,
    /// Write the scene in NFF.
    #[arg(long)]
    nff: Option<PathBuf>,
}

pub fn run(args: &SceneArgs) -> Result<ExitCode> {
    let kind = args.name;
    if let Some(path) = &args.nff {
        check_parent(path)?;
    }
    let scene = Scene::generate(kind, args.size)?;
    let b = scene.bounds();
    say!("{} (size factor {}): {}", kind, scene.size_factor, scene.counts());
    say!(
        "bounds: [{:.4}, {:.4}, {:.4}] - [{:.4}, {:.4}, {:.4}]; {} lights",
        b.lo[0],
        b.lo[1],
        b.lo[2],
        b.hi[0],
        b.hi[1],
        b.hi[2],
        scene.lights.len()
    );
    if let Some(path) = &args.nff {
        scene.write_nff(path)?;
        say!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}
