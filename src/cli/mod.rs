//! The command line: one module per command; what they share lives here.

#[macro_use]
pub mod stdout;
pub mod args;
pub mod bench;
pub mod devices;
pub mod diff;
pub mod export;
pub mod info;
pub mod look;
pub mod octree;
#[cfg(feature = "mpi")]
pub mod ranks;
pub mod render;
pub mod scene;
#[cfg(feature = "view")]
pub mod view;

use clap::Args;
pub use lacuna::frame::check_parent;
use lacuna::gpu::{Context, ContextOptions};
use lacuna::volume::{LoadOptions, RawLayout, Series, Storage, VoxelType};
use lacuna::{Result, TransferFunction, Volume};
use std::process::ExitCode;

/// A volume on the command line: a file or a generator spec.
#[derive(Args)]
pub struct VolumeArgs {
    /// A file (.raw, .nrrd, .nhdr, .nii, .nii.gz), a printf pattern of files (run_%04d_64x64x64_float32.raw: a time series) or NAME:SIZE[:PARAM] (menger, nbody, vessels, turbulence, shells).
    pub volume: String,
    /// Dimensions of a raw file whose name does not give them (WxHxD).
    #[arg(long, requires = "voxel_type", value_parser = parse_dims, allow_hyphen_values = true)]
    pub dims: Option<[u32; 3]>,
    /// Voxel type of a raw file: uint8, uint16, int16, float32, float64 (also int8, uint32, int32).
    #[arg(long = "type", id = "voxel_type", value_name = "TYPE", requires = "dims", value_parser = parse_type)]
    pub voxel_type: Option<VoxelType>,
    /// Time step of a series (a file pattern, a NIfTI time axis, or a generator's animation), from 0.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true)]
    pub time: u32,
    /// Voxel storage on the device: dense (one 3D image), bricks (a pool of the bricks that vary and a page table; constant bricks are not stored) or auto (dense while it fits the device's limits).
    #[arg(long, default_value_t = Storage::Auto)]
    pub storage: Storage,
    /// Source values that a transfer function's 0 and 1 stand for, LO:HI (default: step 0's own range), in every step and channel: a series whose step 0 is empty, or volumes that share one TF.
    #[arg(long, value_name = "LO:HI", value_parser = parse_value_range, allow_hyphen_values = true)]
    pub value_range: Option<[f64; 2]>,
}

/// `LO:HI`: two numbers, as `check_value_range` takes them.
pub fn parse_value_range(s: &str) -> Result<[f64; 2]> {
    let bad = || lacuna::Error::invalid("value range", s, "expected LO:HI, two finite numbers with LO below HI");
    let (lo, hi) = s.split_once(':').ok_or_else(bad)?;
    let range = [lo, hi].map(|v| v.trim().parse::<f64>());
    let [Ok(lo), Ok(hi)] = range else { return Err(bad()) };
    lacuna::volume::check_value_range([lo, hi])?;
    Ok([lo, hi])
}

pub fn parse_dims(s: &str) -> Result<[u32; 3]> {
    lacuna::volume::parse_dims(s)
}

pub fn parse_type(s: &str) -> Result<VoxelType> {
    lacuna::volume::parse_type(s)
}

impl VolumeArgs {
    /// Its series (one step unless the spec names several).
    pub fn series(&self) -> Result<Series> {
        Series::open(&self.volume, &self.options())
    }

    /// "step K of N (what)" for a series, None for one volume.
    pub fn step_line(&self, series: &Series) -> Option<String> {
        (series.steps() > 1).then(|| {
            format!(
                "step {} of {} ({})",
                self.time,
                series.steps(),
                series.step_name(self.time)
            )
        })
    }

    fn options(&self) -> LoadOptions {
        LoadOptions {
            raw: self.dims.zip(self.voxel_type).map(|(dims, ty)| RawLayout { dims, ty }),
            value_range: self.value_range,
        }
    }
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
        say_err!("validation: {m}");
    }
    say_err!("error: {} Vulkan validation message(s)", messages.len());
    ExitCode::from(1)
}

/// The transfer functions given (`--tf` once for every channel, or once per
/// channel), else each channel's default (generators have one; a
/// multi-channel volume's channels without one take `ramp:0:1`).
pub fn tf_for(given: &[TransferFunction], volume: &Volume) -> Result<Option<TransferFunction>> {
    let channels = volume.channel_count();
    if given.len() > 1 || (given.len() == 1 && channels > 1) {
        let tf = match given {
            [one] => one.clone(),
            _ => TransferFunction::per_channel(given.to_vec())?,
        };
        tf.check_channels(channels)?;
        return Ok(Some(tf));
    }
    if let [one] = given {
        return Ok(Some(one.clone()));
    }
    if channels == 1 {
        return volume.default_tf.as_deref().map(TransferFunction::parse).transpose();
    }
    volume.default_transfer_function().map(Some)
}
