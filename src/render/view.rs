//! `View`: every input of the march, set through typed functions (camera,
//! size, step, early termination, sample filter), checked as it is set.

use super::matrices::CameraMatrices;
use super::params::{RenderParams, ERT_OFF};
use super::settings::RenderSettings;
use crate::error::{Error, Result};
use crate::volume::{Filter, GpuVolume};

/// One frame's march inputs for one volume. Units: the step is in voxels
/// (the volume box is `[0, dims]` in voxel space, whatever the spacing);
/// early termination is an accumulated alpha in (0, 1]; the camera is in
/// world space (see `CameraMatrices`). The volume's dims, texel
/// normalisation and the LUT size come from the volume and `tf::LUT_SIZE`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    params: RenderParams,
    filter: Filter,
}

impl View {
    /// `camera` at `width` x `height` for `volume`; step 0.5 voxels, early
    /// termination off, the manual sample filter.
    pub fn new(volume: &GpuVolume, camera: &CameraMatrices, width: u32, height: u32) -> Result<Self> {
        let mut params = camera.params(volume.dims, volume.spacing, width, height)?;
        params.march = [0.5, ERT_OFF, volume.norm[0], volume.norm[1]];
        Ok(View {
            params,
            filter: Filter::Manual,
        })
    }

    /// The CLI's view: `settings`' orbit camera, size, step, ERT and filter.
    pub fn orbit(volume: &GpuVolume, settings: &RenderSettings) -> Result<Self> {
        Ok(View {
            params: settings.params(volume.dims, volume.spacing, volume.norm)?,
            filter: settings.filter,
        })
    }

    /// Sample spacing along each ray, in voxels (> 0).
    pub fn step(mut self, voxels: f32) -> Result<Self> {
        if !(voxels.is_finite() && voxels > 0.0) {
            return Err(Error::invalid(
                "step",
                voxels.to_string(),
                "must be a finite number > 0 (voxels)",
            ));
        }
        self.params.march[0] = voxels;
        Ok(self)
    }

    /// Early ray termination at this accumulated alpha in (0, 1]; None: off.
    pub fn ert(mut self, alpha: Option<f32>) -> Result<Self> {
        if let Some(a) = alpha {
            if !(a > 0.0 && a <= 1.0) {
                return Err(Error::invalid("ert", a.to_string(), "must be in (0, 1]"));
            }
        }
        self.params.march[1] = alpha.unwrap_or(ERT_OFF);
        Ok(self)
    }

    /// How samples are reconstructed between voxels (hardware filtering
    /// needs a volume format the device filters linearly).
    pub fn filter(mut self, filter: Filter) -> Self {
        self.filter = filter;
        self
    }

    pub fn size(&self) -> (u32, u32) {
        (self.params.image[0], self.params.image[1])
    }

    pub fn sample_filter(&self) -> Filter {
        self.filter
    }

    /// The shader block this view fills (for the CPU reference).
    pub fn params(&self) -> &RenderParams {
        &self.params
    }
}
