//! One record per benchmark run (a data set x structure), and one per point
//! of the speed-against-error sweep: what `results.json` and `error.json` hold.

use crate::gpu::timings::median;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The run a record belongs to: config, device, frame size and protocol.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Setup {
    pub config: String,
    pub device: String,
    pub driver: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    /// Least warm-up frames (and builds) per structure.
    pub warmup: u32,
    pub warmup_cap: u32,
    /// Timed rounds per view (frames) and per structure (builds).
    pub rounds: u32,
    pub step: f32,
    /// Early ray termination threshold of the timed frames; null = off.
    pub timed_ert: Option<f32>,
    pub camera: String,
    /// The measured cost model (`accel::cost`), when a structure collapses
    /// leaves by it; null otherwise.
    #[serde(default)]
    pub cost_model: Option<crate::accel::CostModel>,
}

/// Frame times in milliseconds over a record's timed frames.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FrameTimes {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    /// Timed frames behind the figures.
    pub samples: u32,
}

impl FrameTimes {
    pub fn of(ms: Vec<f64>) -> Self {
        let min = ms.iter().cloned().fold(f64::INFINITY, f64::min);
        let max = ms.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let samples = ms.len() as u32;
        let empty = samples == 0;
        FrameTimes {
            median_ms: median(ms),
            min_ms: if empty { f64::NAN } else { min },
            max_ms: if empty { f64::NAN } else { max },
            samples,
        }
    }
}

/// How a structure's warm-up ended.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Warmup {
    /// Untimed builds run before the timed ones.
    pub builds: u32,
    /// Untimed frames run before the timed ones.
    pub frames: u32,
    /// True when builds or frames stopped at the cap without two
    /// consecutive times agreeing: the figures may include warm-up cost.
    pub capped: bool,
}

/// A frame's error against naive marching's (or a reference's).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ImageError {
    pub rmse: f64,
    /// Infinite psnr is written as null: +inf where nothing differs, -inf
    /// where something does (a non-finite difference).
    pub psnr: Option<f64>,
    pub max_abs: f64,
    pub differing: u64,
}

impl ImageError {
    /// The psnr with `decimals`, or `inf` (identical) / `-inf`.
    pub fn psnr_text(&self, decimals: usize) -> String {
        match self.psnr {
            Some(v) => format!("{v:.decimals$}"),
            // +0 against -0 differs bitwise with an rmse of 0: identical.
            None if self.rmse == 0.0 => "inf".into(),
            None => "-inf".into(),
        }
    }
}

impl From<crate::frame::DiffStats> for ImageError {
    fn from(d: crate::frame::DiffStats) -> Self {
        ImageError {
            rmse: d.rmse,
            psnr: d.psnr.is_finite().then_some(d.psnr),
            max_abs: d.max_abs,
            differing: d.differing,
        }
    }
}

/// One structure on one data set: build, frame times and error
/// (`results.json`, `results.csv`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Record {
    #[serde(flatten)]
    pub setup: Setup,
    pub dataset: String,
    pub dims: [u32; 3],
    pub tf: String,
    /// Voxels with alpha > 0 at their own value, percent.
    pub visible_percent: f64,
    /// 8^3 bricks active under range classification, percent.
    pub active_brick_percent: f64,
    pub structure: String,
    pub accel: String,
    pub params: BTreeMap<String, String>,
    /// Per-volume value ranges this structure reads (ms; 0 for naive and the
    /// k-d trees), computed once per data set.
    pub ranges_ms: f64,
    /// Median per phase over the timed builds (the TF-change path), ms.
    pub build_phases_ms: BTreeMap<String, f64>,
    /// Median, least and most total build time over the timed builds, ms.
    pub build_ms: f64,
    pub build_min_ms: f64,
    pub build_max_ms: f64,
    pub nodes: u64,
    pub leaves: u64,
    /// Nodes on the longest root-to-leaf path (the paper's Table 1 height).
    pub tree_height: u32,
    pub bytes: u64,
    /// Over every view and round.
    pub frame: FrameTimes,
    /// Frames per second at the median frame time.
    pub fps: f64,
    /// Speed-up over naive marching in this run: the median, over every
    /// (view, round), of naive's frame time over this structure's, the two
    /// timed back to back in the same round. 1 for naive.
    pub speedup: f64,
    /// Noise: the largest max/min of one view's frame times over the rounds
    /// (view-to-view differences are the workload, not noise).
    pub frame_spread: f64,
    /// max/min of the timed builds (1 for naive).
    pub build_spread: f64,
    /// True when either spread exceeds 1.5: the machine was too noisy for
    /// these figures to be trusted.
    pub unstable: bool,
    pub warmed_up: Warmup,
    /// Frame 0 against naive marching's frame 0 (0 for every exact structure).
    pub error_vs_naive: ImageError,
    /// Sample filter of the timed frames (manual or hardware).
    #[serde(default = "manual")]
    pub filter: String,
    /// For a structure that chooses another (`auto`): its choice
    /// (`distance (cell 4)`, `naive`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chosen: Option<String>,
}

/// Records written before the filter existed sampled by hand.
fn manual() -> String {
    "manual".into()
}

/// One point of a speed-against-error sweep.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ErrorPoint {
    #[serde(flatten)]
    pub setup: Setup,
    pub dataset: String,
    pub accel: String,
    pub sweep_step: f32,
    /// Early termination threshold; null = off.
    pub ert: Option<f32>,
    /// Sample filter of the point's frames; the reference samples by hand.
    #[serde(default = "manual")]
    pub filter: String,
    /// Jittered samples (the reference is not).
    #[serde(default)]
    pub jitter: bool,
    pub frame: FrameTimes,
    pub reference_step: f32,
    pub error: ImageError,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_reads_inf_only_where_nothing_differs() {
        let error = |psnr, rmse| ImageError {
            rmse,
            psnr,
            max_abs: 0.0,
            differing: 3,
        };
        assert_eq!(error(None, 0.0).psnr_text(2), "inf");
        assert_eq!(error(None, f64::INFINITY).psnr_text(2), "-inf");
        assert_eq!(error(Some(41.234), 0.1).psnr_text(2), "41.23");
        let from = |a: f32| {
            let zeros = crate::frame::Frame::new(1, 1, vec![[0.0; 4]]);
            let other = crate::frame::Frame::new(1, 1, vec![[a, 0.0, 0.0, 0.0]]);
            ImageError::from(crate::frame::diff(&zeros, &other).unwrap()).psnr_text(1)
        };
        assert_eq!(
            (from(f32::NAN), from(0.0), from(-0.0)),
            ("-inf".to_string(), "inf".to_string(), "inf".to_string())
        );
    }
}
