//! What a frame is: [`FrameDesc`], every input of one frame besides the
//! scene (volume, transfer function, structure) and where it goes. Every
//! entry point takes one (the library's `Renderer`, `lacuna render`, `view`,
//! `bench`, the embedding API). Its fields are typed, its defaults are
//! here and nowhere else, and it is validated once, when built; the GPU
//! parameter block (`shaders::blocks::RenderParams`) is derived from it.
//!
//! A frame is described, not a renderer configured: what later work adds to
//! a frame (render mode, shading, clip planes, jitter, several channels, a
//! time step) becomes a field here with its default, and the block grows
//! a member; callers that do not set it keep today's frame.

mod clip;
mod kernel;
mod look;
mod matrices;
mod mode;
mod octants;
mod orbit;
mod parse;
pub use parse::parse_size;
mod rays;
pub use rays::Rays;
mod shading;

pub use crate::volume::Filter;
pub use clip::{Clip, MAX_CLIP};
pub use kernel::{with_depth_out, KernelConstants};
pub use look::LookSpec;
pub use matrices::{orthographic, perspective, CameraMatrices};
pub use mode::{Iso, Mode, MAX_ISO, MODE_CONSTANT_ID, SHADE_CONSTANT_ID, SHININESS_CONSTANT_ID};
pub use octants::Octants;
pub use orbit::{Orbit, Projection};
pub use shading::{whole_exponent, Light, Shading};

use crate::error::{Error, Result};
use crate::gpu::shaders::blocks::RenderParams;
use crate::gpu::vk;
use crate::volume::GpuVolume;

/// The default sample spacing along each ray, in voxels.
pub const DEFAULT_STEP: f32 = 0.5;

/// The early-termination alpha the shaders read as "off": a ray ends only
/// once its accumulated alpha is exactly 1. Front-to-back compositing in
/// f32 never takes alpha past 1 (`acc + (1 - acc) * a` rounds to at most
/// 1 for `a <= 1`), and at 1 the transmittance is exactly 0, so every later
/// sample would add exactly 0: ending there changes no bit of the frame,
/// and saves the rest of the ray behind opaque matter.
pub const ERT_OFF: f32 = 1.0;

/// Where the rays come from.
// Unboxed, so a frame description stays `Copy`: a few hundred bytes, made
// once per frame.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Camera {
    /// An orbit about the volume's centre (the command line's cameras).
    Orbit(Orbit),
    /// A host's view and projection matrices (the one way rays are formed;
    /// an orbit becomes these too).
    Matrices(CameraMatrices),
    /// Rays laid out in voxel space by hand (hard cases, probes).
    Rays(Rays),
}

impl Default for Camera {
    fn default() -> Self {
        Camera::Orbit(Orbit::default())
    }
}

impl Camera {
    /// For printouts and frame metadata.
    pub fn describe(&self) -> String {
        match self {
            Camera::Orbit(o) => o.describe(),
            Camera::Matrices(m) => format!(
                "matrices ({}{})",
                if m.is_perspective() {
                    "perspective"
                } else {
                    "orthographic"
                },
                if m.reverse_z { ", reverse-Z" } else { "" }
            ),
            Camera::Rays(r) => format!(
                "rays base={:?} du={:?} dv={:?} {}={:?}",
                r.base,
                r.du,
                r.dv,
                if r.perspective { "eye" } else { "dir" },
                r.eye_or_dir
            ),
        }
    }

    /// The rays for a volume of `dims` voxels with `spacing` at `width` x `height`.
    pub fn rays(&self, dims: [u32; 3], spacing: [f32; 3], width: u32, height: u32) -> Result<Rays> {
        match self {
            Camera::Orbit(o) => o.matrices(dims, spacing, width, height)?.rays(spacing, width, height),
            Camera::Matrices(m) => m.rays(spacing, width, height),
            Camera::Rays(r) => Ok(*r),
        }
    }

    fn validate(&self) -> Result<()> {
        match self {
            Camera::Orbit(o) => o.validate(),
            Camera::Matrices(m) => m.validate(),
            Camera::Rays(r) => r.validate(),
        }
    }
}

