//! Orbit camera (azimuth, elevation about the volume centre; y up) with an
//! orthographic projection fitted to the projected volume box, or a
//! perspective one. Built in physical space as view and projection matrices,
//! whose rays `CameraMatrices` forms (the one way every camera does).

use super::matrices::{orthographic, perspective, CameraMatrices};
use crate::error::{Error, Result};
use glam::{BVec3, DMat4, DVec3, DVec4, UVec3, Vec3};

/// An orbit camera's projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Zoomed so the projected volume box fills the viewport (the paper's setup).
    Orthographic,
    /// Vertical field of view in degrees; `distance` from the volume centre in
    /// units of the box's bounding-sphere radius (None: the sphere just fits;
    /// below 1 the eye can sit inside the volume).
    Perspective { fov_deg: f64, distance: Option<f64> },
}

/// The furthest a perspective eye may sit, in bounding-sphere radii: past
/// it `t` at the volume is so large that a float no longer resolves the
/// step between lattice samples.
pub const MAX_DISTANCE: f64 = 1000.0;

/// Azimuth in [-360, 360] and elevation in [-90, 90] degrees: what names a
/// direction once. Beyond, a value is a mistake (`--camera 1e40,0` would
/// turn by an angle no float can reduce to a turn).
pub fn check_angles(what: &'static str, azimuth_deg: f64, elevation_deg: f64) -> Result<()> {
    if !((-360.0..=360.0).contains(&azimuth_deg) && (-90.0..=90.0).contains(&elevation_deg)) {
        return Err(Error::invalid(
            what,
            format!("{azimuth_deg},{elevation_deg}"),
            "azimuth must be in [-360, 360] and elevation in [-90, 90] degrees",
        ));
    }
    Ok(())
}

/// An orbit about the volume's centre: azimuth about y from +z, elevation
/// above the xz plane, in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    pub projection: Projection,
}

impl Default for Orbit {
    fn default() -> Self {
        Orbit {
            azimuth_deg: 30.0,
            elevation_deg: 20.0,
            projection: Projection::Orthographic,
        }
    }
}

/// (sin, cos) of an angle in degrees, exact at multiples of 90 so
/// axis-aligned views have direction components that are exactly 0.
fn sincos_deg(deg: f64) -> (f64, f64) {
    let quarter = deg / 90.0;
    if quarter.fract() == 0.0 {
        return match (quarter as i64).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        };
    }
    deg.to_radians().sin_cos()
}

impl Orbit {
    /// Parses `AZIMUTH,ELEVATION` in degrees.
    pub fn parse_orbit(s: &str) -> Result<(f64, f64)> {
        let (a, e) = Self::parse_angles(s)?;
        check_angles("camera", a, e)?;
        Ok((a, e))
    }

    fn parse_angles(s: &str) -> Result<(f64, f64)> {
        let bad = || Error::invalid("camera", s, "expected AZIMUTH,ELEVATION in degrees");
        let (a, e) = s.split_once(',').ok_or_else(bad)?;
        let a: f64 = a.trim().parse().map_err(|_| bad())?;
        let e: f64 = e.trim().parse().map_err(|_| bad())?;
        if !a.is_finite() || !e.is_finite() {
            return Err(bad());
        }
        Ok((a, e))
    }

    /// Angles within a turn (`check_angles`); a perspective field of view
    /// in (0, 180) and a distance in [0, `MAX_DISTANCE`] bounding-sphere
    /// radii.
    pub fn validate(&self) -> Result<()> {
        check_angles("camera", self.azimuth_deg, self.elevation_deg)?;
        if let Projection::Perspective { fov_deg, distance } = self.projection {
            if !(fov_deg > 0.0 && fov_deg < 180.0) {
                return Err(Error::invalid(
                    "field of view",
                    fov_deg.to_string(),
                    "must be in (0, 180) degrees",
                ));
            }
            // Fitting the volume in a narrow field puts the eye as far away.
            let fitted = 1.0 / (fov_deg / 2.0).to_radians().sin();
            if distance.is_none() && fitted > MAX_DISTANCE {
                return Err(Error::invalid(
                    "field of view",
                    fov_deg.to_string(),
                    format!(
                        "fits the volume from {fitted:.0} bounding-sphere radii, past the {MAX_DISTANCE} a camera may stand: take a wider field, or --distance"
                    ),
                ));
            }
            if let Some(d) = distance.filter(|d| !(*d >= 0.0 && *d <= MAX_DISTANCE)) {
                return Err(Error::invalid(
                    "camera distance",
                    d.to_string(),
                    format!("must be in [0, {MAX_DISTANCE}] bounding-sphere radii (further, t loses the precision of the sample lattice)"),
                ));
            }
        }
        Ok(())
    }

