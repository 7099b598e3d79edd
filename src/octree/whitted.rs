//! The SPD testing procedure's Whitted ray tracer: one eye ray per pixel
//! corner (513 x 513 for 512 x 512), Phong shading from positional lights,
//! a shadow ray to every light the surface faces, mirror reflection for
//! surfaces with ks > 0 and Snell refraction for transmitters, to a ray tree
//! depth of 5 (the eye ray is depth 1).
//!
//! Rays are traced in waves (all eye rays, then their shadow rays, then all
//! reflected and refracted rays, ...) by a `Tracer` (the GPU, or the CPU
//! reference); shading runs on the host between waves. Every wave can be
//! traced with several traversals: the first one's hits are shaded, and the
//! others' are compared with them (`RenderStats::disagreements`).

use super::prims::{Ray, TraceResult};
use super::traverse::Traversal;
use super::{trace_cpu, GpuTracer, Octree, TraceScene};
use crate::error::Result;
use crate::frame::Frame;
use crate::scene::math::normalize;
use crate::scene::{ConeFrame, Scene, Shape, View};
use glam::{DVec3, Vec3};
use std::time::Instant;

/// Traces batches of rays with a given traversal; returns results and the
/// time spent tracing (GPU timestamps, or CPU wall time) in milliseconds.
pub trait Tracer {
    fn trace(&mut self, kind: Traversal, rays: &[Ray], any_hit: bool) -> Result<(Vec<TraceResult>, f64)>;
}

impl Tracer for GpuTracer<'_> {
    fn trace(&mut self, kind: Traversal, rays: &[Ray], any_hit: bool) -> Result<(Vec<TraceResult>, f64)> {
        GpuTracer::trace(self, kind, rays, any_hit)
    }
}

/// The CPU reference as a tracer.
pub struct CpuTracer<'a> {
    pub tree: &'a Octree,
    pub scene: &'a TraceScene,
}

impl Tracer for CpuTracer<'_> {
    fn trace(&mut self, kind: Traversal, rays: &[Ray], any_hit: bool) -> Result<(Vec<TraceResult>, f64)> {
        let start = Instant::now();
        let r = trace_cpu(self.tree, self.scene, kind, rays, any_hit);
        Ok((r, start.elapsed().as_secs_f64() * 1e3))
    }
}

/// What a Whitted ray tracing of an SPD scene traces and returns.
#[derive(Clone, Copy, Debug)]
pub struct WhittedOptions {
    /// Image edge in pixels (the SPD's is 512).
    pub resolution: u32,
    /// Deepest ray tree level (the SPD's is 5, the eye ray being 1).
    pub max_depth: u32,
    /// Whether to shade and return an image.
    pub image: bool,
}

impl Default for WhittedOptions {
    fn default() -> Self {
        WhittedOptions {
            resolution: 512,
            max_depth: 5,
            image: true,
        }
    }
}

/// The ray counts of the SPD testing procedure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    pub eye_rays: u64,
    pub eye_hits: u64,
    pub shadow_rays: u64,
    pub shadow_hits: u64,
    pub secondary_rays: u64,
    pub secondary_hits: u64,
}

impl RayCounts {
    pub fn total(&self) -> u64 {
        self.eye_rays + self.shadow_rays + self.secondary_rays
    }
}

/// Havran's per-traversal totals over every ray of a rendering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraversalTotals {
    pub traversal: Traversal,
    pub rays: u64,
    pub tests: u64,
    pub steps: u64,
    pub leaves: u64,
    pub empty_leaves: u64,
    /// Tracing time, milliseconds (T_TR).
    pub trace_ms: f64,
}

impl TraversalTotals {
    fn new(traversal: Traversal) -> Self {
        TraversalTotals {
            traversal,
            rays: 0,
            tests: 0,
            steps: 0,
            leaves: 0,
            empty_leaves: 0,
            trace_ms: 0.0,
        }
    }

    fn add(&mut self, results: &[TraceResult], ms: f64) {
        self.rays += results.len() as u64;
        self.trace_ms += ms;
        for r in results {
            self.tests += r.tests as u64;
            self.steps += r.steps as u64;
            self.leaves += r.leaves as u64;
            self.empty_leaves += r.empty_leaves as u64;
        }
    }

    /// Per-ray averages (N_IT, N_TS, N_ETS, N_EETS).
    pub fn per_ray(&self) -> [f64; 4] {
        let n = self.rays.max(1) as f64;
        [self.tests, self.steps, self.leaves, self.empty_leaves].map(|v| v as f64 / n)
    }
}