/// A host's depth image that ends each ray at the first opaque surface: a
/// view of its depth aspect (any depth format; read with `texelFetch`, one
/// texel per pixel) created with `SAMPLED` usage, in `layout`
/// (DEPTH_READ_ONLY_OPTIMAL, DEPTH_STENCIL_READ_ONLY_OPTIMAL,
/// SHADER_READ_ONLY_OPTIMAL or GENERAL). Its depths are unprojected with the
/// frame's camera (`CameraMatrices`: projection and `reverse_z`); the far
/// plane's depth means "nothing drawn".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostDepth {
    pub(crate) view: vk::ImageView,
    pub(crate) layout: vk::ImageLayout,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl HostDepth {
    /// The host's depth image `view` of `width` x `height` texels (size and
    /// layout are checked against the frame when it is built).
    ///
    /// # Safety
    /// Whenever a frame built with it executes, `view` is a live,
    /// single-sampled 2D view of the depth aspect, at least `width` x
    /// `height` texels, of an image of the renderer's device created with
    /// `SAMPLED` usage, in `layout` (`Renderer::render` waits for its own
    /// frames).
    pub unsafe fn new(view: vk::ImageView, layout: vk::ImageLayout, width: u32, height: u32) -> Self {
        HostDepth {
            view,
            layout,
            width,
            height,
        }
    }

    fn check(&self, width: u32, height: u32) -> Result<()> {
        let readable = [
            vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
            vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            vk::ImageLayout::GENERAL,
        ];
        if !readable.contains(&self.layout) {
            return Err(Error::invalid(
                "host depth layout",
                format!("{:?}", self.layout),
                "must be a layout shaders sample depth in (DEPTH_READ_ONLY_OPTIMAL, ...)",
            ));
        }
        if (self.width, self.height) != (width, height) {
            return Err(Error::invalid(
                "host depth",
                format!("{}x{}", self.width, self.height),
                format!("the frame is {width}x{height}"),
            ));
        }
        Ok(())
    }
}

/// Every input of one frame besides the scene: size, camera, sampling,
/// early termination, what a ray accumulates and how it is lit, what of the
/// volume is kept, and a host depth image to end rays at. Made by
/// [`FrameDesc::builder`], which validates; read-only after.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameDesc {
    width: u32,
    height: u32,
    camera: Camera,
    step: f32,
    ert: Option<f32>,
    filter: Option<Filter>,
    depth: Option<HostDepth>,
    mode: Mode,
    shading: Option<Shading>,
    clip: Clip,
    jitter: bool,
    segment: Option<[[f32; 3]; 2]>,
}

/// Sets a [`FrameDesc`]'s fields; `build` checks them all.
#[derive(Clone, Copy, Debug)]
pub struct FrameBuilder(FrameDesc);

impl FrameDesc {
    /// A `width` x `height` frame: the default orbit camera (azimuth 30,
    /// elevation 20, orthographic, fitted), step [`DEFAULT_STEP`], early
    /// termination off, the volume's default sample filter
    /// (`GpuVolume::default_filter`), no depth image, composite mode
    /// unshaded, the whole volume, no jitter.
    pub fn builder(width: u32, height: u32) -> FrameBuilder {
        FrameBuilder(FrameDesc {
            width,
            height,
            camera: Camera::default(),
            step: DEFAULT_STEP,
            ert: None,
            filter: None,
            depth: None,
            mode: Mode::Composite,
            shading: None,
            clip: Clip::default(),
            jitter: false,
            segment: None,
        })
    }

