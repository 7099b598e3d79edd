//! The CPU reference's ray geometry: camera rays, the box, clip planes and
//! crop, jitter and depth, each as its GLSL counterpart computes it.

use crate::gpu::shaders::blocks::RenderParams;
use glam::{Mat4, Vec2, Vec3, Vec4};

/// As `intersect_box` in `glsl/common/ray.glsl`.
pub fn intersect_box(org: Vec3, dir: Vec3, lo: Vec3, hi: Vec3) -> (f32, f32) {
    let (mut t0, mut t1) = (-3.4e38f32, 3.4e38f32);
    for a in 0..3 {
        if dir[a] == 0.0 {
            if org[a] < lo[a] || org[a] > hi[a] {
                return (1.0, -1.0);
            }
        } else {
            let inv = 1.0 / dir[a];
            let ta = (lo[a] - org[a]) * inv;
            let tb = (hi[a] - org[a]) * inv;
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    (t0, t1)
}

/// As `pixel_jitter` in `glsl/common/lattice.glsl`.
pub fn pixel_jitter(x: u32, y: u32) -> f32 {
    let mut h = x
        .wrapping_mul(747796405)
        .wrapping_add(y.wrapping_mul(2891336453))
        .wrapping_add(277803737);
    h = ((h >> ((h >> 28) + 4)) ^ h).wrapping_mul(277803737);
    h = (h >> 22) ^ h;
    (h >> 8) as f32 * (1.0 / 16777216.0)
}

/// As `clip_interval` in `glsl/common/lattice.glsl`: the (lo, hi) in t the
/// clip planes and crop box keep.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn clip_interval(p: &RenderParams, org: Vec3, dir: Vec3) -> (f32, f32) {
    let (mut lo, mut hi) = (-3.4e38f32, 3.4e38f32);
    for c in &p.clip[..p.clip_count as usize] {
        let n = Vec3::new(c[0], c[1], c[2]);
        let at = n.dot(org) + c[3];
        let along = n.dot(dir);
        if along == 0.0 {
            if !(at >= 0.0) {
                (lo, hi) = (1.0, -1.0);
            }
        } else {
            let t = -at / along;
            if along > 0.0 {
                lo = lo.max(t);
            } else {
                hi = hi.min(t);
            }
        }
    }
    if p.crop != 0 {
        let (a, b) = intersect_box(org, dir, Vec3::from(p.crop_lo), Vec3::from(p.crop_hi));
        lo = lo.max(a);
        hi = hi.min(b);
    }
    (lo, hi)
}

/// The ray of pixel (x, y) in voxel space, as `camera_ray` in `glsl/common/camera.glsl`.
pub fn camera_ray(p: &RenderParams, x: u32, y: u32) -> (Vec3, Vec3) {
    let (base, du, dv) = (
        Vec3::from_slice(&p.base),
        Vec3::from_slice(&p.du),
        Vec3::from_slice(&p.dv),
    );
    let point = base + du * (x as f32 + 0.5) + dv * (y as f32 + 0.5);
    let (org, dir) = if p.perspective == 0 {
        (point, Vec3::from_slice(&p.eye_or_dir))
    } else {
        let eye = Vec3::from_slice(&p.eye_or_dir);
        (eye, point - eye)
    };
    // Divided by the length, not glam's normalize() (times its reciprocal,
    // which rounds differently).
    (org, dir / dir.length())
}

/// As `march_depth` in `glsl/common/lattice.glsl`: the depth of the surface
/// point `at` (voxel space) seen by pixel (x, y).
pub(super) fn depth_at(p: &RenderParams, x: u32, y: u32, at: Vec3, ndc: bool) -> f32 {
    if ndc {
        let q = Mat4::from_cols_array_2d(&p.voxel_to_ndc) * at.extend(1.0);
        return q.z / q.w;
    }
    let (org, _) = camera_ray(p, x, y);
    ((at - org) * Vec3::from(p.spacing)).length()
}

/// Per-pixel ray limits (t in voxels) from a host depth image (row-major,
/// one depth per pixel), as `glsl/render/depth_limit.comp`: the far plane's
/// depth (`p.far_depth`) is no limit.
pub fn depth_limits(p: &RenderParams, depth: &[f32]) -> Vec<f32> {
    const NO_LIMIT: f32 = 3.4e38;
    let (w, h) = (p.image[0], p.image[1]);
    let m = Mat4::from_cols_array_2d(&p.ndc_to_voxel);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let d = depth[(y * w + x) as usize];
            if d == p.far_depth {
                return NO_LIMIT;
            }
            let ndc = (Vec2::new(x as f32, y as f32) + 0.5) * 2.0 / Vec2::new(w as f32, h as f32) - 1.0;
            let q = m * Vec4::new(ndc.x, ndc.y, d, 1.0);
            if q.w == 0.0 {
                return NO_LIMIT;
            }
            let (org, dir) = camera_ray(p, x, y);
            let t = (q.truncate() / q.w - org).dot(dir);
            match t {
                t if t.abs() < NO_LIMIT => t,
                t if t < 0.0 => 0.0,
                _ => NO_LIMIT,
            }
        })
        .collect()
}
