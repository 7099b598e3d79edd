//! What a frame fixes in the march kernel that marches it: the
//! specialization constants of its sample filter, mode and shading, and of
//! the volume it samples (NaN voxels, texel kind, cells copy, channels,
//! bricked storage). One kernel is
//! compiled per distinct set (`render::Renderer`, `accel::probe`), so no
//! sample branches on any of them.

use super::{FrameDesc, Mode, MODE_CONSTANT_ID, SHADE_CONSTANT_ID, SHININESS_CONSTANT_ID};
use crate::volume::{
    Filter, GpuVolume, BRICK_CONSTANT_ID, CELLS_CONSTANT_ID, CHANNELS_CONSTANT_ID, FILTER_CONSTANT_ID,
    GRADIENT_CELLS_CONSTANT_ID, KIND_CONSTANT_ID, NAN_CONSTANT_ID, POOL_IMAGES_CONSTANT_ID,
};

/// The frame's and volume's constants, in a fixed order: (constant_id, value).
pub type KernelConstants = [(u32, u32); 12];

/// `constant_id` of `MARCH_CUTS` in `glsl/common/lattice.glsl`.
pub const CUTS_CONSTANT_ID: u32 = 30;
/// `MARCH_CUTS`'s bits (`CUT_*` in `glsl/common/lattice.glsl`): jitter, a
/// host depth image, clip planes or a crop box, a rank's segment of the
/// ray, and a frame that writes its rays' depth.
pub const CUT_JITTER: u32 = 1;
pub const CUT_DEPTH: u32 = 2;
pub const CUT_CLIP: u32 = 4;
pub const CUT_SEGMENT: u32 = 8;
pub const CUT_DEPTH_OUT: u32 = 16;

/// `constants` for a frame that writes its rays' depth (or not).
pub fn with_depth_out(mut constants: KernelConstants, writes: bool) -> KernelConstants {
    for (id, v) in &mut constants {
        if *id == CUTS_CONSTANT_ID {
            *v = (*v & !CUT_DEPTH_OUT) | if writes { CUT_DEPTH_OUT } else { 0 };
        }
    }
    constants
}

impl FrameDesc {
    /// The constants of a march kernel for this frame on `volume`: the
    /// filter (`filter_for`), the mode, whether composite samples are lit
    /// (iso surfaces are always lit, by their own path) and with gradient
    /// opacity, a lit frame's whole Phong exponent, whether the volume has
    /// NaN voxels, how its texels are stored, whether the manual filter
    /// reads its cells copy and (lit frames) the gradient's, how many
    /// channels it has, its pool's brick edge (0: dense) and images, and
    /// which cuts of a ray's interval the frame has (`cuts_constant`).
    pub fn kernel_constants(&self, volume: &GpuVolume) -> KernelConstants {
        let filter = self.filter_for(volume);
        let shade = matches!(self.mode(), Mode::Composite) && self.shading().is_some();
        let cells = filter == Filter::Manual && volume.cells().is_some();
        let lit = shade || matches!(self.mode(), Mode::Iso(_));
        let gradient_cells = filter == Filter::Manual && lit && volume.gradient_cells().is_some();
        let shininess = match (lit, self.lighting()) {
            (true, Some(l)) => l.whole_shininess(),
            _ => 0,
        };
        [
            (FILTER_CONSTANT_ID, filter.constant()),
            (MODE_CONSTANT_ID, self.mode().constant()),
            (SHADE_CONSTANT_ID, shade_constant(shade, self)),
            (SHININESS_CONSTANT_ID, shininess),
            (NAN_CONSTANT_ID, volume.has_nan as u32),
            (KIND_CONSTANT_ID, volume.kind.constant()),
            (CELLS_CONSTANT_ID, cells as u32),
            (GRADIENT_CELLS_CONSTANT_ID, gradient_cells as u32),
            (CHANNELS_CONSTANT_ID, volume.channels),
            (BRICK_CONSTANT_ID, volume.brick_edge()),
            (POOL_IMAGES_CONSTANT_ID, volume.pool_image_count()),
            (CUTS_CONSTANT_ID, self.cuts_constant()),
        ]
    }

    /// `MARCH_CUTS`: the `CUT_*` bits of the cuts this frame's rays have
    /// ([`CUT_DEPTH_OUT`] is the target's, set by [`with_depth_out`]). A
    /// ray has only the code of what its frame does.
    pub fn cuts_constant(&self) -> u32 {
        let clipped = !self.clip.planes().is_empty() || self.clip.crop_box().is_some();
        [
            (self.jitter, CUT_JITTER),
            (self.depth.is_some(), CUT_DEPTH),
            (clipped, CUT_CLIP),
            (self.segment.is_some(), CUT_SEGMENT),
        ]
        .iter()
        .filter(|(has, _)| *has)
        .fold(0, |bits, (_, bit)| bits | bit)
    }
}

/// `MARCH_SHADE`: 0 unlit, 1 lit, 2 lit with gradient opacity.
fn shade_constant(shade: bool, desc: &FrameDesc) -> u32 {
    match desc.lighting() {
        Some(l) if shade && l.gradient_opacity.is_some() => 2,
        _ => shade as u32,
    }
}