    /// This frame's fields, to change some and build again.
    pub fn to_builder(&self) -> FrameBuilder {
        FrameBuilder(*self)
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Sample spacing along each ray, in voxels.
    pub fn step(&self) -> f32 {
        self.step
    }

    /// Early ray termination at this accumulated alpha (None: off).
    pub fn ert(&self) -> Option<f32> {
        self.ert
    }

    /// The sample filter asked for (None: the volume's default).
    pub fn filter(&self) -> Option<Filter> {
        self.filter
    }

    /// The sample filter of this frame on `volume`.
    pub fn filter_for(&self, volume: &GpuVolume) -> Filter {
        self.filter.unwrap_or_else(|| volume.default_filter())
    }

    pub fn depth(&self) -> Option<&HostDepth> {
        self.depth.as_ref()
    }

    /// What a ray accumulates.
    pub fn mode(&self) -> &Mode {
        &self.mode
    }

    /// Gradient shading of composite samples (None: unshaded).
    pub fn shading(&self) -> Option<&Shading> {
        self.shading.as_ref()
    }

    /// The lighting a sample or surface gets: the frame's, or for iso
    /// surfaces (always lit) the default.
    pub fn lighting(&self) -> Option<Shading> {
        match self.mode {
            Mode::Iso(_) => Some(self.shading.unwrap_or_default()),
            _ => self.shading,
        }
    }

    pub fn clip(&self) -> &Clip {
        &self.clip
    }

    /// Whether each pixel's lattice is shifted by a hashed fraction of the step.
    pub fn jitter(&self) -> bool {
        self.jitter
    }

    /// The shader parameter block for `volume` (the volume-dependent checks:
    /// the samples-per-ray cap, rays that stay finite).
    pub fn params(&self, volume: &GpuVolume) -> Result<RenderParams> {
        let mut p = self.params_for(volume.dims, volume.spacing, volume.norm)?;
        p.channel_lo = volume.norms.map(|n| n[0]);
        p.channel_scale = volume.norms.map(|n| n[1]);
        Ok(p)
    }

    /// The checks that need the volume (the samples-per-ray cap, finite
    /// rays), before it is loaded: a volume of `dims` voxels with `spacing`.
    pub fn check_for(&self, dims: [u32; 3], spacing: [f32; 3]) -> Result<()> {
        self.params_for(dims, spacing, [0.0, 1.0]).map(|_| ())
    }

    /// That a naive march of this frame through a `dims` box fits the
    /// loop passes of the device `info` describes (lavapipe caps them;
    /// `limits::check_loop_passes`). `Renderer` checks every frame with it;
    /// auto checks it before it builds or probes anything.
    pub fn check_loop_passes(&self, info: &crate::gpu::DeviceInfo, dims: [u32; 3]) -> Result<()> {
        // Lit composite frames pass twice per visible sample (lattice.glsl, march_lit_run).
        let lit = self.lighting().is_some() && self.mode == Mode::Composite;
        crate::limits::check_loop_passes(&info.name, info.loop_pass_limit, dims, self.step, lit)
    }

    /// As `params`, for a volume of `dims` voxels with `spacing` whose
    /// texels `norm` maps to values (the CPU reference's host volumes).
    pub fn params_for(&self, dims: [u32; 3], spacing: [f32; 3], norm: [f32; 2]) -> Result<RenderParams> {
        crate::limits::check_samples_per_ray(dims, self.step)?;
        self.clip.check_for(dims)?;
        let r = self.camera.rays(dims, spacing, self.width, self.height)?;
        let mut clip = [[0.0; 4]; MAX_CLIP];
        clip[..self.clip.planes().len()].copy_from_slice(self.clip.planes());
        let [crop_lo, crop_hi] = self.clip.crop_box().unwrap_or_default();
        let (iso, iso_count, iso_color) = match &self.mode {
            Mode::Iso(i) => {
                let mut v = [0.0; MAX_ISO];
                v[..i.values().len()].copy_from_slice(i.values());
                (v, i.values().len() as u32, i.color)
            }
            _ => ([0.0; MAX_ISO], 0, None),
        };
        let light = self.lighting().unwrap_or_default();
        // The gradient volume is per shortest voxel side (volume/gradient.rs):
        // the ramp, given per unit of physical length, is scaled to it.
        let shortest = spacing.into_iter().fold(f32::INFINITY, f32::min);
        let [gradient_lo, gradient_hi] = light.gradient_opacity.unwrap_or_default().map(|g| g * shortest);
        Ok(RenderParams {
            base: r.base,
            perspective: r.perspective as u32,
            du: r.du,
            step: self.step,
            dv: r.dv,
            ert: self.ert.unwrap_or(ERT_OFF),
            eye_or_dir: r.eye_or_dir,
            lut_size: crate::tf::LUT_SIZE as u32,
            dims,
            depth_limits: self.depth.is_some() as u32,
            image: [self.width, self.height],
            norm,
            ndc_to_voxel: r.ndc_to_voxel,
            far_depth: r.far_depth,
            jitter: self.jitter as u32,
            clip_count: self.clip.planes().len() as u32,
            crop: self.clip.crop_box().is_some() as u32,
            clip,
            crop_lo,
            iso_count,
            crop_hi,
            iso_colored: iso_color.is_some() as u32,
            iso,
            iso_color: iso_color.unwrap_or_default(),
            gradient_lo,
            light: light.light_dir().unwrap_or_default(),
            headlight: light.light_dir().is_none() as u32,
            shading: [light.ambient, light.diffuse, light.specular, light.shininess],
            spacing,
            gradient_hi,
            gradient_opacity: light.gradient_opacity.is_some() as u32,
            // The TF's: the renderer sets it (`Mode::value_bound`).
            value_bound: self.mode.value_bound(None),
            value_margin: crate::volume::value_margin(norm),
            // The renderer sets where iso depth goes (`DepthOut`).
            depth_out: 0,
            voxel_to_ndc: r.voxel_to_ndc.unwrap_or_default(),
            no_hit_depth: match self.camera_has_ndc() {
                true => r.far_depth,
                false => f32::INFINITY,
            },
            // Several channels: the volume's and the TF's (`params`, the renderer).
            tf_channel_step: 0,
            channel_pad0: 0,
            channel_pad1: 0,
            channel_lo: [norm[0], 0.0, 0.0, 0.0],
            channel_scale: [norm[1], 0.0, 0.0, 0.0],
            segment_lo: self.segment.unwrap_or_default()[0],
            segment: self.segment.is_some() as u32,
            segment_hi: self.segment.unwrap_or_default()[1],
            segment_pad: 0,
        })
    }

    /// Whether the camera has NDC (host matrices): iso depth is written as
    /// NDC depth, else as a distance (`render::HostDepthOut`).
    pub fn camera_has_ndc(&self) -> bool {
        matches!(self.camera, Camera::Matrices(_))
    }

    /// Whether the frame's depth output holds each ray's value instead of
    /// a depth: a segment's (a rank's part) MIP or MinIP frame, whose
    /// ranks keep the colour of the largest (smallest) value
    /// (`crate::parallel::pick`). -1 (2) where no sample shows (past `Mode::value_bound`).
    pub fn writes_ray_values(&self) -> bool {
        self.segment.is_some() && matches!(self.mode, Mode::Mip | Mode::MinIp)
    }

    /// Whether the frame writes its depth output: iso frames (the surface's
    /// depth) and `writes_ray_values`.
    pub fn writes_depth(&self) -> bool {
        matches!(self.mode, Mode::Iso(_)) || self.writes_ray_values()
    }

    /// (name, value) pairs for printouts and frame metadata.
    pub fn describe(&self, volume: &GpuVolume) -> Vec<(&'static str, String)> {
        let mut out = vec![
            ("camera", self.camera.describe()),
            ("step", self.step.to_string()),
            ("ert", self.ert.map_or("off".into(), |e| e.to_string())),
            ("filter", self.filter_for(volume).to_string()),
        ];
        out.extend(self.describe_look());
        out
    }

    /// (name, value) pairs of what differs from a plain composite frame of
    /// the whole box, in `render`'s flag syntax.
    pub fn describe_look(&self) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        if self.mode != Mode::Composite {
            out.push(("mode", self.mode.name().into()));
        }
        if let Mode::Iso(i) = &self.mode {
            let values: Vec<String> = i.values().iter().map(|v| v.to_string()).collect();
            out.push(("iso", values.join(",")));
            if let Some([r, g, b]) = i.color {
                out.push(("iso_color", format!("{r},{g},{b}")));
            }
        }
        if let Some(s) = self.lighting() {
            out.push(("shade", s.describe()));
        }
        for (i, [a, b, c, d]) in self.clip.planes().iter().enumerate() {
            let key = ["clip0", "clip1", "clip2", "clip3", "clip4", "clip5"][i];
            out.push((key, format!("{a},{b},{c},{d}")));
        }
        if let Some([lo, hi]) = self.clip.crop_box() {
            let axes: Vec<String> = (0..3).map(|a| format!("{}:{}", lo[a], hi[a])).collect();
            out.push(("crop", axes.join(",")));
        }
        if self.jitter {
            out.push(("jitter", "on".into()));
        }
        if let Some([lo, hi]) = self.segment {
            let axes: Vec<String> = (0..3).map(|a| format!("{}:{}", lo[a], hi[a])).collect();
            out.push(("segment", axes.join(",")));
        }
        out
    }
}

