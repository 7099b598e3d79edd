//! A camera as a host engine has it: view and projection matrices in Vulkan
//! clip space, and where the volume sits in the world. This is the one place
//! rays are formed; the CLI's orbit cameras come here too (`Orbit::matrices`).
//!
//! Conventions (Vulkan): clip x right, y down, depth 0 at the near plane and 1
//! at the far one (`reverse_z`: 1 near, 0 far); pixel (x, y) of a W x H image
//! has its centre at NDC ((x + 0.5) 2/W - 1, (y + 0.5) 2/H - 1). World space
//! is the volume's physical space placed by `model` (identity: the volume's
//! box is `[0, dims * spacing]`); voxel space divides that by the spacing.
//!
//! Rays, computed in f64 and handed to the shaders in f32 voxel space:
//! - perspective (the projection's last row is not (0, 0, 0, 1)): rays start at
//!   the view-space origin (the eye) and pass through the pixel centres on a
//!   plane of constant clip w, as far from the eye as the volume's origin
//!   (not the near plane), so their directions keep f32's precision at any
//!   scale;
//! - orthographic: rays start on the view-space plane z = 0 (the eye plane)
//!   and run from the near towards the far plane.
//!
//! The volume is marched from where a ray enters it (never behind its start)
//! to where it leaves; the near and far planes do not clip it, a depth image
//! does (`HostDepth`).

use super::Rays;
use crate::error::{Error, Result};
use glam::{DMat4, DVec2, DVec3, DVec4, Mat4, Vec3};

/// A host's camera (see the module documentation for the conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMatrices {
    /// World to view space.
    pub view: DMat4,
    /// View to Vulkan clip space.
    pub projection: DMat4,
    /// The volume's physical space (box `[0, dims * spacing]`) to world space.
    pub model: DMat4,
    /// Depth 1 at the near plane and 0 at the far one.
    pub reverse_z: bool,
}

/// A Vulkan orthographic projection (y down, depth 0..1 from `near` to
/// `far`) of the view-space box `[-half_w, half_w] x [-half_h, half_h]`
/// looking down -z.
pub fn orthographic(half_w: f64, half_h: f64, near: f64, far: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(1.0 / half_w, 0.0, 0.0, 0.0),
        DVec4::new(0.0, -1.0 / half_h, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 1.0 / (near - far), 0.0),
        DVec4::new(0.0, 0.0, near / (near - far), 1.0),
    )
}

/// A Vulkan perspective projection (y down, depth 0..1 from `near` to
/// `far`) with `tan_half_fov` the tangent of half the vertical field of view
/// and `aspect` width / height, looking down -z.
pub fn perspective(tan_half_fov: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(1.0 / (tan_half_fov * aspect), 0.0, 0.0, 0.0),
        DVec4::new(0.0, -1.0 / tan_half_fov, 0.0, 0.0),
        DVec4::new(0.0, 0.0, far / (near - far), -1.0),
        DVec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    )
}

fn finite(m: &DMat4) -> bool {
    m.to_cols_array().iter().all(|v| v.is_finite())
}

impl CameraMatrices {
    /// A camera with the volume's physical box at the world origin (`model`
    /// identity) and standard depth (`reverse_z` false).
    pub fn new(view: DMat4, projection: DMat4) -> Self {
        CameraMatrices {
            view,
            projection,
            model: DMat4::IDENTITY,
            reverse_z: false,
        }
    }

    /// As `new`, from an engine's f32 matrices.
    pub fn from_f32(view: Mat4, projection: Mat4) -> Self {
        Self::new(view.as_dmat4(), projection.as_dmat4())
    }

    /// Places the volume's physical box in the world.
    pub fn with_model(mut self, model: DMat4) -> Self {
        self.model = model;
        self
    }

    /// Marks the projection as reverse-Z (depth 1 near, 0 far).
    pub fn with_reverse_z(mut self, reverse_z: bool) -> Self {
        self.reverse_z = reverse_z;
        self
    }

