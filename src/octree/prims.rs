//! The traced form of a surface scene, shared by the CPU reference and the
//! GPU (`glsl/common/octree_prims.glsl`): f32 primitives with precomputed
//! frames, a vertex pool for polygons, and conservative f32 boxes. The
//! intersection routines here mirror the GLSL ones operation for operation
//! (no fused multiply-adds on either side), so both find the same t.

use super::build::Box3;
use crate::scene::math::normalize;
use crate::scene::{ConeFrame, Scene, Shape};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

/// Primitive kinds as the trace kernels read them.
pub const SPHERE: u32 = 0;
pub const CONE: u32 = 1;
pub const POLYGON: u32 = 2;

/// 64 bytes, std430.
/// - sphere: `a` = centre, radius;
/// - cone: `a` = base centre, base radius; `b` = unit axis, height;
///   `c.x` = radius slope (apex - base radius) / height;
/// - polygon: `b` = unit normal, plane offset; `info` = kind, first vertex,
///   vertex count, dropped axis (the normal's largest component).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Prim {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    pub info: [u32; 4],
}

crate::gpu::check_layout!(Prim => crate::gpu::shaders::blocks::Prim { a: a, b: b, c: c, info: info });

/// A ray as the GPU reads it (32 bytes): hits count in (tmin, tmax).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub org: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

crate::gpu::check_layout!(Ray => crate::gpu::shaders::blocks::TraceRay { org: org_tmin, dir: dir_tmax });

/// One ray's result and Havran's per-ray counters (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct TraceResult {
    /// Bits of the hit's t (compared bit for bit between implementations).
    pub t_bits: u32,
    /// Primitive hit, or `MISS`.
    pub prim: u32,
    /// N_IT: ray/object intersection tests.
    pub tests: u32,
    /// N_TS: traversal steps (see `Traversal`).
    pub steps: u32,
    /// N_ETS: leaves visited.
    pub leaves: u32,
    /// N_EETS: empty leaves visited.
    pub empty_leaves: u32,
    pub pad: [u32; 2],
}

/// A `TraceResult`'s primitive when the ray hit nothing.
pub const MISS: u32 = u32::MAX;

impl TraceResult {
    pub fn t(&self) -> f32 {
        f32::from_bits(self.t_bits)
    }

    pub fn hit(&self) -> bool {
        self.prim != MISS
    }
}

/// Largest f32 <= x.
pub fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        next_toward(f, f32::NEG_INFINITY)
    } else {
        f
    }
}

/// Smallest f32 >= x.
pub fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        next_toward(f, f32::INFINITY)
    } else {
        f
    }
}

fn next_toward(f: f32, to: f32) -> f32 {
    if f == 0.0 {
        return if to > 0.0 {
            f32::from_bits(1)
        } else {
            -f32::from_bits(1)
        };
    }
    let bits = f.to_bits();
    let up = (to > f) == (f > 0.0);
    f32::from_bits(if up { bits + 1 } else { bits - 1 })
}

/// The traced scene.
#[derive(Clone, Debug)]
pub struct TraceScene {
    pub prims: Vec<Prim>,
    pub verts: Vec<[f32; 4]>,
    /// Conservative (outward rounded) f32 bounds of each primitive.
    pub boxes: Vec<Box3>,
    /// Their union.
    pub bounds: Box3,
}

fn v4(p: DVec3, w: f64) -> [f32; 4] {
    p.as_vec3().extend(w as f32).to_array()
}

impl TraceScene {
    pub fn new(scene: &Scene) -> TraceScene {
        let mut prims = Vec::with_capacity(scene.objects.len());
        let mut verts = Vec::new();
        let mut boxes = Vec::with_capacity(scene.objects.len());
        let mut bounds = Box3 {
            lo: [f32::INFINITY; 3],
            hi: [f32::NEG_INFINITY; 3],
        };
        for o in &scene.objects {
            let mut p = Prim::default();
            match &o.shape {
                Shape::Sphere { center, radius } => {
                    p.a = v4(*center, *radius);
                    p.info[0] = SPHERE;
                }
                Shape::Cone {
                    base,
                    base_radius,
                    apex,
                    apex_radius,
                } => {
                    let f = ConeFrame::new(*base, *base_radius, *apex, *apex_radius);
                    p.a = v4(*base, *base_radius);
                    p.b = v4(f.axis, f.height);
                    p.c = [f.slope as f32, 0.0, 0.0, 0.0];
                    p.info[0] = CONE;
                }
                Shape::Polygon { vertices } => push_polygon(&mut p, &mut verts, vertices, &o.shape),
                Shape::Patch { vertices, .. } => push_polygon(&mut p, &mut verts, vertices, &o.shape),
            }
            let b = o.shape.bounds();
            let fb = Box3 {
                lo: b.lo.to_array().map(f32_down),
                hi: b.hi.to_array().map(f32_up),
            };
            for a in 0..3 {
                bounds.lo[a] = bounds.lo[a].min(fb.lo[a]);
                bounds.hi[a] = bounds.hi[a].max(fb.hi[a]);
            }
            prims.push(p);
            boxes.push(fb);
        }
        TraceScene {
            prims,
            verts,
            boxes,
            bounds,
        }
    }

