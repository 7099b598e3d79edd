//! The command line: one module per command; what they share lives here.

pub mod args;
pub mod bench;
pub mod devices;
pub mod diff;
pub mod export;
pub mod info;
pub mod look;
pub mod octree;
pub mod render;
pub mod scene;
#[cfg(feature = "view")]
pub mod view;

use clap::Args;
pub use lacuna::frame::check_parent;
use lacuna::gpu::{Context, ContextOptions, DeviceInfo};
use lacuna::volume::{LoadOptions, RawLayout, VoxelType};
use lacuna::{Result, TransferFunction, Volume};
use std::process::ExitCode;

/// A volume on the command line: a file or a generator spec.
#[derive(Args)]
pub struct VolumeArgs {
    /// A file (.raw, .nrrd, .nhdr, .nii, .nii.gz) or NAME:SIZE[:PARAM] (menger, nbody, vessels, turbulence, shells).
    pub volume: String,
    /// Dimensions of a raw file whose name does not give them (WxHxD).
    #[arg(long, requires = "voxel_type", value_parser = parse_dims)]
    pub dims: Option<[u32; 3]>,
    /// Voxel type of a raw file: uint8, uint16, int16, float32, float64.
    #[arg(long = "type", id = "voxel_type", value_name = "TYPE", requires = "dims", value_parser = parse_type)]
    pub voxel_type: Option<VoxelType>,
}

pub fn parse_dims(s: &str) -> Result<[u32; 3]> {
    lacuna::volume::parse_dims(s)
}

pub fn parse_type(s: &str) -> Result<VoxelType> {
    lacuna::volume::parse_type(s)
}

impl VolumeArgs {
    pub fn load(&self) -> Result<Volume> {
        load_volume(&self.volume, self.dims, self.voxel_type, None)
    }

    /// As `load`, checking the volume's size against `ctx`'s device first.
    pub fn load_for(&self, ctx: &Context) -> Result<Volume> {
        load_volume(&self.volume, self.dims, self.voxel_type, Some(ctx.info()))
    }
}

/// Loads a volume spec; `dims` and `ty` (given together) are a raw file's layout.
pub fn load_volume(
    spec: &str,
    dims: Option<[u32; 3]>,
    ty: Option<VoxelType>,
    device: Option<&DeviceInfo>,
) -> Result<Volume> {
    let raw = match (dims, ty) {
        (Some(dims), Some(ty)) => Some(RawLayout { dims, ty }),
        _ => None,
    };
    Volume::load_within(spec, &LoadOptions { raw }, device)
}

/// A headless context; `validate` adds validation with synchronization validation.
pub fn context(validate: bool) -> Result<Context> {
    let mut options = ContextOptions::from_env();
    options.validation |= validate;
    Context::new(&options)
}

/// Exit 1 after printing every collected validation message, else success.
pub fn validation_verdict(ctx: &Context) -> ExitCode {
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

/// The transfer function given, else the volume's default (generators have one).
pub fn tf_for(spec: Option<&TransferFunction>, volume: &Volume) -> Result<Option<TransferFunction>> {
    match (spec, &volume.default_tf) {
        (Some(tf), _) => Ok(Some(tf.clone())),
        (None, Some(s)) => Ok(Some(TransferFunction::parse(s)?)),
        (None, None) => Ok(None),
    }
}
