//! Frame comparison: rmse, psnr, max abs difference over all RGBA channels,
//! the same of the depth (`Z`) where both frames have one, and the count of
//! pixels that differ at all; optional PNG heatmap.

use super::Frame;
use crate::error::{Error, Result};
#[cfg(feature = "frames")]
use std::path::Path;

/// How two frames differ, over every pixel's RGBA.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct DiffStats {
    pub rmse: f64,
    /// Peak signal 1.0; infinite for identical frames, minus infinity where
    /// a channel is non-finite in one frame and differs.
    pub psnr: f64,
    pub max_abs: f64,
    /// Pixels where any channel differs, the depth included where both
    /// frames have one (bitwise; NaN equals only itself).
    pub differing: u64,
    pub pixels: u64,
    pub depth: DepthDiff,
}

/// How two frames' depth (`Z`: an iso frame's surface depth) differ.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum DepthDiff {
    /// Neither frame has one.
    Neither,
    /// Both have one: the largest difference (infinite where one is
    /// non-finite and differs) and the pixels whose depth differs.
    Both { max_abs: f64, differing: u64 },
    /// Only the first frame (A) has one.
    OnlyA,
    /// Only the second (B).
    OnlyB,
}

impl std::fmt::Display for DiffStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "rmse {:.6e}  psnr {}  max_abs {:.6e}  differing {} of {} pixels",
            self.rmse,
            // +inf: identical; -inf: a non-finite difference (a NaN or an
            // infinity against a number), the largest there is.
            if self.psnr.is_infinite() {
                format!("{} dB", self.psnr)
            } else {
                format!("{:.2} dB", self.psnr)
            },
            self.max_abs,
            self.differing,
            self.pixels
        )?;
        match self.depth {
            DepthDiff::Neither => Ok(()),
            DepthDiff::Both { max_abs, differing } => {
                write!(
                    f,
                    "\ndepth (Z): max_abs {max_abs:.6e}  differing {differing} of {} pixels",
                    self.pixels
                )
            }
            DepthDiff::OnlyA => write!(f, "\ndepth (Z): only in the first frame"),
            DepthDiff::OnlyB => write!(f, "\ndepth (Z): only in the second frame"),
        }
    }
}

fn channel_diff(a: f32, b: f32) -> f64 {
    if a.to_bits() == b.to_bits() {
        0.0
    } else if a.is_finite() && b.is_finite() {
        (a as f64 - b as f64).abs()
    } else {
        f64::INFINITY
    }
}

/// The largest channel difference of two pixels (infinite where a channel
/// is non-finite in one and differs).
pub fn pixel_diff(a: [f32; 4], b: [f32; 4]) -> f64 {
    (0..4).map(|c| channel_diff(a[c], b[c])).fold(0.0, f64::max)
}

/// Compares two frames of the same size (an error otherwise).
pub fn diff(a: &Frame, b: &Frame) -> Result<DiffStats> {
    a.check()?;
    b.check()?;
    if (a.width, a.height) != (b.width, b.height) {
        return Err(Error::invalid(
            "frames",
            format!("{}x{} vs {}x{}", a.width, a.height, b.width, b.height),
            "sizes differ",
        ));
    }
    let mut sum = 0.0f64;
    let mut max_abs = 0.0f64;
    let mut differing = 0u64;
    let (mut depth_max, mut depth_differing) = (0.0f64, 0u64);
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        let mut any = false;
        for c in 0..4 {
            let d = channel_diff(pa[c], pb[c]);
            any |= pa[c].to_bits() != pb[c].to_bits();
            sum += d * d;
            max_abs = max_abs.max(d);
        }
        if let (Some(za), Some(zb)) = (&a.depth, &b.depth) {
            let differs = za[i].to_bits() != zb[i].to_bits();
            depth_max = depth_max.max(channel_diff(za[i], zb[i]));
            depth_differing += differs as u64;
            any |= differs;
        }
        differing += any as u64;
    }
    let depth = match (&a.depth, &b.depth) {
        (None, None) => DepthDiff::Neither,
        (Some(_), Some(_)) => DepthDiff::Both {
            max_abs: depth_max,
            differing: depth_differing,
        },
        (Some(_), None) => DepthDiff::OnlyA,
        (None, Some(_)) => DepthDiff::OnlyB,
    };
    let n = (a.pixels.len() * 4).max(1) as f64;
    let rmse = (sum / n).sqrt();
    let psnr = if rmse == 0.0 {
        f64::INFINITY
    } else {
        20.0 * (1.0 / rmse).log10()
    };
    Ok(DiffStats {
        rmse,
        psnr,
        max_abs,
        differing,
        pixels: a.pixels.len() as u64,
        depth,
    })
}

