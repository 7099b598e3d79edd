//! The volume's cells copy: for every cell of the sample lattice, the eight
//! voxels a trilinear sample in it reads, in one texel of a uniform texel
//! buffer. The manual filter then fetches one texel per sample instead of
//! eight (`glsl/common/volume.glsl`, `cell_voxels`), with the same values
//! and the same arithmetic, so its samples are the same bit for bit. On a
//! CPU device, where every fetch is a gather of eight lanes, that makes the
//! exact filter faster than the sampler's (README, "Sample filter"); it
//! costs `bytes_per_voxel` (8, 16 or 32) bytes per voxel.
//!
//! Cell (i, j, k) for i in -1..W-1 (and so on) sits at texel
//! `(i + 1) + (W + 1) * ((j + 1) + (H + 1) * (k + 1))` and holds the voxels
//! `clamp(i + dx, j + dy, k + dz)`, x fastest: unorm8 as the bytes of two
//! words, unorm16 as the 16-bit halves of four, float32 as the bits of
//! eight (two texels).

use super::{Volume, VoxelData};
use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, Context, DeviceInfo, Staging, TexelBuffer};
use rayon::prelude::*;

/// How a volume's texels are stored, as the march kernels' `VOLUME_KIND`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TexelKind {
    Float32,
    Unorm8,
    Unorm16,
}

/// `constant_id` of `VOLUME_KIND` in `glsl/common/volume.glsl`.
pub const KIND_CONSTANT_ID: u32 = 20;
/// `constant_id` of `VOLUME_CELLS`: 1 when the manual filter reads the cells copy.
pub const CELLS_CONSTANT_ID: u32 = 21;
/// `constant_id` of `GRADIENT_CELLS`: 1 when the manual filter reads the
/// gradient's cells copy.
pub const GRADIENT_CELLS_CONSTANT_ID: u32 = 25;

impl TexelKind {
    pub fn of(data: &VoxelData) -> TexelKind {
        match data.texel_bytes() {
            1 => TexelKind::Unorm8,
            2 => TexelKind::Unorm16,
            _ => TexelKind::Float32,
        }
    }

    /// The value of `VOLUME_KIND` in the shaders.
    pub fn constant(self) -> u32 {
        match self {
            TexelKind::Float32 => 0,
            TexelKind::Unorm8 => 1,
            TexelKind::Unorm16 => 2,
        }
    }

    /// Words (u32) per cell of the cells copy.
    fn words(self) -> usize {
        match self {
            TexelKind::Unorm8 => 2,
            TexelKind::Unorm16 => 4,
            TexelKind::Float32 => 8,
        }
    }

    /// Bytes per cell (about one cell per voxel).
    pub fn bytes_per_voxel(self) -> u64 {
        4 * self.words() as u64
    }

    /// The texel format of the cells copy and texels per cell.
    fn format(self) -> (vk::Format, u64) {
        match self {
            TexelKind::Unorm8 => (vk::Format::R32G32_UINT, 1),
            TexelKind::Unorm16 => (vk::Format::R32G32B32A32_UINT, 1),
            TexelKind::Float32 => (vk::Format::R32G32B32A32_UINT, 2),
        }
    }
}

/// Cells per axis: one more than voxels (the cells below voxel 0 too).
fn cell_dims(dims: [u32; 3]) -> [u64; 3] {
    dims.map(|d| d as u64 + 1)
}

/// Bytes of the cells copy of a volume of `dims` and `kind`.
pub fn cells_bytes(dims: [u32; 3], kind: TexelKind) -> u64 {
    cell_dims(dims)
        .iter()
        .fold(kind.bytes_per_voxel(), |acc, &n| acc.saturating_mul(n))
}