    pub fn is_perspective(&self) -> bool {
        self.projection.row(3) != DVec4::W
    }

    /// The inverses the rays need: clip to view, view to world, world to
    /// physical volume space; an error names a singular matrix.
    fn inverses(&self) -> Result<(DMat4, DMat4, DMat4)> {
        let inverse = |m: &DMat4, what: &'static str| {
            let inv = m.inverse();
            if finite(m) && finite(&inv) && m.determinant() != 0.0 {
                Ok(inv)
            } else {
                Err(Error::invalid(what, format!("{m:?}"), "must be finite and invertible"))
            }
        };
        let model_inv = if self.model == DMat4::IDENTITY {
            DMat4::IDENTITY
        } else {
            inverse(&self.model, "model matrix")?
        };
        Ok((
            inverse(&self.projection, "projection matrix")?,
            inverse(&self.view, "view matrix")?,
            model_inv,
        ))
    }

    /// Finite, invertible matrices.
    pub fn validate(&self) -> Result<()> {
        self.inverses().map(|_| ())
    }

    /// The rays (and the depth unprojection) in the voxel space of a volume
    /// with `spacing`, rendered at `width` x `height`.
    pub fn rays(&self, spacing: [f32; 3], width: u32, height: u32) -> Result<Rays> {
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "size",
                format!("{width}x{height}"),
                "width and height must be > 0",
            ));
        }
        let (clip_to_view, view_to_world, world_to_model) = self.inverses()?;
        let spacing = Vec3::from(spacing).as_dvec3();
        let identity = self.model == DMat4::IDENTITY;
        // World to voxel space (the model's inverse skipped when it is the
        // identity, so exact zeros stay exact).
        let to_voxel_point = |p: DVec3| {
            let p = if identity {
                p
            } else {
                world_to_model.transform_point3(p)
            };
            (p / spacing).as_vec3()
        };
        let to_voxel_vector = |v: DVec3| {
            let v = if identity {
                v
            } else {
                world_to_model.transform_vector3(v)
            };
            (v / spacing).as_vec3()
        };
        let unproject = |ndc: DVec2, z: f64| {
            let h = clip_to_view * ndc.extend(z).extend(1.0);
            h.truncate() / h.w
        };
        let (near_z, far_z) = if self.reverse_z { (1.0, 0.0) } else { (0.0, 1.0) };
        let (w, h) = (width as f64, height as f64);
        let corners = [DVec2::new(-1.0, -1.0), DVec2::new(1.0, -1.0), DVec2::new(-1.0, 1.0)];
        let v3 = |p: Vec3| p.to_array();
        let mut rays = Rays::orthographic([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
        if self.is_perspective() {
            let w_row = self.projection.row(3).truncate();
            let eye = view_to_world.transform_point3(DVec3::ZERO);
            // The pixel's ray (through the view origin) at clip w = `depth`:
            // the w of a point as far from the eye as the volume's origin
            // (1 where that is the eye), so in voxel space the points stand
            // as far from the eye as the eye from the origin, at any scale
            // of spacing, model or view. At w = 1 a volume of 1e7 units a
            // voxel put every point within the eye's rounding, and no ray
            // had a direction.
            let origin = self.view.transform_point3(self.model.transform_point3(DVec3::ZERO));
            let depth = Some(origin.length() * w_row.length())
                .filter(|d| d.is_normal())
                .unwrap_or(1.0);
            let unit = |ndc: DVec2| {
                let a = unproject(ndc, near_z);
                a * (depth / w_row.dot(a))
            };
            let [c0, c1, c2] = corners.map(unit);
            rays.base = v3(to_voxel_point(view_to_world.transform_point3(c0)));
            rays.du = v3(to_voxel_vector(view_to_world.transform_vector3((c1 - c0) / w)));
            rays.dv = v3(to_voxel_vector(view_to_world.transform_vector3((c2 - c0) / h)));
            rays.eye_or_dir = v3(to_voxel_point(eye));
            rays.perspective = true;
        } else {
            // The pixel's ray (near to far) and where it crosses view z = 0.
            let origin = |ndc: DVec2| {
                let a = unproject(ndc, near_z);
                let b = unproject(ndc, far_z);
                let d = b - a;
                (a - d * (a.z / d.z), d)
            };
            let [(c0, dir), (c1, _), (c2, _)] = corners.map(origin);
            rays.base = v3(to_voxel_point(view_to_world.transform_point3(c0)));
            rays.du = v3(to_voxel_vector(view_to_world.transform_vector3((c1 - c0) / w)));
            rays.dv = v3(to_voxel_vector(view_to_world.transform_vector3((c2 - c0) / h)));
            // The f32 direction normalised in f64: divided by the length
            // (not times its reciprocal, as glam's normalize() does).
            let d = to_voxel_vector(view_to_world.transform_vector3(dir / dir.length())).as_dvec3();
            rays.eye_or_dir = v3((d / d.length()).as_vec3());
        }
        let finite_rays = [rays.base, rays.du, rays.dv, rays.eye_or_dir]
            .iter()
            .flatten()
            .all(|v| v.is_finite());
        if !finite_rays {
            return Err(Error::invalid(
                "camera",
                "view and projection matrices",
                format!("form no finite rays for a volume of spacing {spacing}: degenerate matrices, or a spacing f32 cannot hold"),
            ));
        }
        // NDC (with depth) to voxel space, for rays that end at a host depth.
        let mut world_to_voxel = DMat4::from_scale(1.0 / spacing);
        if !identity {
            world_to_voxel *= world_to_model;
        }
        let ndc_to_voxel = world_to_voxel * view_to_world * clip_to_view;
        rays.ndc_to_voxel = ndc_to_voxel.as_mat4().to_cols_array_2d();
        rays.voxel_to_ndc = Some(ndc_to_voxel.inverse().as_mat4().to_cols_array_2d());
        rays.far_depth = far_z as f32;
        Ok(rays)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The centre pixel's ray direction and its point's distance from the eye, in voxel space.
    fn centre_ray(m: &CameraMatrices, spacing: f32) -> (Vec3, f32) {
        let r = m.rays([spacing; 3], 2, 2).unwrap();
        let (base, du, dv, eye) = (
            Vec3::from(r.base),
            Vec3::from(r.du),
            Vec3::from(r.dv),
            Vec3::from(r.eye_or_dir),
        );
        let along = base + du + dv - eye;
        (along / along.length(), along.length())
    }

    #[test]
    fn perspective_rays_keep_their_direction_at_any_scale_of_spacing_model_or_view() {
        let projection = perspective(0.5, 1.0, 0.1, 1e3);
        let look = |eye: DVec3, at: DVec3| glam::dcamera::rh::view::look_at_mat4(eye, at, DVec3::Y);
        let eye = DVec3::new(40.0, 25.0, 60.0);
        let at = DVec3::splat(8.0);
        let unit = CameraMatrices::new(look(eye, at), projection);
        let (dir, _) = centre_ray(&unit, 1.0);
        for k in [1e-10, 1e-3, 1e3, 1e7, 1e25] {
            // The same scene in physical units k times larger, by the
            // spacing, by a model scale, and by both.
            let far = CameraMatrices::new(look(eye * k, at * k), projection);
            let scaled = far.with_model(DMat4::from_scale(DVec3::splat(k)));
            let both = CameraMatrices::new(look(eye * k * k, at * k * k), projection)
                .with_model(DMat4::from_scale(DVec3::splat(k)));
            for (what, m, spacing) in [("spacing", far, k), ("model", scaled, 1.0), ("both", both, k)] {
                let (d, apart) = centre_ray(&m, spacing as f32);
                assert!(d.abs_diff_eq(dir, 1e-5), "{what} x {k}: {d} against {dir}");
                // As far from the eye as the eye from the origin (74 voxels).
                assert!(apart > 10.0, "{what} x {k}: the point is {apart} voxels from the eye");
            }
        }
    }
}