/// Writes a PNG of the per-pixel max abs difference: black where equal, then
/// blue to red up to `scale` (default: the frame's max difference).
#[cfg(feature = "frames")]
pub fn write_heatmap(a: &Frame, b: &Frame, path: &Path, scale: Option<f64>) -> Result<()> {
    diff(a, b)?;
    let diffs: Vec<f64> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(pa, pb)| pixel_diff(*pa, *pb))
        .collect();
    let top = scale.unwrap_or_else(|| diffs.iter().cloned().filter(|d| d.is_finite()).fold(0.0, f64::max));
    let mut rgb = Vec::with_capacity(diffs.len() * 3);
    for d in diffs {
        let px = if d == 0.0 {
            [0, 0, 0]
        } else if !d.is_finite() {
            [255, 255, 255]
        } else {
            let t = if top > 0.0 { (d / top).clamp(0.0, 1.0) } else { 1.0 };
            // Non-zero differences are never black, however small.
            let t = 0.15 + 0.85 * t;
            [(255.0 * t) as u8, (64.0 * (1.0 - t)) as u8, (255.0 * (1.0 - t)) as u8]
        };
        rgb.extend_from_slice(&px);
    }
    super::png::write_png8(path, a.width, a.height, ::png::ColorType::Rgb, &rgb, &[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_non_finite_difference_is_the_worst_psnr_and_equal_frames_the_best() {
        let zeros = Frame::new(2, 1, vec![[0.0; 4]; 2]);
        for bad in [f32::NAN, f32::INFINITY] {
            let other = Frame::new(2, 1, vec![[0.0; 4], [bad, 0.0, 0.0, 0.0]]);
            let d = diff(&zeros, &other).unwrap();
            assert_eq!((d.psnr, d.differing), (f64::NEG_INFINITY, 1), "{bad}");
            assert!(d.to_string().contains("psnr -inf dB"), "{d}");
        }
        let d = diff(&zeros, &zeros).unwrap();
        assert!(d.psnr == f64::INFINITY && d.to_string().contains("psnr inf dB"), "{d}");
    }

    #[test]
    fn a_depth_is_compared_where_both_frames_have_one_and_named_where_one_has() {
        let with = |z: [f32; 2]| Frame {
            depth: Some(z.to_vec()),
            ..Frame::new(2, 1, vec![[0.5; 4]; 2])
        };
        let d = diff(&with([1.0, 2.0]), &with([1.0, 7.0])).unwrap();
        assert_eq!(
            (d.differing, d.max_abs, d.depth),
            (
                1,
                0.0,
                DepthDiff::Both {
                    max_abs: 5.0,
                    differing: 1
                }
            )
        );
        assert!(
            d.to_string()
                .contains("depth (Z): max_abs 5.000000e0  differing 1 of 2 pixels"),
            "{d}"
        );
        let plain = Frame::new(2, 1, vec![[0.5; 4]; 2]);
        let d = diff(&plain, &with([1.0, 2.0])).unwrap();
        assert_eq!((d.differing, d.depth), (0, DepthDiff::OnlyB));
        assert!(d.to_string().contains("depth (Z): only in the second frame"), "{d}");
    }
}