/// Whether the device can hold the cells copy of a volume of `dims`: its
/// texels within `maxTexelBufferElements`, its bytes within
/// `maxMemoryAllocationSize` and the device-local heap; the error names
/// the limit.
pub fn check_cells(info: &DeviceInfo, dims: [u32; 3], kind: TexelKind) -> Result<u64> {
    let (format, per_cell) = kind.format();
    check_texel_copy(info, "cells copy", dims, per_cell, cells_bytes(dims, kind), format)
}

/// Checks a per-cell copy of `per_cell` texels of `format` (`bytes` in
/// all) against the texel-buffer, allocation and heap limits.
fn check_texel_copy(
    info: &DeviceInfo,
    copy: &str,
    dims: [u32; 3],
    per_cell: u64,
    bytes: u64,
    format: vk::Format,
) -> Result<u64> {
    let texels = cell_dims(dims).iter().fold(per_cell, |acc, &n| acc.saturating_mul(n));
    let what = format!(
        "{copy} of volume {}x{}x{} ({bytes} bytes, {texels} texels of {format:?})",
        dims[0], dims[1], dims[2]
    );
    info.check(
        what.clone(),
        "maxTexelBufferElements",
        texels,
        info.max_texel_buffer_elements as u64,
    )?;
    info.check(
        what.clone(),
        "maxMemoryAllocationSize",
        bytes,
        info.max_memory_allocation_size,
    )?;
    if info.device_local_bytes > 0 {
        info.check(what, "device-local heap size", bytes, info.device_local_bytes)?;
    }
    Ok(bytes)
}

/// The words of cell layers `layers` (k + 1 in 0..=D) of a volume of
/// `dims`, `words` a cell, each cell filled by `fill` from the voxel index
/// of its corner `b` (0..8, x fastest; clamped at the edges as the sampler
/// clamps).
fn pack_cells<F>(dims: [u32; 3], words: usize, layers: std::ops::Range<u64>, fill: F) -> Vec<u32>
where
    F: Fn(&mut [u32], &dyn Fn(usize) -> usize) + Sync,
{
    let [w, h, d] = dims.map(|n| n as i64);
    let [cw, ch, _] = cell_dims(dims);
    let row = cw as usize * words;
    let rows = (layers.end - layers.start) * ch;
    let mut out = vec![0u32; rows as usize * row];
    let index = |x: i64, y: i64, z: i64| -> usize {
        let (x, y, z) = (x.clamp(0, w - 1), y.clamp(0, h - 1), z.clamp(0, d - 1));
        (x + w * (y + h * z)) as usize
    };
    out.par_chunks_mut(row).enumerate().for_each(|(r, out)| {
        let r = r as i64;
        let k = layers.start as i64 + r / ch as i64 - 1;
        let j = r % ch as i64 - 1;
        for (c, cell) in out.chunks_exact_mut(words).enumerate() {
            let i = c as i64 - 1;
            let corner = |b: usize| index(i + (b & 1) as i64, j + (b >> 1 & 1) as i64, k + (b >> 2 & 1) as i64);
            fill(cell, &corner);
        }
    });
    out
}

/// The words of cell layers `layers` of `volume`.
fn pack_layers(volume: &Volume, layers: std::ops::Range<u64>) -> Vec<u32> {
    let words = TexelKind::of(&volume.data).words();
    pack_cells(volume.dims, words, layers, |cell, corner| match &volume.data {
        VoxelData::U8(v) => {
            for half in 0..2 {
                cell[half] = (0..4).fold(0u32, |acc, b| acc | (v[corner(4 * half + b)] as u32) << (8 * b));
            }
        }
        VoxelData::U16(v) => {
            for pair in 0..4 {
                cell[pair] = v[corner(2 * pair)] as u32 | (v[corner(2 * pair + 1)] as u32) << 16;
            }
        }
        VoxelData::F32(v) => {
            for (b, word) in cell.iter_mut().enumerate() {
                *word = v[corner(b)].to_bits();
            }
        }
        // The same words from the texels' bytes (little-endian, as above).
        VoxelData::Bricks(p) => {
            let tb = p.layout.texel_bytes as usize;
            let per_word = 4 / tb;
            for (w, word) in cell.iter_mut().enumerate() {
                *word = (0..per_word).fold(0u32, |acc, k| {
                    let t = p.texel_bytes_at(corner(w * per_word + k));
                    let v = t.iter().rev().fold(0u32, |a, &b| a << 8 | b as u32);
                    acc | v << (8 * tb * k)
                });
            }
        }
    })
}

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

