//! The volume's gradient for shading: per voxel, central differences of
//! the normalised values one voxel apart (clamped at the edges, as the
//! sampler clamps), stored as RGBA16F (x, y, z, 0) in normalised value per
//! voxel. Interpolated trilinearly at a sample, this *is* the central
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
    let scale = 0.5 * volume.norm[1];
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
                    (texel(x + 1, y, z) - texel(x - 1, y, z)) * scale,
                    (texel(x, y + 1, z) - texel(x, y - 1, z)) * scale,
                    (texel(x, y, z + 1) - texel(x, y, z - 1)) * scale,
                ];
                [f16::from_f32(g[0]), f16::from_f32(g[1]), f16::from_f32(g[2]), f16::ZERO]
            })
        })
        .collect()
}