impl FrameBuilder {
    pub fn camera(mut self, camera: Camera) -> Self {
        self.0.camera = camera;
        self
    }

    /// An orbit camera at `azimuth`, `elevation` degrees.
    pub fn orbit(self, azimuth_deg: f64, elevation_deg: f64, projection: Projection) -> Self {
        self.camera(Camera::Orbit(Orbit {
            azimuth_deg,
            elevation_deg,
            projection,
        }))
    }

    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.0.width = width;
        self.0.height = height;
        self
    }

    /// Sample spacing along each ray, in voxels (> 0).
    pub fn step(mut self, voxels: f32) -> Self {
        self.0.step = voxels;
        self
    }

    /// Early ray termination at this accumulated alpha in (0, 1]; None: off.
    pub fn ert(mut self, alpha: Option<f32>) -> Self {
        self.0.ert = alpha;
        self
    }

    /// How samples are reconstructed between voxels (hardware filtering
    /// needs a volume format the device filters linearly).
    pub fn filter(mut self, filter: Filter) -> Self {
        self.0.filter = Some(filter);
        self
    }

    /// The volume's default sample filter (`GpuVolume::default_filter`).
    pub fn default_filter(mut self) -> Self {
        self.0.filter = None;
        self
    }

    /// Rays end at the host's depth image (of the frame's size).
    pub fn depth(mut self, depth: Option<HostDepth>) -> Self {
        self.0.depth = depth;
        self
    }

    /// What a ray accumulates (default composite).
    pub fn mode(mut self, mode: Mode) -> Self {
        self.0.mode = mode;
        self
    }

    /// Gradient shading of composite samples, and the lighting of iso
    /// surfaces (None: composite unshaded; iso lit by the default).
    pub fn shading(mut self, shading: Option<Shading>) -> Self {
        self.0.shading = shading;
        self
    }

    /// What of the volume is kept.
    pub fn clip(mut self, clip: Clip) -> Self {
        self.0.clip = clip;
        self
    }

    /// Shifts each pixel's lattice by a hashed fraction of the step.
    pub fn jitter(mut self, on: bool) -> Self {
        self.0.jitter = on;
        self
    }

    /// One part of a data-parallel frame (`crate::parallel`): only the
    /// lattice samples inside the box `[lo, hi]` (voxel space), each
    /// weighted as the whole frame weights it, so the parts of boxes that
    /// tile the volume, blended front to back, are the whole frame. Unlike
    /// a crop, the box does not end the ray: its last sample keeps its step.
    pub fn segment(mut self, segment: Option<[[f32; 3]; 2]>) -> Self {
        self.0.segment = segment;
        self
    }

    /// The frame, every field checked.
    pub fn build(self) -> Result<FrameDesc> {
        let d = self.0;
        let side = crate::limits::MAX_FRAME_SIDE;
        if d.width == 0 || d.height == 0 || d.width > side || d.height > side {
            return Err(Error::invalid(
                "size",
                format!("{}x{}", d.width, d.height),
                format!("width and height must be in 1..={side} pixels"),
            ));
        }
        // The frame buffer's readback and the frame itself.
        crate::limits::check_host(
            format_args!("frame {}x{}", d.width, d.height),
            d.width as u64 * d.height as u64,
            32,
        )?;
        if !(d.step.is_finite() && d.step > 0.0) {
            return Err(Error::invalid(
                "step",
                d.step.to_string(),
                "must be a finite number > 0 (voxels)",
            ));
        }
        if let Some(e) = d.ert {
            if !(e > 0.0 && e <= 1.0) {
                return Err(Error::invalid("ert", e.to_string(), "must be in (0, 1]"));
            }
        }
        d.camera.validate()?;
        if let Some(depth) = &d.depth {
            depth.check(d.width, d.height)?;
        }
        mode::validate(&d.mode, &d.shading, d.ert)?;
        if let Some([lo, hi]) = d.segment {
            if !lo.iter().chain(&hi).all(|v| v.is_finite()) || (0..3).any(|a| lo[a] > hi[a]) {
                return Err(Error::invalid(
                    "segment",
                    format!("{lo:?} to {hi:?}"),
                    "must be finite, LO <= HI per axis",
                ));
            }
            // Parts blend front to back (composite), keep the extreme ray
            // value (MIP, MinIP) or the nearest surface (iso); an
            // average's mean is no join of the parts' colours.
            if d.mode == Mode::Average {
                return Err(Error::invalid(
                    "segment",
                    d.mode.name(),
                    "parts of a frame join in composite, mip, minip and iso modes only",
                ));
            }
        }
        Ok(d)
    }
}
