//! The rays of a frame in voxel space, as a camera makes them.

use crate::error::{Error, Result};

/// Rays in voxel space (the volume box is `[0, dims]`, voxel i centred at
/// i + 0.5): pixel (x, y) passes through `base + (x + 0.5) du + (y + 0.5) dv`;
/// orthographic rays start there along `eye_or_dir`, perspective rays start
/// at the eye `eye_or_dir` and pass there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rays {
    pub base: [f32; 3],
    pub du: [f32; 3],
    pub dv: [f32; 3],
    pub eye_or_dir: [f32; 3],
    pub perspective: bool,
    /// NDC (x, y, depth, 1) to homogeneous voxel space: unprojects a host depth.
    pub ndc_to_voxel: [[f32; 4]; 4],
    /// The depth of the far plane (where a host depth image has nothing).
    pub far_depth: f32,
    /// Voxel space to NDC, where the camera has one (host matrices): where
    /// iso frames write their surface depth.
    pub voxel_to_ndc: Option<[[f32; 4]; 4]>,
}

impl Rays {
    /// Orthographic rays along `dir` (not normalised: the shaders do)
    /// starting at pixel (0, 0)'s corner `base`.
    pub fn orthographic(base: [f32; 3], du: [f32; 3], dv: [f32; 3], dir: [f32; 3]) -> Rays {
        Rays {
            base,
            du,
            dv,
            eye_or_dir: dir,
            perspective: false,
            ndc_to_voxel: [[0.0; 4]; 4],
            far_depth: 0.0,
            voxel_to_ndc: None,
        }
    }

    pub(super) fn validate(&self) -> Result<()> {
        let finite = [self.base, self.du, self.dv, self.eye_or_dir]
            .iter()
            .flatten()
            .all(|v| v.is_finite());
        if !finite {
            return Err(Error::invalid("rays", format!("{self:?}"), "must be finite"));
        }
        // Every ray needs a direction: an orthographic one along a nonzero
        // vector; a perspective one from an eye off the pixels' plane (in
        // f64: the plane's normal underflows f32 at small steps).
        let v = |a: [f32; 3]| a.map(f64::from);
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let normal = cross(v(self.du), v(self.dv));
        let to_eye: [f64; 3] = std::array::from_fn(|a| v(self.eye_or_dir)[a] - v(self.base)[a]);
        let why = if !self.perspective && dot(v(self.eye_or_dir), v(self.eye_or_dir)) == 0.0 {
            Some("an orthographic direction must not be zero")
        } else if self.perspective && dot(normal, normal) > 0.0 && dot(normal, to_eye) == 0.0 {
            Some("a perspective eye must not lie in the pixels' plane")
        } else {
            None
        };
        match why {
            Some(why) => Err(Error::invalid(
                "rays",
                format!(
                    "du {:?} dv {:?} eye or direction {:?}",
                    self.du, self.dv, self.eye_or_dir
                ),
                why,
            )),
            None => Ok(()),
        }
    }
}
