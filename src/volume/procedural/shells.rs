//! Thin concentric spherical shells about the volume centre, each with its own
//! value, about two voxels thick at any size. Over time they expand, a
//! quarter of their spacing a step, and the outermost re-enters at the
//! centre.

use std::ops::Range;

/// Layers `layers` (z) of the volume, x fastest.
pub fn generate(dims: [u32; 3], count: u32, time: u32, layers: Range<u32>) -> Vec<u8> {
    let centre = dims.map(|d| d as f32 / 2.0);
    let radius = 0.45 * dims.into_iter().min().unwrap_or(1) as f32;
    let half_thickness = (radius * 0.01).max(1.0);
    super::fill(dims, layers, |x, y, z| {
        let p = [x, y, z].map(|c| c as f32 + 0.5);
        let r = (0..3).map(|a| (p[a] - centre[a]).powi(2)).sum::<f32>().sqrt();
        let mut best = 0.0f32;
        for i in 0..count {
            let phase = (i as f32 + 0.25 * time as f32) % count as f32 + 1.0;
            let ri = radius * phase / count as f32;
            let profile = (1.0 - (r - ri).abs() / half_thickness).max(0.0);
            let peak = 0.4 + 0.6 * (i + 1) as f32 / count as f32;
            best = best.max(profile * peak);
        }
        (best * 255.0).round() as u8
    })
}
