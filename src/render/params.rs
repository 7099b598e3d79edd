//! `RenderParams`: the fixed part of the storage block of
//! `glsl/common/render_params.glsl` (the per-pixel depth limits follow it in
//! the same buffer). Build it with `CameraMatrices::params` / `View`, not by hand.

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
    /// NDC (x, y, depth, 1) to homogeneous voxel space: unprojects a host depth.
    pub ndc_to_voxel: [[f32; 4]; 4],
    /// x: the depth of the far plane (0 or 1: no surface); y: 1 when each
    /// ray ends at its per-pixel limit (the `t_max` array after this block).
    pub depth: [f32; 4],
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
