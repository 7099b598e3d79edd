//! Clip planes and a crop box: what of the volume a frame keeps.

use super::parse::numbers;
use crate::error::{Error, Result};

/// Clip planes a frame can have.
pub const MAX_CLIP: usize = 6;

/// What of the volume a frame keeps: up to six half-spaces and a box, in
/// voxel coordinates (the volume box is `[0, dims]`). They cut each ray's
/// interval before any structure is traversed; the sample lattice stays the
/// volume's (`t_k = t_enter + k dt` from the box entry).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clip {
    planes: [[f32; 4]; MAX_CLIP],
    count: usize,
    crop: Option<[[f32; 3]; 2]>,
}

impl Clip {
    /// Keeps `a x + b y + c z + d >= 0`.
    pub fn plane(mut self, plane: [f32; 4]) -> Result<Clip> {
        let shown = plane.map(|v| v.to_string()).join(",");
        if !plane.iter().all(|v| v.is_finite()) {
            return Err(Error::invalid("clip", shown, "must be four finite numbers A,B,C,D"));
        }
        if plane[..3] == [0.0; 3] {
            return Err(Error::invalid("clip", shown, "the normal (A, B, C) is zero"));
        }
        if self.count == MAX_CLIP {
            return Err(Error::invalid("clip", shown, format!("at most {MAX_CLIP} clip planes")));
        }
        self.planes[self.count] = plane;
        self.count += 1;
        Ok(self)
    }

    /// Keeps the box `[lo, hi]` (voxel coordinates; a zero thickness keeps
    /// nothing).
    pub fn crop(mut self, lo: [f32; 3], hi: [f32; 3]) -> Result<Clip> {
        let shown = format!("{}:{},{}:{},{}:{}", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
        if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
            return Err(Error::invalid("crop", shown, "must be finite"));
        }
        if (0..3).any(|a| lo[a] > hi[a]) {
            return Err(Error::invalid("crop", shown, "is inverted (each axis needs LO <= HI)"));
        }
        self.crop = Some([lo, hi]);
        Ok(self)
    }

    /// Adds `--clip A,B,C,D`.
    pub fn parse_plane(self, s: &str) -> Result<Clip> {
        let v = numbers("clip", s, 4, &[','], "A,B,C,D (keeps A x + B y + C z + D >= 0)")?;
        self.plane([v[0], v[1], v[2], v[3]])
    }

    /// Sets `--crop X0:X1,Y0:Y1,Z0:Z1`.
    pub fn parse_crop(self, s: &str) -> Result<Clip> {
        let v = numbers("crop", s, 6, &[',', ':'], "X0:X1,Y0:Y1,Z0:Z1 in voxels")?;
        if s.matches(':').count() != 3 {
            return Err(Error::invalid("crop", s, "expected X0:X1,Y0:Y1,Z0:Z1 in voxels"));
        }
        self.crop([v[0], v[2], v[4]], [v[1], v[3], v[5]])
    }

    pub fn planes(&self) -> &[[f32; 4]] {
        &self.planes[..self.count]
    }

    pub fn crop_box(&self) -> Option<[[f32; 3]; 2]> {
        self.crop
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0 && self.crop.is_none()
    }

    /// A crop box that misses a volume of `dims` voxels is an error.
    pub(crate) fn check_for(&self, dims: [u32; 3]) -> Result<()> {
        if let Some([lo, hi]) = self.crop {
            if (0..3).any(|a| hi[a] < 0.0 || lo[a] > dims[a] as f32) {
                return Err(Error::invalid(
                    "crop",
                    format!("{}:{},{}:{},{}:{}", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]),
                    format!(
                        "lies outside the volume [0, {}] x [0, {}] x [0, {}]",
                        dims[0], dims[1], dims[2]
                    ),
                ));
            }
        }
        Ok(())
    }
}
