//! `RenderParams`: the std140 uniform block of `glsl/common/render_params.glsl`.

use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RenderParams {
    /// Voxel-space point of pixel (0, 0)'s corner: pixel (x, y) samples
    /// `base + (x + 0.5) * du + (y + 0.5) * dv`.
    pub base: [f32; 4],
    pub du: [f32; 4],
    pub dv: [f32; 4],
    /// xyz: orthographic direction or perspective eye; w: 0 ortho, 1 perspective.
    pub eye_or_dir: [f32; 4],
    /// xyz: volume dims; w: LUT entries.
    pub dims: [u32; 4],
    /// x, y: image size.
    pub image: [u32; 4],
    /// x: dt (voxels); y: ERT alpha (> 1 = off); z, w: texel normalisation.
    pub march: [f32; 4],
}

/// ERT threshold meaning "off": accumulated alpha never exceeds 1.
pub const ERT_OFF: f32 = 2.0;