/// The words of the gradient's cell layers `layers`: per cell the eight
/// corners' (x, y, z) halves of `gradient` (the volume's gradient texels,
/// `dims`), corner-major, x fastest, two halves a word (low first).
fn pack_gradient_layers(gradient: &[[half::f16; 4]], dims: [u32; 3], layers: std::ops::Range<u64>) -> Vec<u32> {
    pack_cells(dims, GRADIENT_WORDS, layers, |cell, corner| {
        let halves = (0..8).flat_map(|b| {
            let g = gradient[corner(b)];
            [g[0], g[1], g[2]]
        });
        let halves: Vec<u16> = halves.map(half::f16::to_bits).collect();
        for (word, pair) in cell.iter_mut().zip(halves.chunks_exact(2)) {
            *word = pair[0] as u32 | (pair[1] as u32) << 16;
        }
    })
}

/// The gradient's cells copy on the device, uploaded and waited for, layer
/// block by layer block.
pub fn upload_gradient_cells(ctx: &Context, gradient: &[[half::f16; 4]], dims: [u32; 3]) -> Result<TexelBuffer> {
    let bytes = check_gradient_cells(ctx.info(), dims)?;
    let buffer = Buffer::upload_target(ctx, "gradient cells", bytes, vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER)?;
    let [cw, ch, cd] = cell_dims(dims);
    let layer = cw * ch * GRADIENT_CELL_BYTES;
    let per_upload = (LAYER_BYTES / layer).max(1);
    let mut k = 0;
    while k < cd {
        let end = (k + per_upload).min(cd);
        let words = pack_gradient_layers(gradient, dims, k..end);
        buffer.upload(k * layer, bytemuck::cast_slice(&words))?;
        k = end;
    }
    TexelBuffer::new(ctx, buffer, vk::Format::R32G32B32A32_UINT)
}

/// Cell layers per upload: bounds the host memory packing takes.
const LAYER_BYTES: u64 = 64 << 20;

/// The cells copy of `volume` on the device, uploaded and waited for, layer
/// block by layer block (host memory stays within about 64 MiB).
pub fn upload_cells(ctx: &Context, volume: &Volume) -> Result<TexelBuffer> {
    let kind = TexelKind::of(&volume.data);
    let bytes = check_cells(ctx.info(), volume.dims, kind)?;
    let buffer = cells_buffer(ctx, bytes)?;
    let [cw, ch, cd] = cell_dims(volume.dims);
    let layer = cw * ch * kind.bytes_per_voxel();
    let per_upload = (LAYER_BYTES / layer).max(1);
    let mut k = 0;
    while k < cd {
        let end = (k + per_upload).min(cd);
        let words = pack_layers(volume, k..end);
        buffer.upload(k * layer, bytemuck::cast_slice(&words))?;
        k = end;
    }
    TexelBuffer::new(ctx, buffer, kind.format().0)
}

/// As `upload_cells`, recorded into `cmd` (one staging buffer of the whole
/// copy; keep it until the submission completed), ending with a barrier to
/// compute-shader reads.
pub fn record_upload_cells(ctx: &Context, cmd: vk::CommandBuffer, volume: &Volume) -> Result<(TexelBuffer, Staging)> {
    let kind = TexelKind::of(&volume.data);
    let bytes = check_cells(ctx.info(), volume.dims, kind)?;
    crate::limits::check_host(format_args!("cells copy of {}", volume.name), bytes, 1)?;
    let words = pack_layers(volume, 0..cell_dims(volume.dims)[2]);
    let (buffer, staging) = Buffer::record_with_data(
        ctx,
        cmd,
        "volume cells",
        bytemuck::cast_slice(&words),
        vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
    )?;
    Ok((TexelBuffer::new(ctx, buffer, kind.format().0)?, staging))
}

