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

// Every march kernel reads the block at binding 0.
const _: () = {
    use crate::gpu::shaders::*;
    let size = std::mem::size_of::<RenderParams>() as u32;
    assert!(
        size == MARCH_NAIVE.block_sizes[0],
        "RenderParams does not match render_params.glsl"
    );
    assert!(
        size == MARCH_BVH.block_sizes[0],
        "RenderParams does not match render_params.glsl"
    );
    assert!(
        size == MARCH_GRID.block_sizes[0],
        "RenderParams does not match render_params.glsl"
    );
    assert!(
        size == MARCH_HYBRID.block_sizes[0],
        "RenderParams does not match render_params.glsl"
    );
    assert!(
        size == MARCH_OCTREE.block_sizes[0],
        "RenderParams does not match render_params.glsl"
    );
};

/// ERT threshold meaning "off": accumulated alpha never exceeds 1.
pub const ERT_OFF: f32 = 2.0;
