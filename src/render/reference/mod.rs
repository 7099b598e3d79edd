//! CPU reference of the naive marcher: the same ray setup, lattice, trilinear
//! sampling, LUT lookup and compositing as the GLSL, in f32, for tests. Its
//! sampling is the manual filter's; against `Filter::Hardware` it differs by
//! the device's filtering precision (README, "Sample filter").

mod rays;

use super::mix::mix_channels;
use crate::desc::FrameDesc;
use crate::frame::Frame;
use crate::gpu::shaders::blocks::RenderParams;
use crate::tf::{self, TransferFunction};
use crate::volume::{Volume, VoxelData};
use glam::{I64Vec3, UVec3, Vec3};
use rayon::prelude::*;
use rays::depth_at;
pub use rays::{camera_ray, clip_interval, depth_limits, intersect_box, pixel_jitter};

/// Trilinear sample with clamp-to-edge at voxel-space point `p`, normalised.
pub fn sample(volume: &Volume, p: Vec3) -> f32 {
    volume.normalize(sample_raw(volume, p))
}

/// The stored texel value trilinearly interpolated at voxel-space point `p`
/// (clamp to edge), as `sample_manual` in `glsl/common/volume.glsl`: unorm
/// voxels are interpolated in their stored units, then scaled once.
pub fn sample_raw(volume: &Volume, p: Vec3) -> f32 {
    match &volume.data {
        VoxelData::U8(v) => trilinear(volume, p, |i| v[i] as f32) * (1.0 / 255.0),
        VoxelData::U16(v) => trilinear(volume, p, |i| v[i] as f32) * (1.0 / 65535.0),
        VoxelData::F32(v) => trilinear(volume, p, |i| v[i]),
        VoxelData::Bricks(b) => {
            let scale = match b.layout.texel_bytes {
                1 => 1.0 / 255.0,
                2 => 1.0 / 65535.0,
                _ => 1.0,
            };
            trilinear(volume, p, |i| b.stored(b.texel_bytes_at(i)) as f32) * scale
        }
    }
}

/// The values `texel(voxel index)` of `volume`'s voxels trilinearly
/// interpolated at `p` (clamp to edge), with the shaders' weights and order.
fn trilinear<T>(volume: &Volume, p: Vec3, texel: impl Fn(usize) -> T) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let hi = UVec3::from(volume.dims).as_i64vec3() - 1;
    let q = p - 0.5;
    let fl = q.floor();
    let f = q - fl;
    let i = fl.as_i64vec3();
    let at = |dx: i64, dy: i64, dz: i64| {
        let c = i + I64Vec3::new(dx, dy, dz);
        let c = [0, 1, 2].map(|a| c[a].clamp(0, hi[a]) as u32);
        texel(volume.index(c[0], c[1], c[2]))
    };
    let mix = |a: T, b: T, t: f32| a * (1.0 - t) + b * t;
    let c00 = mix(at(0, 0, 0), at(1, 0, 0), f.x);
    let c10 = mix(at(0, 1, 0), at(1, 1, 0), f.x);
    let c01 = mix(at(0, 0, 1), at(1, 0, 1), f.x);
    let c11 = mix(at(0, 1, 1), at(1, 1, 1), f.x);
    mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z)
}

/// How a frame's samples are combined (the shaders' specialization
/// constants): `FrameDesc::mode().constant()` and whether composite
/// samples are lit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Look {
    pub mode: u32,
    pub shade: bool,
}

impl Look {
    /// A frame description's.
    pub fn of(desc: &FrameDesc) -> Look {
        Look {
            mode: desc.mode().constant(),
            shade: desc.shading().is_some(),
        }
    }
}

const MODE_COMPOSITE: u32 = 0;
const MODE_MIP: u32 = 1;
const MODE_MINIP: u32 = 2;
const MODE_AVERAGE: u32 = 3;
const MODE_ISO: u32 = 4;
/// As `ISO_BISECTIONS` in `glsl/common/lattice.glsl`.
const ISO_BISECTIONS: u32 = 16;

