//! A bench data set loaded: its volume (step FIRST of a series) and its
//! transfer function, one per channel.

use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use crate::tf::TransferFunction;
use crate::volume::{Series, Storage};
use crate::Volume;

pub struct Loaded {
    /// The data set's label (`DatasetConfig::label`).
    pub spec: String,
    pub volume: Volume,
    pub tf: TransferFunction,
}

/// The data set: its step `time` when it is a series.
pub fn load(
    (storage, device): (Storage, &DeviceInfo),
    series: &Series,
    time: Option<[u32; 2]>,
    label: String,
    tf: Option<&str>,
) -> Result<Loaded> {
    let volume = series.load_stored(time.map_or(0, |[first, _]| first), storage, device, None)?;
    let tf = match tf {
        Some(spec) => parse_tf(spec)?,
        None => volume.default_transfer_function()?,
    };
    tf.check_channels(volume.channel_count())?;
    Ok(Loaded {
        spec: label,
        tf,
        volume,
    })
}

/// A data set's `tf`; a file it cannot read is an invalid transfer
/// function, not an I/O error: `optional` skips a missing volume, not a
/// missing transfer function file.
pub fn parse_tf(spec: &str) -> Result<TransferFunction> {
    TransferFunction::parse_channels(spec).map_err(|e| match e {
        Error::Io { .. } => Error::invalid("transfer function", spec, e.to_string()),
        e => e,
    })
}
