//! What a frame is rendered with: size, camera, step, early termination and
//! the sample filter.

use super::camera::Camera;
use super::params::{RenderParams, ERT_OFF};
use crate::error::{Error, Result};
use crate::volume::Filter;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    /// Sample spacing along the ray, in voxels.
    pub step: f32,
    /// Early ray termination at this accumulated alpha (None: off).
    pub ert: Option<f32>,
    /// How samples are reconstructed between voxels. The default is manual,
    /// exact on every device; `GpuVolume::default_filter` gives the faster.
    pub filter: Filter,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 1024,
            height: 1024,
            camera: Camera::default(),
            step: 0.5,
            ert: None,
            filter: Filter::Manual,
        }
    }
}

/// Parses `WxH` (both > 0).
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = |why: &str| Error::invalid("size", s, why.to_string());
    let (w, h) = s.split_once('x').ok_or_else(|| bad("expected WxH"))?;
    let w: u32 = w.trim().parse().map_err(|_| bad("expected WxH with integers"))?;
    let h: u32 = h.trim().parse().map_err(|_| bad("expected WxH with integers"))?;
    if w == 0 || h == 0 {
        return Err(bad("width and height must be > 0"));
    }
    Ok((w, h))
}

impl RenderSettings {
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(
                "size",
                format!("{}x{}", self.width, self.height),
                "width and height must be > 0",
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(Error::invalid(
                "step",
                self.step.to_string(),
                "must be a finite number > 0 (voxels)",
            ));
        }
        // The frame buffer's readback and the frame itself.
        crate::limits::check_host(
            format_args!("frame {}x{}", self.width, self.height),
            self.width as u64 * self.height as u64,
            32,
        )?;
        if let Some(e) = self.ert {
            if !(e > 0.0 && e <= 1.0) {
                return Err(Error::invalid("ert", e.to_string(), "must be in (0, 1]"));
            }
        }
        Ok(())
    }

    /// Full shader parameters for a volume.
    pub fn params(&self, dims: [u32; 3], spacing: [f32; 3], norm: [f32; 2]) -> Result<RenderParams> {
        self.validate()?;
        crate::limits::check_samples_per_ray(dims, self.step)?;
        let mut p = self.camera.params(dims, spacing, self.width, self.height)?;
        p.march = [self.step, self.ert.unwrap_or(ERT_OFF), norm[0], norm[1]];
        Ok(p)
    }
}