/// One frame's rays on the CPU, as the GLSL marches them.
pub struct Tracer<'a> {
    pub volume: &'a Volume,
    pub tf: &'a TransferFunction,
    pub p: &'a RenderParams,
    pub look: Look,
    /// `tf.corrected_lut(p.step)` per channel: full-length samples read
    /// it, the ray's shortened last sample corrects the raw LUT's alpha
    /// itself.
    corrected: Vec<Vec<[f32; 4]>>,
    /// The volume's gradient texels, for lit looks (`volume::gradient_texels`).
    gradient: Vec<[half::f16; 4]>,
}

impl<'a> Tracer<'a> {
    pub fn new(volume: &'a Volume, tf: &'a TransferFunction, p: &'a RenderParams, look: Look) -> Self {
        let lit = look.shade || look.mode == MODE_ISO;
        Tracer {
            volume,
            tf,
            p,
            look,
            corrected: (0..volume.channel_count())
                .map(|c| tf.channel(c).corrected_lut(p.step))
                .collect(),
            gradient: if lit {
                crate::volume::gradient_texels(volume)
            } else {
                Vec::new()
            },
        }
    }

    /// The normalised sample at voxel-space point `pos` (NaN: no data).
    fn sample(&self, pos: Vec3) -> f32 {
        self.sample_channel(0, pos)
    }

    /// Channel `c`'s colour at value `v` for a sample standing for `w`
    /// voxels, as `shade` in `glsl/common/lattice.glsl`: the corrected LUT
    /// for a full-length sample, else the raw one's alpha corrected for `w`.
    fn colour(&self, c: usize, v: f32, w: f32) -> [f32; 4] {
        if w < self.p.step {
            let x = self.tf.channel(c).lookup(v);
            return [x[0], x[1], x[2], tf::opacity(x[3], w)];
        }
        tf::lookup_in(&self.corrected[c], v)
    }

    /// Channel `c`'s normalised sample at `pos` (NaN: no data).
    fn sample_channel(&self, c: usize, pos: Vec3) -> f32 {
        let channel = self.volume.channel(c);
        let v = (sample_raw(channel, pos) - channel.norm[0]) * channel.norm[1];
        if v.is_nan() {
            v
        } else {
            v.clamp(0.0, 1.0)
        }
    }

