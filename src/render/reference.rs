//! CPU reference of the naive marcher: the same ray setup, lattice, trilinear
//! sampling, LUT lookup and compositing as the GLSL, in f32, for tests. Its
//! sampling is the manual filter's; against `Filter::Hardware` it differs by
//! the device's filtering precision (README, "Sample filter").

use crate::frame::Frame;
use crate::gpu::shaders::blocks::RenderParams;
use crate::tf::{self, TransferFunction};
use crate::volume::Volume;
use glam::{I64Vec3, Mat4, UVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

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

/// Trilinear sample with clamp-to-edge at voxel-space point `p`.
pub fn sample(volume: &Volume, p: Vec3) -> f32 {
    let hi = UVec3::from(volume.dims).as_i64vec3() - 1;
    let q = p - 0.5;
    let fl = q.floor();
    let f = q - fl;
    let i = fl.as_i64vec3();
    let texel = |dx: i64, dy: i64, dz: i64| {
        let c = i + I64Vec3::new(dx, dy, dz);
        let c = [0, 1, 2].map(|a| c[a].clamp(0, hi[a]) as u32);
        volume.data.texel(volume.index(c[0], c[1], c[2]))
    };
    let mix = |a: f32, b: f32, t: f32| a * (1.0 - t) + b * t;
    let c00 = mix(texel(0, 0, 0), texel(1, 0, 0), f.x);
    let c10 = mix(texel(0, 1, 0), texel(1, 1, 0), f.x);
    let c01 = mix(texel(0, 0, 1), texel(1, 0, 1), f.x);
    let c11 = mix(texel(0, 1, 1), texel(1, 1, 1), f.x);
    let raw = mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
    volume.normalize(raw)
}

/// The premultiplied RGBA of one pixel; `corrected` is
/// `tf.corrected_lut(p.step)` (full-length samples read it, the ray's
/// shortened last sample corrects the raw LUT's alpha itself, as the GLSL).
// Negated comparisons mirror the GLSL: a NaN bound stops the march.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn trace(
    volume: &Volume,
    tf: &TransferFunction,
    corrected: &[[f32; 4]],
    p: &RenderParams,
    x: u32,
    y: u32,
) -> [f32; 4] {
    trace_to(volume, tf, corrected, p, x, y, None)
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

/// As `trace`, the ray ending at `t_limit` (voxels along it) when given.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn trace_to(
    volume: &Volume,
    tf: &TransferFunction,
    corrected: &[[f32; 4]],
    p: &RenderParams,
    x: u32,
    y: u32,
    t_limit: Option<f32>,
) -> [f32; 4] {
    let (org, dir) = camera_ray(p, x, y);
    let hi = UVec3::from(volume.dims).as_vec3();
    let (t_near, t_exit) = intersect_box(org, dir, Vec3::ZERO, hi);
    let t_enter = t_near.max(0.0);
    let t_exit = match t_limit {
        Some(limit) if t_enter < t_exit => t_exit.min(limit),
        _ => t_exit,
    };
    let dt = p.step;
    let ert = p.ert;
    let mut acc = [0f32; 4];
    if !(t_enter < t_exit) {
        return acc;
    }
    let lattice_t = |k: u32| t_enter + k as f32 * dt;
    let mut k = 0u32;
    loop {
        let t = lattice_t(k);
        if !(t < t_exit) {
            break;
        }
        // Only the ray's last sample is shortened (glsl/common/lattice.glsl).
        let last = !(lattice_t(k + 1) < t_exit);
        let w = if last { dt.min(t_exit - t) } else { dt };
        let pos = org + dir * t;
        let v = sample(volume, pos);
        let c = if w < dt {
            let c = tf.lookup(v);
            [c[0], c[1], c[2], tf::opacity(c[3], w)]
        } else {
            tf::lookup_in(corrected, v)
        };
        if c[3] > 0.0 {
            let a = c[3].min(1.0);
            let transmit = 1.0 - acc[3];
            for ch in 0..3 {
                acc[ch] += transmit * a * c[ch];
            }
            acc[3] += transmit * a;
        }
        k += 1;
        if acc[3] >= ert {
            break;
        }
    }
    acc
}

/// Renders a whole frame on the CPU (parallel over rows).
pub fn render(volume: &Volume, tf: &TransferFunction, p: &RenderParams) -> Frame {
    render_to(volume, tf, p, None)
}

/// As `render`, each ray ending at its pixel's limit (`depth_limits`) when given.
pub fn render_to(volume: &Volume, tf: &TransferFunction, p: &RenderParams, limits: Option<&[f32]>) -> Frame {
    let (w, h) = (p.image[0], p.image[1]);
    let corrected = tf.corrected_lut(p.step);
    let corrected = &corrected;
    let pixels: Vec<[f32; 4]> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let limit = limits.map(|l| l[(y * w + x) as usize]);
            trace_to(volume, tf, corrected, p, x, y, limit)
        })
        .collect();
    Frame::new(w, h, pixels)
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
