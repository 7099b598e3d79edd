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

use super::{Volume, VoxelData};
use half::{f16, slice::HalfFloatSliceExt};
use rayon::prelude::*;

/// Bytes per gradient texel.
pub const GRADIENT_TEXEL_BYTES: u64 = 8;

/// The gradient texels of `volume`, x fastest.
pub fn gradient_texels(volume: &Volume) -> Vec<[f16; 4]> {
    let shortest = volume.spacing.into_iter().fold(f32::INFINITY, f32::min);
    let scale = volume.spacing.map(|s| 0.5 * volume.norm[1] * shortest / s);
    match &volume.data {
        VoxelData::U8(v) => gradient_rows(volume.dims, scale, |i| v[i] as f32 / 255.0),
        VoxelData::U16(v) => gradient_rows(volume.dims, scale, |i| v[i] as f32 / 65535.0),
        VoxelData::F32(v) => gradient_rows(volume.dims, scale, |i| v[i]),
        VoxelData::Bricks(_) => gradient_rows(volume.dims, scale, |i| volume.data.texel(i)),
    }
}

/// Central differences of the texels `texel` reads (by voxel index), a
/// row at a time: the row's differences in f32, then converted to f16 as
/// one slice (vector instructions where the CPU has them).
fn gradient_rows(dims: [u32; 3], scale: [f32; 3], texel: impl Fn(usize) -> f32 + Sync) -> Vec<[f16; 4]> {
    let [w, h, d] = dims.map(|n| n as usize);
    let mut out = vec![[f16::ZERO; 4]; w * h * d];
    out.par_chunks_mut(w.max(1)).enumerate().for_each_init(
        || vec![0f32; 4 * w],
        |row, (r, out)| {
            let (y, z) = (r % h, r / h);
            let at = |y: usize, z: usize| (y + h * z) * w;
            let here = at(y, z);
            let (down, up) = (at(y.saturating_sub(1), z), at((y + 1).min(h - 1), z));
            let (back, front) = (at(y, z.saturating_sub(1)), at(y, (z + 1).min(d - 1)));
            for (x, g) in row.chunks_exact_mut(4).enumerate() {
                let (left, right) = (x.saturating_sub(1), (x + 1).min(w - 1));
                g[0] = (texel(here + right) - texel(here + left)) * scale[0];
                g[1] = (texel(up + x) - texel(down + x)) * scale[1];
                g[2] = (texel(front + x) - texel(back + x)) * scale[2];
            }
            out.as_flattened_mut().convert_from_f32_slice(row);
        },
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{VoxelData, VoxelType};

    /// The row-wise gradient against central differences voxel by voxel,
    /// bit for bit, on odd dims of every kind (a NaN among the floats).
    #[test]
    fn gradient_rows_equal_differences_voxel_by_voxel() {
        for v in crate::volume::cells::tests::odd_volumes([1.0, 2.0, 0.5]) {
            let dims = v.dims;
            let ty = v.source_type;
            let scale = v.spacing.map(|s| 0.5 * v.norm[1] * 0.5 / s);
            let [w, h, d] = dims.map(|n| n as i64);
            let texel = |x: i64, y: i64, z: i64| {
                v.data.texel(v.index(
                    x.clamp(0, w - 1) as u32,
                    y.clamp(0, h - 1) as u32,
                    z.clamp(0, d - 1) as u32,
                ))
            };
            let got = gradient_texels(&v);
            for z in 0..d {
                for y in 0..h {
                    for x in 0..w {
                        let want = [
                            (texel(x + 1, y, z) - texel(x - 1, y, z)) * scale[0],
                            (texel(x, y + 1, z) - texel(x, y - 1, z)) * scale[1],
                            (texel(x, y, z + 1) - texel(x, y, z - 1)) * scale[2],
                        ]
                        .map(|g| f16::from_f32(g).to_bits());
                        let g = got[v.index(x as u32, y as u32, z as u32)];
                        assert_eq!([g[0], g[1], g[2]].map(f16::to_bits), want, "{ty:?} at {x},{y},{z}");
                    }
                }
            }
        }
    }

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