    /// The octree root: the scene bounds grown by a tiny relative epsilon.
    pub fn root_box(&self) -> Box3 {
        let ext = (0..3)
            .map(|a| self.bounds.hi[a] - self.bounds.lo[a])
            .fold(0.0f32, f32::max);
        let e = ext.max(1e-6) * 1e-5;
        Box3 {
            lo: self.bounds.lo.map(|x| x - e),
            hi: self.bounds.hi.map(|x| x + e),
        }
    }
}

fn push_polygon(p: &mut Prim, verts: &mut Vec<[f32; 4]>, vertices: &[DVec3], shape: &Shape) {
    let n = normalize(shape.plane_normal().unwrap_or(DVec3::Z));
    let drop = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
    p.b = v4(n, n.dot(vertices[0]));
    p.info = [POLYGON, verts.len() as u32, vertices.len() as u32, drop as u32];
    verts.extend(vertices.iter().map(|v| v4(*v, 0.0)));
}

/// Nearest t in (tmin, tmax) where `ray` meets primitive `p` (unit direction).
///
/// On glam's `Vec3` (plain per-component IEEE operations, no fused
/// multiply-adds): `a.dot(b)` is `a.x*b.x + a.y*b.y + a.z*b.z` summed left to
/// right, as the shader's `dot3`, and `v * s` multiplies each component (the
/// shader's `s * v`: the same IEEE products).
pub fn intersect(scene: &TraceScene, p: &Prim, r: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
    let o = Vec3::from(r.org);
    let d = Vec3::from(r.dir);
    let inside = |t: f32| t > tmin && t < tmax;
    match p.info[0] {
        SPHERE => {
            let oc = o - Vec3::from_slice(&p.a);
            let b = oc.dot(d);
            // Distance to the centre across the ray, without cancellation.
            let f = oc - d * b;
            let disc = p.a[3] * p.a[3] - f.dot(f);
            if disc < 0.0 {
                return None;
            }
            let h = disc.sqrt();
            let t0 = -b - h;
            if inside(t0) {
                return Some(t0);
            }
            let t1 = -b + h;
            inside(t1).then_some(t1)
        }
        CONE => {
            let u = Vec3::from_slice(&p.b);
            let w = o - Vec3::from_slice(&p.a);
            let a0 = w.dot(u);
            let ad = d.dot(u);
            // Components across the axis, free of the large along-axis part.
            let wp = w - u * a0;
            let dp = d - u * ad;
            let k = p.c[0];
            let rr = p.a[3] + k * a0;
            let qa = dp.dot(dp) - k * k * ad * ad;
            let qb = 2.0 * (wp.dot(dp) - rr * k * ad);
            let qc = wp.dot(wp) - rr * rr;
            let disc = qb * qb - 4.0 * qa * qc;
            if qa == 0.0 || disc < 0.0 {
                return None;
            }
            let s = disc.sqrt();
            let mut t0 = (-qb - s) / (2.0 * qa);
            let mut t1 = (-qb + s) / (2.0 * qa);
            if t0 > t1 {
                std::mem::swap(&mut t0, &mut t1);
            }
            for t in [t0, t1] {
                if inside(t) {
                    let along = a0 + t * ad;
                    if along >= 0.0 && along <= p.b[3] && p.a[3] + k * along >= 0.0 {
                        return Some(t);
                    }
                }
            }
            None
        }
        _ => {
            let n = Vec3::from_slice(&p.b);
            let denom = n.dot(d);
            if denom == 0.0 {
                return None;
            }
            let t = (p.b[3] - n.dot(o)) / denom;
            if !inside(t) {
                return None;
            }
            let hit = o + d * t;
            let drop = p.info[3] as usize;
            let (iu, iv) = ((drop + 1) % 3, (drop + 2) % 3);
            let (pu, pv) = (hit[iu], hit[iv]);
            let first = p.info[1] as usize;
            let count = p.info[2] as usize;
            // Crossing-number test in the plane that drops the normal's axis.
            let mut odd = false;
            let mut j = count - 1;
            for i in 0..count {
                let a = scene.verts[first + i];
                let b = scene.verts[first + j];
                if (a[iv] > pv) != (b[iv] > pv) && pu < (b[iu] - a[iu]) * (pv - a[iv]) / (b[iv] - a[iv]) + a[iu] {
                    odd = !odd;
                }
                j = i;
            }
            odd.then_some(t)
        }
    }
}
