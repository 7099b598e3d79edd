//! The gradient's cells copy (`cells.rs` for the volume's): per cell its
//! eight corners' (x, y, z) half-float gradients, which a lit sample of
//! the manual filter reads in three fetches instead of eight.

use super::cells::{cell_dims, cell_layers, check_texel_copy, host_shared, LAYER_BYTES};
use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, Context, DeviceInfo, MemoryLocation, TexelBuffer};

/// Words (u32) per cell of the gradient's cells copy: eight corners of three
/// f16 components, two halves a word.
const GRADIENT_WORDS: usize = 12;

/// Bytes per voxel of the gradient's cells copy (`GpuVolume::add_gradient`
/// makes it beside the volume's cells copy): 48.
pub const GRADIENT_CELL_BYTES: u64 = 4 * GRADIENT_WORDS as u64;

/// Whether the device can hold the gradient's cells copy of a volume of
/// `dims` (as `check_cells`).
pub fn check_gradient_cells(info: &DeviceInfo, dims: [u32; 3]) -> Result<u64> {
    let bytes = cell_dims(dims)
        .iter()
        .fold(GRADIENT_CELL_BYTES, |acc, &n| acc.saturating_mul(n));
    check_texel_copy(
        info,
        "gradient cells copy",
        dims,
        3,
        bytes,
        vk::Format::R32G32B32A32_UINT,
    )
}

/// Packs the gradient's cell layers from `first` on into `out`: per cell
/// the eight corners' (x, y, z) halves of `gradient` (the volume's gradient
/// texels, `dims`), corner-major, as the words' little-endian halves.
fn pack_gradient_layers(gradient: &[[half::f16; 4]], dims: [u32; 3], first: u64, out: &mut [u16]) {
    cell_layers(
        gradient,
        dims,
        first as usize,
        out,
        2 * GRADIENT_WORDS,
        |cell, corners| {
            for (b, g) in corners.iter().enumerate() {
                for c in 0..3 {
                    cell[3 * b + c] = g[c].to_bits();
                }
            }
        },
        None,
    );
}

/// The gradient's cells copy on the device: packed in place where the
/// device's memory is the host's (`host_shared`), else uploaded layer block
/// by layer block and waited for.
pub fn upload_gradient_cells(ctx: &Context, gradient: &[[half::f16; 4]], dims: [u32; 3]) -> Result<TexelBuffer> {
    let bytes = check_gradient_cells(ctx.info(), dims)?;
    let format = vk::Format::R32G32B32A32_UINT;
    let usage = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
    if host_shared(ctx) {
        let buffer = Buffer::new(ctx, "gradient cells", bytes, usage, MemoryLocation::CpuToGpu)?;
        let mut cells = TexelBuffer::new(ctx, buffer, format)?;
        repack_gradient_shared(&mut cells, gradient, dims)?;
        return Ok(cells);
    }
    let buffer = Buffer::upload_target(ctx, "gradient cells", bytes, usage)?;
    let [cw, ch, cd] = cell_dims(dims);
    let layer = cw * ch * GRADIENT_CELL_BYTES;
    let per_upload = (LAYER_BYTES / layer).max(1);
    let mut k = 0;
    while k < cd {
        let end = (k + per_upload).min(cd);
        let mut halves = vec![0u16; ((end - k) * layer / 2) as usize];
        pack_gradient_layers(gradient, dims, k, &mut halves);
        buffer.upload(k * layer, bytemuck::cast_slice(&halves))?;
        k = end;
    }
    TexelBuffer::new(ctx, buffer, format)
}

/// As `repack_shared`, for the gradient's cells copy of `dims`.
pub fn repack_gradient_shared(cells: &mut TexelBuffer, gradient: &[[half::f16; 4]], dims: [u32; 3]) -> Result<()> {
    let [cw, ch, cd] = cell_dims(dims);
    let bytes = (cw * ch * cd * GRADIENT_CELL_BYTES) as usize;
    let out = cells.host_mut()?;
    if out.len() < bytes {
        return Err(Error::Interface(format!(
            "gradient cells copy of {} bytes for {bytes}",
            out.len()
        )));
    }
    pack_gradient_layers(gradient, dims, 0, bytemuck::cast_slice_mut(&mut out[..bytes]));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gradient_cell_holds_its_corners_halves_in_order() {
        let dims = [2u32, 2, 1];
        let g: Vec<[half::f16; 4]> = (0..4)
            .map(|v| [1.0, 2.0, 3.0].map(|c| half::f16::from_f32(c + 10.0 * v as f32)))
            .map(|[x, y, z]| [x, y, z, half::f16::ZERO])
            .collect();
        let mut halves = vec![0u16; 3 * 3 * 2 * 2 * GRADIENT_WORDS];
        pack_gradient_layers(&g, dims, 0, &mut halves);
        let words: Vec<u32> = bytemuck::cast_slice(&halves).to_vec();
        // Packing in blocks of layers gives the same halves.
        let layer = halves.len() / 2;
        let mut blocks = vec![0u16; halves.len()];
        for k in 0..2 {
            pack_gradient_layers(&g, dims, k as u64, &mut blocks[k * layer..(k + 1) * layer]);
        }
        assert_eq!(blocks, halves);
        // Cell (0, 0, 0): texel 1 + 3 * (1 + 3 * 1) = 13; corner b is voxel
        // (b & 1, b >> 1 & 1, 0) (z clamps).
        let cell = &words[13 * GRADIENT_WORDS..14 * GRADIENT_WORDS];
        let halves: Vec<f32> = cell
            .iter()
            .flat_map(|w| [*w as u16, (*w >> 16) as u16])
            .map(|b| half::f16::from_bits(b).to_f32())
            .collect();
        for b in 0..8usize {
            let v = (b & 1) + 2 * (b >> 1 & 1);
            let want = [1.0, 2.0, 3.0].map(|c| c + 10.0 * v as f32);
            assert_eq!(&halves[3 * b..3 * b + 3], &want, "corner {b}");
        }
    }
}