    /// As `trace` for a volume of several channels (composite, mip, minip,
    /// average), as `take_channels` and `mix_channels` in
    /// `glsl/common/lattice.glsl`.
    fn trace_channels(&self, org: Vec3, dir: Vec3, samples: LatticeSamples) -> [f32; 4] {
        let p = self.p;
        let n = self.volume.channel_count();
        let mode = self.look.mode;
        let mut acc = [0f32; 4];
        let mut best = vec![if mode == MODE_MINIP { 2.0f32 } else { -1.0 }; n];
        let (mut sum, mut count) = (vec![0f32; n], vec![0f32; n]);
        for (t, w) in samples {
            let pos = org + dir * t;
            let values: Vec<f32> = (0..n).map(|c| self.sample_channel(c, pos)).collect();
            if mode == MODE_COMPOSITE {
                let colours: Vec<[f32; 4]> = values
                    .iter()
                    .enumerate()
                    .map(|(c, &v)| if v.is_nan() { [0.0; 4] } else { self.colour(c, v, w) })
                    .collect();
                composite(&mut acc, mix_channels(&colours));
                if acc[3] >= p.ert {
                    break;
                }
                continue;
            }
            for (c, &v) in values.iter().enumerate().filter(|(_, v)| !v.is_nan()) {
                match mode {
                    MODE_MIP => best[c] = best[c].max(v),
                    MODE_MINIP => best[c] = best[c].min(v),
                    _ => {
                        sum[c] += v;
                        count[c] += 1.0;
                    }
                }
            }
            let done = |b: &f32| if mode == MODE_MIP { *b >= 1.0 } else { *b <= 0.0 };
            if (mode == MODE_MIP || mode == MODE_MINIP) && best.iter().all(done) {
                break;
            }
        }
        if mode == MODE_COMPOSITE {
            return acc;
        }
        let colours: Vec<[f32; 4]> = (0..n)
            .map(|c| {
                let x = match mode {
                    MODE_AVERAGE if count[c] == 0.0 => -1.0,
                    MODE_AVERAGE => sum[c] / count[c],
                    _ => best[c],
                };
                match (0.0..=1.0).contains(&x) {
                    true => self.tf.channel(c).lookup(x),
                    false => [0.0; 4],
                }
            })
            .collect();
        let c = mix_channels(&colours);
        [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]]
    }

    /// As `sample_gradient` in `glsl/common/volume.glsl` (manual filter).
    fn sample_gradient(&self, p: Vec3) -> Vec3 {
        trilinear(self.volume, p, |i| {
            let g = self.gradient[i];
            Vec3::new(g[0].to_f32(), g[1].to_f32(), g[2].to_f32())
        })
    }

    /// As `light_sample` in `glsl/common/light.glsl`.
    fn light(&self, pos: Vec3, dir: Vec3, c: [f32; 4]) -> [f32; 4] {
        let p = self.p;
        // Relative to the shortest side, as the shader takes it.
        let spacing = Vec3::from(p.spacing) / p.spacing.into_iter().fold(f32::INFINITY, f32::min);
        // The gradient texels are in physical units already.
        let g = self.sample_gradient(pos);
        let d = g.dot(g);
        let [ka, kd, ks, shininess] = p.shading;
        let view = (-dir * spacing).normalize();
        let l = if p.headlight != 0 { view } else { Vec3::from(p.light) };
        let rgb = Vec3::new(c[0], c[1], c[2]);
        let lit = if d > 0.0 && d < 3.4e38 {
            let n = g * (1.0 / d.sqrt());
            let h = (l + view).normalize();
            let nd = n.dot(l).abs();
            let nh = n.dot(h).abs();
            rgb * (ka + kd * nd) + Vec3::splat(ks * specular_power(nh, shininess))
        } else {
            rgb * (ka + kd)
        };
        let mut a = c[3];
        if p.gradient_opacity != 0 {
            let len = d.sqrt();
            let ramp = ((len - p.gradient_lo) / (p.gradient_hi - p.gradient_lo)).clamp(0.0, 1.0);
            a *= if ramp.is_nan() { 0.0 } else { ramp };
        }
        let lit = lit.min(Vec3::ONE);
        [lit.x, lit.y, lit.z, a]
    }

    /// The premultiplied RGBA of pixel (x, y), its ray ending at `t_limit`
    /// (voxels along it) when given.
    // Negated comparisons mirror the GLSL: a NaN bound stops the march.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn pixel(&self, x: u32, y: u32, t_limit: Option<f32>) -> [f32; 4] {
        self.trace(x, y, t_limit).0
    }

    /// As `pixel`, with the surface hit's point (voxel space) in iso mode.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn trace(&self, x: u32, y: u32, t_limit: Option<f32>) -> ([f32; 4], Option<Vec3>) {
        let p = self.p;
        let (org, dir) = camera_ray(p, x, y);
        let hi = UVec3::from(self.volume.dims).as_vec3();
        let (t_near, box_exit) = intersect_box(org, dir, Vec3::ZERO, hi);
        let t_enter = t_near.max(0.0);
        let mut t_exit = match t_limit {
            Some(limit) if t_enter < box_exit => box_exit.min(limit),
            _ => box_exit,
        };
        let jitter = if p.jitter != 0 { pixel_jitter(x, y) } else { 0.0 };
        let dt = p.step;
        let lattice_t = |k: u32| t_enter + (k as f32 + jitter) * dt;
        let mut k = 0u32;
        if !(t_enter < t_exit) {
            return ([0.0; 4], None);
        }
        if p.clip_count != 0 || p.crop != 0 {
            let (lo, clip_hi) = clip_interval(p, org, dir);
            t_exit = t_exit.min(clip_hi);
            while lattice_t(k) < lo {
                k += 1;
            }
        }
        // A rank's segment stops the samples, not the ray (`march_pixel`).
        let mut t_stop = t_exit;
        let whole_first = k;
        if p.segment != 0 {
            let (lo, hi) = segment_interval(p, org, dir);
            t_stop = t_stop.min(hi);
            while lattice_t(k) < lo {
                k += 1;
            }
        }
        let samples = LatticeSamples {
            t_enter,
            t_exit,
            t_stop,
            dt,
            jitter,
            k,
        };
        if self.volume.channel_count() > 1 {
            return (self.trace_channels(org, dir, samples), None);
        }
        let mode = self.look.mode;
        let mut acc = [0f32; 4];
        let mut best = if mode == MODE_MINIP { 2.0f32 } else { -1.0 };
        let (mut sum, mut count) = (0f32, 0f32);
        // An iso segment pairs its first sample with the whole ray's one
        // before it, as `march_pixel` does.
        let mut prev: Option<(f32, f32)> = None;
        if mode == MODE_ISO && k > whole_first {
            let t = lattice_t(k - 1);
            prev = Some((t, self.sample(org + dir * t))).filter(|(_, v)| !v.is_nan());
        }
        for (t, w) in samples {
            let pos = org + dir * t;
            let v = self.sample(pos);
            if v.is_nan() {
                prev = None;
                continue;
            }
            match mode {
                MODE_COMPOSITE => {
                    let mut c = self.colour(0, v, w);
                    if self.look.shade && c[3] > 0.0 {
                        c = self.light(pos, dir, c);
                    }
                    composite(&mut acc, c);
                    if acc[3] >= p.ert {
                        break;
                    }
                }
                MODE_MIP => {
                    best = best.max(v);
                    if best >= 1.0 {
                        break;
                    }
                }
                MODE_MINIP => {
                    best = best.min(v);
                    if best <= 0.0 {
                        break;
                    }
                }
                MODE_AVERAGE => {
                    sum += v;
                    count += 1.0;
                }
                _ => {
                    if let Some((t0, v0)) = prev {
                        if let Some((t_hit, iso)) = self.iso_crossing(org, dir, (t0, v0), (t, v)) {
                            return (self.iso_surface(org, dir, t_hit, iso), Some(org + dir * t_hit));
                        }
                    }
                    prev = Some((t, v));
                }
            }
        }
        let rgba = match mode {
            MODE_COMPOSITE => acc,
            MODE_AVERAGE | MODE_MIP | MODE_MINIP => {
                let v = if mode == MODE_AVERAGE {
                    if count == 0.0 {
                        return ([0.0; 4], None);
                    }
                    sum / count
                } else if !(0.0..=1.0).contains(&best) {
                    return ([0.0; 4], None);
                } else {
                    best
                };
                let c = self.tf.lookup(v);
                [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]]
            }
            _ => [0.0; 4],
        };
        (rgba, None)
    }

    /// As `iso_bracket` and `iso_refine` in `glsl/common/lattice.glsl`: the smallest refined
    /// crossing of an iso value between consecutive lattice samples
    /// (t0, v0) and (t1, v1).
    fn iso_crossing(&self, org: Vec3, dir: Vec3, (t0, v0): (f32, f32), (t1, v1): (f32, f32)) -> Option<(f32, f32)> {
        let mut best: Option<(f32, f32)> = None;
        for &iso in &self.p.iso[..self.p.iso_count as usize] {
            let below = v0 < iso;
            if below == (v1 < iso) {
                continue;
            }
            let (mut a, mut b) = (t0, t1);
            for _ in 0..ISO_BISECTIONS {
                let mid = 0.5 * (a + b);
                if (self.sample(org + dir * mid) < iso) == below {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            let t = 0.5 * (a + b);
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, iso));
            }
        }
        best
    }

    fn iso_surface(&self, org: Vec3, dir: Vec3, t: f32, iso: f32) -> [f32; 4] {
        let rgb = if self.p.iso_colored != 0 {
            self.p.iso_color
        } else {
            let c = self.tf.lookup(iso);
            [c[0], c[1], c[2]]
        };
        let lit = self.light(org + dir * t, dir, [rgb[0], rgb[1], rgb[2], 1.0]);
        [lit[0], lit[1], lit[2], 1.0]
    }
}