    pub fn describe(&self) -> String {
        match self.projection {
            Projection::Orthographic => {
                format!("ortho az={} el={}", self.azimuth_deg, self.elevation_deg)
            }
            Projection::Perspective { fov_deg, distance } => format!(
                "persp az={} el={} fov={} distance={}",
                self.azimuth_deg,
                self.elevation_deg,
                fov_deg,
                distance.map_or("fit".to_string(), |d| d.to_string())
            ),
        }
    }

    /// The orbit camera as view and projection matrices (Vulkan clip space)
    /// for a volume of `dims` voxels with `spacing` at `width` x `height`;
    /// the volume's physical box `[0, dims * spacing]` is the world. The frame
    /// forms its rays from these, so a host passing the same matrices to
    /// [`CameraMatrices`] renders the same image bit for bit.
    pub fn matrices(&self, dims: [u32; 3], spacing: [f32; 3], width: u32, height: u32) -> Result<CameraMatrices> {
        self.validate()?;
        let extent = UVec3::from(dims).as_dvec3() * Vec3::from(spacing).as_dvec3();
        let centre = extent * 0.5;
        let radius = centre.length();
        let (sa, ca) = sincos_deg(self.azimuth_deg);
        let (se, ce) = sincos_deg(self.elevation_deg);
        let to_eye = DVec3::new(ce * sa, se, ce * ca);
        // Times -1 (-to_eye would differ in a NaN's sign bit).
        let forward = to_eye * -1.0;
        let right = DVec3::new(ca, 0.0, -sa);
        let up = right.cross(forward);
        let (w, h) = (width as f64, height as f64);
        let (eye, projection) = match self.projection {
            Projection::Orthographic => {
                let mut half = [0.0f64; 2];
                for i in 0..8 {
                    let high = BVec3::new(i & 1 == 1, i >> 1 & 1 == 1, i >> 2 & 1 == 1);
                    let corner = DVec3::select(high, centre, -centre);
                    half[0] = half[0].max(corner.dot(right).abs());
                    half[1] = half[1].max(corner.dot(up).abs());
                }
                let pixel = (2.0 * half[0] / w).max(2.0 * half[1] / h).max(f64::MIN_POSITIVE);
                // The eye plane (where orthographic rays start) a unit in
                // front of the volume, or a radius where the volume is
                // smaller: a unit in front of a 1e-9 box put the rays'
                // origins 1e9 voxels out, where f32 no longer resolves a step.
                let gap = radius + radius.min(1.0);
                let p = orthographic(pixel * w / 2.0, pixel * h / 2.0, 0.0, 2.0 * gap);
                (centre + to_eye * gap, p)
            }
            Projection::Perspective { fov_deg, distance } => {
                let half_fov = (fov_deg / 2.0).to_radians();
                let dist = distance.map_or(radius / half_fov.sin(), |d| d * radius);
                let near = (radius * 1e-3).max(f64::MIN_POSITIVE);
                let p = perspective(half_fov.tan(), w / h, near, dist + 2.0 * radius + 1.0);
                (centre + to_eye * dist, p)
            }
        };
        // World to view: rows right, up, back (view space is right-handed, -z ahead).
        let view = DMat4::from_cols(
            DVec4::new(right.x, up.x, to_eye.x, 0.0),
            DVec4::new(right.y, up.y, to_eye.y, 0.0),
            DVec4::new(right.z, up.z, to_eye.z, 0.0),
            DVec4::new(-right.dot(eye), -up.dot(eye), -to_eye.dot(eye), 1.0),
        );
        Ok(CameraMatrices::new(view, projection))
    }
}
