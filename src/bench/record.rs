//! One record per benchmark run (a data set x structure), and one per point
//! of the speed-against-error sweep: what `results.json` and `error.json` hold.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Setup {
    pub config: String,
    pub device: String,
    pub driver: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    pub step: f32,
    pub camera: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FrameTimes {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

impl FrameTimes {
    pub fn of(mut ms: Vec<f64>) -> Self {
        ms.sort_by(f64::total_cmp);
        let n = ms.len();
        let median = if n == 0 {
            f64::NAN
        } else if n % 2 == 1 {
            ms[n / 2]
        } else {
            (ms[n / 2 - 1] + ms[n / 2]) / 2.0
        };
        FrameTimes {
            median_ms: median,
            min_ms: *ms.first().unwrap_or(&f64::NAN),
            max_ms: *ms.last().unwrap_or(&f64::NAN),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ImageError {
    pub rmse: f64,
    /// Infinite psnr is written as null.
    pub psnr: Option<f64>,
    pub max_abs: f64,
    pub differing: u64,
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
    pub build_ms: f64,
    pub nodes: u64,
    pub leaves: u64,
    /// Nodes on the longest root-to-leaf path (the paper's Table 1 height).
    pub tree_height: u32,
    pub bytes: u64,
    pub frame: FrameTimes,
    pub fps: f64,
    /// Frame 0 against naive marching's frame 0 (0 for every exact structure).
    pub error_vs_naive: ImageError,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ErrorPoint {
    #[serde(flatten)]
    pub setup: Setup,
    pub dataset: String,
    pub accel: String,
    pub sweep_step: f32,
    /// Early termination threshold; null = off.
    pub ert: Option<f32>,
    pub frame: FrameTimes,
    pub reference_step: f32,
    pub error: ImageError,
}