/// What a Whitted tracing counted, and its image when asked for.
#[derive(Clone, Debug)]
pub struct RenderStats {
    pub counts: RayCounts,
    pub totals: Vec<TraversalTotals>,
    /// Rays on which a traversal's hit (primitive or t) differed from the first's.
    pub disagreements: u64,
    pub image: Option<Frame>,
}

/// Host-side shading data per primitive, in f64.
struct Shading<'a> {
    scene: &'a Scene,
    light_scale: f64,
}

/// A ray waiting to be traced with what its result contributes to.
#[derive(Clone, Copy)]
struct Pending {
    corner: u32,
    weight: DVec3,
    depth: u32,
}

struct ShadowPending {
    corner: u32,
    color: DVec3,
}

fn to_ray(o: DVec3, d: DVec3, tmin: f64, tmax: f64) -> Ray {
    Ray {
        org: o.as_vec3().to_array(),
        tmin: tmin as f32,
        dir: d.as_vec3().to_array(),
        tmax: tmax as f32,
    }
}

const FAR: f64 = 1e30;

impl Shading<'_> {
    /// Unit geometric (or, for patches, interpolated) normal at p.
    fn normal(&self, prim: u32, p: DVec3) -> DVec3 {
        match &self.scene.objects[prim as usize].shape {
            Shape::Sphere { center, .. } => normalize(p - *center),
            Shape::Cone {
                base,
                base_radius,
                apex,
                apex_radius,
            } => {
                let f = ConeFrame::new(*base, *base_radius, *apex, *apex_radius);
                let w = p - *base;
                let radial = normalize(w - f.axis * w.dot(f.axis));
                normalize(radial - f.axis * f.slope)
            }
            Shape::Polygon { .. } => self.scene.objects[prim as usize]
                .shape
                .plane_normal()
                .unwrap_or(DVec3::Z),
            Shape::Patch { vertices, normals } => {
                let (a, b, c) = (vertices[0], vertices[1], vertices[2]);
                let n = (b - a).cross(c - a);
                let area = n.dot(n);
                if area == 0.0 {
                    return normalize(normals[0]);
                }
                let wa = (b - p).cross(c - p).dot(n) / area;
                let wb = (c - p).cross(a - p).dot(n) / area;
                let wc = 1.0 - wa - wb;
                let s = normals[0] * wa + normals[1] * wb + normals[2] * wc;
                let s = normalize(s);
                if s.dot(s) == 0.0 {
                    normalize(n)
                } else {
                    s
                }
            }
        }
    }
}

/// Self-intersection allowance for rays leaving a surface at p.
fn surface_eps(p: DVec3) -> f64 {
    // f64::max from 1 over x, y, z, not glam's max_element (another order
    // and NaN rule).
    2e-5 * p.to_array().into_iter().fold(1.0f64, |m, x| m.max(x.abs()))
}

/// The SPD's eye rays for a `resolution`^2 image: one per pixel corner,
/// (resolution + 1)^2, rows from the top. The field of view spans the pixel
/// centres of the outer rows, so the corners reach half a pixel beyond.
pub fn eye_rays(v: &View, resolution: u32) -> Vec<Ray> {
    let corners = resolution + 1;
    let forward = normalize(v.at - v.from);
    let right = normalize(forward.cross(v.up));
    let up = right.cross(forward);
    let half = (v.fov_deg.to_radians() / 2.0).tan();
    let centre = resolution as f64 / 2.0;
    let span = (resolution as f64 - 1.0).max(1.0) / 2.0;
    let mut rays = Vec::with_capacity((corners * corners) as usize);
    for j in 0..corners {
        for i in 0..corners {
            let x = half * (i as f64 - centre) / span;
            let y = half * (centre - j as f64) / span;
            let d = normalize(forward + (right * x + up * y));
            rays.push(to_ray(v.from, d, v.hither.max(0.0), FAR));
        }
    }
    rays
}