/// As `segment_interval` in `glsl/common/lattice.glsl`: the ray's part in
/// the rank's block, a ray lying in a shared face in the block above it.
fn segment_interval(p: &RenderParams, org: Vec3, dir: Vec3) -> (f32, f32) {
    let in_face = (0..3).any(|a| dir[a] == 0.0 && org[a] == p.segment_hi[a] && p.segment_hi[a] < p.dims[a] as f32);
    if in_face {
        return (1.0, -1.0);
    }
    intersect_box(org, dir, Vec3::from(p.segment_lo), Vec3::from(p.segment_hi))
}

/// A ray's lattice samples from index `k` on, as the GLSL march takes
/// them: (t_k, the path length it stands for). Only the ray's last sample
/// is shortened (`glsl/common/lattice.glsl`).
struct LatticeSamples {
    t_enter: f32,
    t_exit: f32,
    /// A segment's end (<= t_exit): no sample at or past it.
    t_stop: f32,
    dt: f32,
    jitter: f32,
    k: u32,
}

impl LatticeSamples {
    fn t(&self, k: u32) -> f32 {
        self.t_enter + (k as f32 + self.jitter) * self.dt
    }
}

impl Iterator for LatticeSamples {
    type Item = (f32, f32);

    // Negated comparisons mirror the GLSL: a NaN bound stops the march.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn next(&mut self) -> Option<(f32, f32)> {
        let t = self.t(self.k);
        if !(t < self.t_stop) {
            return None;
        }
        let last = !(self.t(self.k + 1) < self.t_exit);
        self.k += 1;
        Some((t, if last { self.dt.min(self.t_exit - t) } else { self.dt }))
    }
}

