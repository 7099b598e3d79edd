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
        // Not an Io error: `optional` skips a missing volume, not a
        // missing transfer function file.
        Some(spec) => TransferFunction::parse_channels(spec)
            .map_err(|e| Error::invalid("transfer function", spec, e.to_string()))?,
        None => volume.default_transfer_function()?,
    };
    tf.check_channels(volume.channel_count())?;
    Ok(Loaded {
        spec: label,
        tf,
        volume,
    })
}
