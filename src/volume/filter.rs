//! How the march kernels reconstruct the volume between voxels: by hand
//! (eight `texelFetch`, full f32 weights, as the CPU reference) or by the
//! sampler's own linear filtering (one fetch, weights of the device's
//! `subTexelPrecisionBits`). Each march kernel is compiled for one filter
//! through a specialization constant, so no sample pays a branch.

use crate::error::{Error, Result};

/// How a sample is interpolated from the voxels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Filter {
    /// Trilinear from eight `texelFetch` in f32: the same on every device.
    #[default]
    Manual,
    /// The sampler's linear filtering: needs the volume format's
    /// `SAMPLED_IMAGE_FILTER_LINEAR` feature (optional for R16 and R32F).
    Hardware,
}

/// `constant_id` of `VOLUME_FILTER` in `glsl/common/volume.glsl`; above the
/// ids structures use for their own constants (0, 1, ...).
pub const FILTER_CONSTANT_ID: u32 = 16;

/// `constant_id` of `VOLUME_NAN` in `glsl/common/volume.glsl`: 1 for volumes
/// with NaN voxels, whose samples the march tests.
pub const NAN_CONSTANT_ID: u32 = 19;

/// How far an interpolated sample of a volume with texel normalisation
/// `norm` can lie beyond the normalised range of its eight voxels, under
/// either filter: the rounding of the trilinear weights and sums (relative
/// to the largest texel magnitude, scaled by the normalisation) and of a
/// hardware filter's fixed-point weights, with room to spare. Structures
/// that compare samples with value ranges (MIP, MinIP) widen them by it.
pub fn value_margin(norm: [f32; 2]) -> f32 {
    let [lo, scale] = norm;
    let rounding = if scale != 0.0 {
        let magnitude = lo.abs().max((lo + 1.0 / scale).abs());
        64.0 * f32::EPSILON * magnitude * scale.abs()
    } else {
        0.0
    };
    1.0 / 65536.0 + rounding
}

impl Filter {
    pub const ALL: [Filter; 2] = [Filter::Manual, Filter::Hardware];

    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "manual" => Ok(Filter::Manual),
            "hardware" => Ok(Filter::Hardware),
            _ => Err(Error::invalid("filter", s, "expected manual or hardware")),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Filter::Manual => "manual",
            Filter::Hardware => "hardware",
        }
    }

    /// The value of `VOLUME_FILTER` in the shaders.
    pub fn constant(self) -> u32 {
        match self {
            Filter::Manual => 0,
            Filter::Hardware => 1,
        }
    }

    /// The faster filter where both are available: hardware. Measured on
    /// lavapipe (README, "Sample filter") and true of GPUs, whose texture
    /// units filter for free; manual where the format does not filter.
    pub fn device_default(filters_linearly: bool) -> Self {
        if filters_linearly {
            Filter::Hardware
        } else {
            Filter::Manual
        }
    }
}

impl std::fmt::Display for Filter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Filter {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Self::parse(s)
    }
}