/// As `composite` in `glsl/common/lattice.glsl`: sample `c` over `acc`,
/// front to back.
fn composite(acc: &mut [f32; 4], c: [f32; 4]) {
    if c[3] > 0.0 {
        let a = c[3].min(1.0);
        let transmit = 1.0 - acc[3];
        for ch in 0..3 {
            acc[ch] += transmit * a * c[ch];
        }
        acc[3] += transmit * a;
    }
}

/// Renders a whole composite, unshaded frame on the CPU (parallel over rows).
pub fn render(volume: &Volume, tf: &TransferFunction, p: &RenderParams) -> Frame {
    render_to(volume, tf, p, None)
}

/// As `render`, each ray ending at its pixel's limit (`depth_limits`) when given.
pub fn render_to(volume: &Volume, tf: &TransferFunction, p: &RenderParams, limits: Option<&[f32]>) -> Frame {
    render_look(&Tracer::new(volume, tf, p, Look::default()), limits)
}

/// Renders frame `desc` of `volume` on the CPU: its mode, shading, clip,
/// crop and jitter (the sample filter is always the manual one's); an iso
/// frame with its depth (`render::HostDepthOut`).
pub fn render_frame(volume: &Volume, tf: &TransferFunction, desc: &FrameDesc) -> crate::Result<Frame> {
    let p = desc.params_for(volume.dims, volume.spacing, volume.norm)?;
    let tracer = Tracer::new(volume, tf, &p, Look::of(desc));
    if !matches!(desc.mode(), crate::desc::Mode::Iso(_)) {
        return Ok(render_look(&tracer, None));
    }
    let (w, h) = (p.image[0], p.image[1]);
    let ndc = desc.camera_has_ndc();
    let traced: Vec<([f32; 4], f32)> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (rgba, hit) = tracer.trace(x, y, None);
            (rgba, hit.map_or(p.no_hit_depth, |at| depth_at(&p, x, y, at, ndc)))
        })
        .collect();
    let mut frame = Frame::new(w, h, traced.iter().map(|t| t.0).collect());
    frame.depth = Some(traced.iter().map(|t| t.1).collect());
    Ok(frame)
}

fn render_look(tracer: &Tracer, limits: Option<&[f32]>) -> Frame {
    let (w, h) = (tracer.p.image[0], tracer.p.image[1]);
    let pixels: Vec<[f32; 4]> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| tracer.pixel(x, y, limits.map(|l| l[(y * w + x) as usize])))
        .collect();
    Frame::new(w, h, pixels)
}

/// `nh` to the Phong exponent as `light.glsl`'s `specular_power`: by
/// repeated squaring where it is whole, else `powf`.
fn specular_power(nh: f32, shininess: f32) -> f32 {
    let whole = crate::desc::whole_exponent(shininess);
    if whole == 0 {
        return nh.powf(shininess);
    }
    let (mut r, mut b, mut e) = (1.0f32, nh, whole);
    while e != 0 {
        if e & 1 != 0 {
            r *= b;
        }
        b *= b;
        e >>= 1;
    }
    r
}
