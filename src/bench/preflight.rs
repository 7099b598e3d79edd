//! What a config's data sets can be checked for before anything runs,
//! from their specs and headers, no voxel read: a missing file, a time
//! range past the series' end, bricks with the hardware filter, and (from
//! `Series::channels_known`) more transfer functions than channels or a
//! look several channels cannot take. Found minutes into a run, each
//! would throw the data sets already timed away.

use super::config::BenchConfig;
use super::dataset::parse_tf;
use super::series::check_range;
use crate::error::{Error, Result};
use crate::render::{Filter, FrameDesc, Mode};
use crate::volume::{check_one_channel, Series, Storage};

/// Checks every data set of `config` read from `origin`; an error names
/// the file and the data set.
pub fn check(config: &BenchConfig, origin: &str) -> Result<()> {
    for ds in &config.datasets {
        let label = ds.label(config)?;
        let within = |e: Error| Error::format(origin, format!("data set '{label}': {e}"));
        let opened = ds.options().and_then(|o| Series::open(&ds.volume, &o));
        let series = match opened.and_then(|s| s.check_files().map(|_| s)) {
            Ok(s) => s,
            // Skipped with a note when the run reaches it.
            Err(Error::Io { .. }) if ds.optional => continue,
            Err(e) => return Err(within(e)),
        };
        if let Some(range) = ds.time {
            check_range(&series, range).map_err(within)?;
        }
        let desc = ds.look(config).apply(FrameDesc::builder(1, 1))?.build()?;
        if let Some(channels) = series.channels_known() {
            if let Some(spec) = &ds.tf {
                let tf = parse_tf(spec).map_err(within)?;
                tf.check_channels(channels).map_err(within)?;
            }
            if desc.lighting().is_some() || matches!(desc.mode(), Mode::Iso(_)) {
                check_one_channel(channels, "shaded and iso frames").map_err(within)?;
            }
        }
        let bricks = matches!(ds.storage()?, Storage::Bricks { .. });
        if bricks && config.timed_filter()? == Some(Filter::Hardware) {
            return Err(within(Error::invalid(
                "filter",
                "hardware",
                "bricked storage is sampled by the manual filter only; use filter = \"manual\" or another storage",
            )));
        }
    }
    Ok(())
}
