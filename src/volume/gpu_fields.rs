//! What a host engine reads of an uploaded volume, to bind it in its own
//! passes or place its camera: read-only, since every kernel lacuna
//! records trusts these to describe the memory the volume owns.

use super::cells::TexelKind;
use super::{GpuVolume, MAX_CHANNELS};
use crate::gpu::{vk, Image3d};

impl GpuVolume {
    /// The texels: the dense 3D image, or the brick pool's first image.
    pub fn image(&self) -> &Image3d {
        &self.image
    }

    /// The nearest sampler every `texelFetch` user binds.
    pub fn sampler(&self) -> vk::Sampler {
        self.sampler
    }

    /// Voxels along x, y and z.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// The voxel spacing along x, y and z.
    pub fn spacing(&self) -> [f32; 3] {
        self.spacing
    }

    /// Channel 1's texel normalisation, as `Volume::norm`.
    pub fn norm(&self) -> [f32; 2] {
        self.norm
    }

    /// How many channels each texel holds.
    pub fn channels(&self) -> u32 {
        self.channels
    }

    /// Each channel's texel normalisation (unused channels: [0, 0]).
    pub fn norms(&self) -> [[f32; 2]; MAX_CHANNELS] {
        self.norms
    }

    /// Whether it holds NaN voxels (no data).
    pub fn has_nan(&self) -> bool {
        self.has_nan
    }

    /// How its texels are stored.
    pub fn kind(&self) -> TexelKind {
        self.kind
    }
}