/// Renders `scene` through `tracer` with each of `traversals` (at least one).
pub fn render(
    scene: &Scene,
    tracer: &mut dyn Tracer,
    traversals: &[Traversal],
    options: &WhittedOptions,
) -> Result<RenderStats> {
    if traversals.is_empty() {
        return Err(crate::error::Error::invalid(
            "octree traversals",
            "none",
            "give at least one to render with",
        ));
    }
    let res = options.resolution;
    let corners = res + 1;
    let shading = Shading {
        scene,
        light_scale: 1.0 / (scene.lights.len().max(1) as f64).sqrt(),
    };
    let mut color = vec![DVec3::ZERO; (corners * corners) as usize];
    let mut counts = RayCounts::default();
    let mut totals: Vec<TraversalTotals> = traversals.iter().map(|&t| TraversalTotals::new(t)).collect();
    let mut disagreements = 0u64;

    let mut rays = eye_rays(&scene.view, res);
    let mut pending: Vec<Pending> = (0..rays.len() as u32)
        .map(|corner| Pending {
            corner,
            weight: DVec3::ONE,
            depth: 1,
        })
        .collect();
    counts.eye_rays = rays.len() as u64;

    let mut trace_all = |rays: &[Ray], any_hit: bool, totals: &mut Vec<TraversalTotals>| -> Result<Vec<TraceResult>> {
        let mut first: Option<Vec<TraceResult>> = None;
        for (k, &t) in traversals.iter().enumerate() {
            let (res, ms) = tracer.trace(t, rays, any_hit)?;
            totals[k].add(&res, ms);
            match &first {
                None => first = Some(res),
                Some(f) => {
                    disagreements += f
                        .iter()
                        .zip(&res)
                        .filter(|(a, b)| a.prim != b.prim || a.t_bits != b.t_bits)
                        .count() as u64
                }
            }
        }
        Ok(first.unwrap_or_default())
    };

    while !rays.is_empty() {
        let hits = trace_all(&rays, false, &mut totals)?;
        let mut shadow_rays = Vec::new();
        let mut shadows = Vec::new();
        let mut next_rays = Vec::new();
        let mut next = Vec::new();
        for ((ray, pend), hit) in rays.iter().zip(&pending).zip(&hits) {
            let primary = pend.depth == 1;
            if !hit.hit() {
                color[pend.corner as usize] += pend.weight * scene.background;
                continue;
            }
            if primary {
                counts.eye_hits += 1;
            } else {
                counts.secondary_hits += 1;
            }
            let o = Vec3::from(ray.org).as_dvec3();
            let d = Vec3::from(ray.dir).as_dvec3();
            let p = o + d * hit.t() as f64;
            let mut n = shading.normal(hit.prim, p);
            let entering = n.dot(d) < 0.0;
            if !entering {
                // Times -1 as before (-n would differ in a NaN's sign bit).
                n *= -1.0;
            }
            let m = &scene.materials[scene.objects[hit.prim as usize].material as usize];
            let eps = surface_eps(p);
            let reflected = d - n * (2.0 * d.dot(n));
            for l in &scene.lights {
                let to = *l - p;
                let dist = to.length();
                let ldir = to * (1.0 / dist);
                let facing = n.dot(ldir);
                if facing <= 0.0 {
                    continue;
                }
                let spec = if m.ks > 0.0 {
                    m.ks * reflected.dot(ldir).max(0.0).powf(m.shine.max(1.0))
                } else {
                    0.0
                };
                let c = pend.weight * shading.light_scale * (m.kd * m.color * facing + spec);
                shadow_rays.push(to_ray(p, ldir, eps, dist - eps));
                shadows.push(ShadowPending {
                    corner: pend.corner,
                    color: c,
                });
            }
            if pend.depth >= options.max_depth {
                continue;
            }
            if m.ks > 0.0 {
                next_rays.push(to_ray(p, normalize(reflected), eps, FAR));
                next.push(Pending {
                    corner: pend.corner,
                    weight: pend.weight * m.ks,
                    depth: pend.depth + 1,
                });
            }
            if m.transmit > 0.0 {
                let ior = if m.ior > 0.0 { m.ior } else { 1.0 };
                let eta = if entering { 1.0 / ior } else { ior };
                let cosi = -d.dot(n);
                let k = 1.0 - eta * eta * (1.0 - cosi * cosi);
                if k >= 0.0 {
                    let t = normalize(d * eta + n * (eta * cosi - k.sqrt()));
                    next_rays.push(to_ray(p, t, eps, FAR));
                    next.push(Pending {
                        corner: pend.corner,
                        weight: pend.weight * m.transmit,
                        depth: pend.depth + 1,
                    });
                }
            }
        }
        if !shadow_rays.is_empty() {
            counts.shadow_rays += shadow_rays.len() as u64;
            let blocked = trace_all(&shadow_rays, true, &mut totals)?;
            for (s, b) in shadows.iter().zip(&blocked) {
                if b.hit() {
                    counts.shadow_hits += 1;
                } else {
                    color[s.corner as usize] += s.color;
                }
            }
        }
        counts.secondary_rays += next_rays.len() as u64;
        rays = next_rays;
        pending = next;
    }

    let image = options.image.then(|| {
        let mut pixels = Vec::with_capacity((res * res) as usize);
        for y in 0..res {
            for x in 0..res {
                let at = |i: u32, j: u32| color[(j * corners + i) as usize];
                let c = (at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1)) / 4.0;
                pixels.push(c.as_vec3().extend(1.0).to_array());
            }
        }
        Frame::new(res, res, pixels)
    });
    Ok(RenderStats {
        counts,
        totals,
        disagreements,
        image,
    })
}
