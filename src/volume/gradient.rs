//! The volume's gradient for shading: per voxel, central differences of
//! the normalised values one voxel apart (clamped at the edges, as the
//! sampler clamps), stored as RGBA16F (x, y, z, 0) in normalised value per
//! shortest voxel side: each axis divided by its spacing over the shortest
//! here, once, rather than at every lit sample, and not by the spacing
//! itself, which would overflow f16 on a micrometre grid (the
//! gradient-opacity ramp is scaled to match: `FrameDesc::params_for`).
//! Interpolated trilinearly at a sample, this *is* the central
//! difference of the trilinear field at that sample (each axis' difference
//! of two interpolations with the same weights is the interpolation of the
//! differences), read with one filtered fetch instead of six. Computed on
//! the host so its rounding to f16 is the same everywhere (the CPU
//! reference reads these very values). A NaN voxel makes its neighbours'
//! gradients NaN: shading there is unlit (`glsl/common/light.glsl`).

use super::Volume;
use half::f16;
use rayon::prelude::*;

/// Bytes per gradient texel.
pub const GRADIENT_TEXEL_BYTES: u64 = 8;

/// The gradient texels of `volume`, x fastest.
pub fn gradient_texels(volume: &Volume) -> Vec<[f16; 4]> {
    let [w, h, d] = volume.dims.map(|n| n as i64);
    let shortest = volume.spacing.into_iter().fold(f32::INFINITY, f32::min);
    let scale = volume.spacing.map(|s| 0.5 * volume.norm[1] * shortest / s);
    let texel = |x: i64, y: i64, z: i64| {
        let c = [x.clamp(0, w - 1), y.clamp(0, h - 1), z.clamp(0, d - 1)];
        volume.data.texel(volume.index(c[0] as u32, c[1] as u32, c[2] as u32))
    };
    (0..d * h)
        .into_par_iter()
        .flat_map_iter(|zy| {
            let (z, y) = (zy / h, zy % h);
            (0..w).map(move |x| {
                let g = [
                    (texel(x + 1, y, z) - texel(x - 1, y, z)) * scale[0],
                    (texel(x, y + 1, z) - texel(x, y - 1, z)) * scale[1],
                    (texel(x, y, z + 1) - texel(x, y, z - 1)) * scale[2],
                ];
                [f16::from_f32(g[0]), f16::from_f32(g[1]), f16::from_f32(g[2]), f16::ZERO]
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{VoxelData, VoxelType};

    /// A ramp along x and z on a micrometre grid, z voxels twice as long:
    /// per unit of physical length its gradient (~1.6e5) would overflow
    /// f16; per shortest side it is finite, and z keeps its share.
    #[test]
    fn tiny_spacings_keep_gradients_finite_and_in_proportion() {
        let values: Vec<u8> = (0..64).map(|i| ((i % 4) * 40 + (i / 16) * 20) as u8).collect();
        let spacing = [1e-6, 1e-6, 2e-6];
        let volume = Volume::new("ramp", [4, 4, 4], spacing, VoxelType::U8, VoxelData::U8(values)).unwrap();
        let g = gradient_texels(&volume)[volume.index(1, 1, 1)].map(|c| c.to_f32());
        // Normalised over the range 0..180: per voxel 40/180 along x and
        // 20/180 along z, whose voxel is two sides long.
        let want = [40.0 / 180.0, 0.0, 10.0 / 180.0];
        for (got, want) in g.iter().zip(want) {
            assert!((got - want).abs() < 1e-3, "{g:?} against {want}");
        }
    }
}