/// A one-texel buffer bound in place of a volume's cells copy where it has
/// none: the kernels' `VOLUME_CELLS` constant keeps them from reading it.
pub fn no_cells(ctx: &Context) -> Result<TexelBuffer> {
    let buffer = Buffer::with_data(ctx, "no cells", &[0u8; 16], vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER)?;
    TexelBuffer::new(ctx, buffer, vk::Format::R32G32B32A32_UINT)
}

fn cells_buffer(ctx: &Context, bytes: u64) -> Result<Buffer> {
    if bytes == 0 {
        return Err(Error::invalid("cells copy", "of 0 bytes", "the volume has no voxels"));
    }
    Buffer::upload_target(ctx, "volume cells", bytes, vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    #[test]
    fn a_cell_holds_its_eight_clamped_corners_x_fastest() {
        let dims = [3u32, 2, 2];
        let data: Vec<u8> = (0..12).map(|i| 10 * i as u8).collect();
        let v = Volume::new("t", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data.clone())).unwrap();
        let words = pack_layers(&v, 0..3);
        let at = |x: i64, y: i64, z: i64| {
            let c = |a: i64, n: u32| a.clamp(0, n as i64 - 1) as usize;
            data[c(x, 3) + 3 * (c(y, 2) + 2 * c(z, 2))]
        };
        for k in -1..2i64 {
            for j in -1..2i64 {
                for i in -1..3i64 {
                    let t = ((i + 1) + 4 * ((j + 1) + 3 * (k + 1))) as usize;
                    let bytes: Vec<u8> = words[2 * t..2 * t + 2].iter().flat_map(|w| w.to_le_bytes()).collect();
                    let want: Vec<u8> = (0..8)
                        .map(|b| at(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)))
                        .collect();
                    assert_eq!(bytes, want, "cell {i},{j},{k}");
                }
            }
        }
        // Packing in blocks of layers gives the same words.
        let blocks: Vec<u32> = (0..3).flat_map(|k| pack_layers(&v, k..k + 1)).collect();
        assert_eq!(blocks, words);
        assert_eq!(cells_bytes(dims, TexelKind::Unorm8), 4 * 3 * 3 * 8);
    }

    #[test]
    fn a_gradient_cell_holds_its_corners_halves_in_order() {
        let dims = [2u32, 2, 1];
        let g: Vec<[half::f16; 4]> = (0..4)
            .map(|v| [1.0, 2.0, 3.0].map(|c| half::f16::from_f32(c + 10.0 * v as f32)))
            .map(|[x, y, z]| [x, y, z, half::f16::ZERO])
            .collect();
        let words = pack_gradient_layers(&g, dims, 0..2);
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

    #[test]
    fn unorm16_and_float_cells_keep_every_bit() {
        let v16 = Volume::new(
            "t",
            [2, 1, 1],
            [1.0; 3],
            VoxelType::U16,
            VoxelData::U16(vec![0x1234, 0xfedc]),
        )
        .unwrap();
        // Cell (0, 0, 0) at texel 1 + 3 * (1 + 2 * 1) = 10: x pairs (c000, c100).
        let w = pack_layers(&v16, 0..2);
        assert_eq!(&w[40..44], &[0xfedc_1234; 4]);
        let f = [f32::NAN, -0.0];
        let vf = Volume::new("t", [2, 1, 1], [1.0; 3], VoxelType::F32, VoxelData::F32(f.to_vec())).unwrap();
        let w = pack_layers(&vf, 0..2);
        let cell = &w[80..88];
        for b in 0..8 {
            assert_eq!(cell[b], f[b & 1].to_bits(), "corner {b}");
        }
    }
}
