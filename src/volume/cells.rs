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
//!
//! Where the device's memory is the host's (a CPU device) the host packs
//! the copy straight into memory the device reads (`shared_cells`); on
//! other devices a kernel makes it from the volume image
//! (`record_pack_cells`, `glsl/volume/cells.comp`), so neither staging nor
//! the host's packing of 8 to 32 bytes a voxel is paid.

use super::cells_simd::pack_u8_blocks;
use super::{Volume, VoxelData};
use crate::error::{Error, Result};
use crate::gpu::record::{self, Access};
use crate::gpu::shaders::{self, volume_cells as k};
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, DeviceInfo, Kernel, MemoryLocation, OptionalTimer, TexelBuffer, Timer};
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
pub(super) fn cell_dims(dims: [u32; 3]) -> [u64; 3] {
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
pub(super) fn check_texel_copy(
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

/// Whether the device's memory is the host's (a CPU device): then the host
/// packs the cells copies in place, with no staging and no copy
/// (`shared_cells`: 34 ms for nbody:256 on lavapipe, where the device's
/// packing took 150 ms and packing, staging and copying 300 ms).
pub fn host_shared(ctx: &Context) -> bool {
    ctx.info().is_cpu()
}

/// Cell layers per upload: bounds the host memory packing takes.
pub(super) const LAYER_BYTES: u64 = 64 << 20;

/// Packs the first cells between a row's edge cells a block at a time and
/// returns how many it packed (`cell_layers` packs the rest one by one):
/// given the four voxel rows they read and their `out`.
pub(super) type PackBlocks<T, U> = fn(&mut [U], [&[T]; 4]) -> usize;

/// Fills `out`, `per_cell` items a cell for the cell layers from `first`
/// on that `out` holds (cells x fastest, from -1), with `put(cell,
/// corners)`: the cell's eight voxels of `v` clamped to the volume, in
/// corner order (x fastest); `blocks` packs the first cells of each row
/// between its edge cells where given. Row by row: the four voxel rows a
/// row of cells reads are sliced once.
pub(super) fn cell_layers<T: Copy + Sync, U: Send>(
    v: &[T],
    dims: [u32; 3],
    first: usize,
    out: &mut [U],
    per_cell: usize,
    put: impl Fn(&mut [U], [T; 8]) + Sync,
    blocks: Option<PackBlocks<T, U>>,
) {
    let [w, h, d] = dims.map(|n| n as usize);
    let [cw, ch, _] = cell_dims(dims).map(|n| n as usize);
    // Cell i reads voxels i and i + 1 clamped; counted from -1, so these.
    let clamp = |a: usize, n: usize| a.saturating_sub(1).min(n - 1);
    out.par_chunks_mut(cw * per_cell).enumerate().for_each(|(r, out)| {
        let (j, k) = (r % ch, first + r / ch);
        let row = |dy: usize, dz: usize| &v[(clamp(j + dy, h) + h * clamp(k + dz, d)) * w..][..w];
        let [r0, r1, r2, r3] = [row(0, 0), row(1, 0), row(0, 1), row(1, 1)];
        let edge = |x: usize| [r0[x], r0[x], r1[x], r1[x], r2[x], r2[x], r3[x], r3[x]];
        // Cell 0 reads voxel 0 twice, cell w voxel w - 1; the cells between
        // read voxels c - 1 and c, a window of each row with no clamping
        // or bounds check per cell (nbody:256's 17 million cells packed
        // in 35-40 ms with them on lavapipe's two cores).
        let (head, rest) = out.split_at_mut(per_cell);
        let (middle, tail) = rest.split_at_mut((cw - 2) * per_cell);
        put(head, edge(0));
        let done = blocks.map_or(0, |pack| pack(middle, [r0, r1, r2, r3]));
        let [r0, r1, r2, r3] = [r0, r1, r2, r3].map(|r| &r[done..]);
        let windows = r0.windows(2).zip(r1.windows(2)).zip(r2.windows(2).zip(r3.windows(2)));
        for (cell, ((a, b), (c, e))) in middle[done * per_cell..].chunks_exact_mut(per_cell).zip(windows) {
            put(cell, [a[0], a[1], b[0], b[1], c[0], c[1], e[0], e[1]]);
        }
        put(tail, edge(w - 1));
    });
}

/// Packs `v` into its cells copy `out`: a cell is its eight voxels' texels
/// in corner order, which is the words' layout for every kind (bytes,
/// halves and words are little-endian).
fn pack_rows<T: Copy + Send + Sync>(v: &[T], dims: [u32; 3], out: &mut [T], blocks: Option<PackBlocks<T, T>>) {
    cell_layers(
        v,
        dims,
        0,
        out,
        8,
        |cell, corners| cell.copy_from_slice(&corners),
        blocks,
    );
}

/// Packs dense `volume`'s cells copy into `out` (its `cells_bytes`).
pub(super) fn pack_into(volume: &Volume, out: &mut [u8]) {
    match &volume.data {
        VoxelData::U8(v) => pack_rows(v, volume.dims, out, Some(pack_u8_blocks)),
        VoxelData::U16(v) => pack_rows(v, volume.dims, bytemuck::cast_slice_mut(out), None),
        VoxelData::F32(v) => pack_rows(v, volume.dims, bytemuck::cast_slice_mut(out), None),
        // Not reached by dense uploads of streamed volumes through the CLI;
        // a library caller's: packed in blocks of layers, as the host's
        // memory for it is bounded.
        VoxelData::Bricks(_) => {
            let [cw, ch, cd] = cell_dims(volume.dims);
            let layer = (cw * ch * TexelKind::of(&volume.data).bytes_per_voxel()) as usize;
            let per_block = (LAYER_BYTES as usize / layer).max(1);
            for (b, block) in out.chunks_mut(per_block * layer).enumerate() {
                let first = (b * per_block) as u64;
                let end = (first + per_block as u64).min(cd);
                block.copy_from_slice(bytemuck::cast_slice(&pack_layers(volume, first..end)));
            }
        }
    }
}

/// The march kernels read a cells copy; a host may read it back.
const CELLS_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER.as_raw() | vk::BufferUsageFlags::TRANSFER_SRC.as_raw(),
);

/// The cells copy of dense `volume` in memory both the host and the
/// device see, packed there by the host: no staging and no copy. For
/// devices whose memory is the host's (`host_shared`), where
/// `record_pack_cells`'s fetches cost more than packing on the host.
pub fn shared_cells(ctx: &Context, volume: &Volume) -> Result<TexelBuffer> {
    let kind = TexelKind::of(&volume.data);
    let bytes = check_cells(ctx.info(), volume.dims, kind)?;
    let buffer = Buffer::new(ctx, "volume cells", bytes, CELLS_USAGE, MemoryLocation::CpuToGpu)?;
    let mut cells = TexelBuffer::new(ctx, buffer, kind.format().0)?;
    repack_shared(&mut cells, volume)?;
    Ok(cells)
}

/// Packs `volume`'s cells copy into `cells`, host-visible and made for a
/// volume of its dims and kind (`shared_cells`): another time step's goes
/// where the last one's was, with no new memory to fault in (on lavapipe
/// that was 27 of nbody:256's 42 ms).
pub fn repack_shared(cells: &mut TexelBuffer, volume: &Volume) -> Result<()> {
    let bytes = cells_bytes(volume.dims, TexelKind::of(&volume.data)) as usize;
    let out = cells.host_mut()?;
    if out.len() < bytes {
        return Err(Error::Interface(format!(
            "cells copy of {} bytes for {bytes}",
            out.len()
        )));
    }
    pack_into(volume, &mut out[..bytes]);
    Ok(())
}

/// The words of `volume`'s cells copy packed on the host: what
/// `record_pack_cells` makes on the device, bit for bit (tests/integration/cells.rs).
pub fn cells_words(volume: &Volume) -> Vec<u32> {
    pack_layers(volume, 0..cell_dims(volume.dims)[2])
}

/// The cells copy of a dense volume of `dims` and `kind` made on the device
/// from its image (`view`, read through the nearest `sampler`), recorded
/// into `cmd` after the image's upload and its barrier to compute reads:
/// one dispatch per block of cell rows of at most `range` bytes (the
/// device's `maxStorageBufferRange`, or less), then a barrier from their
/// writes to compute-shader reads. No host packing and no staging of 8 to
/// 32 bytes a voxel. Timed as pass "cells" on `timer`. Keep the returned
/// kernel until the submission completed.
///
/// # Safety
/// `view` is a view of a 3D image of `cmd`'s device holding a volume of
/// `dims` texels of `kind`, in SHADER_READ_ONLY_OPTIMAL when the commands
/// execute, and `sampler` a sampler of that device; both stay alive until
/// the commands have executed.
pub unsafe fn record_pack_cells(
    cmd: Recording<'_>,
    mut timer: Option<&mut Timer>,
    (view, sampler): (vk::ImageView, vk::Sampler),
    dims: [u32; 3],
    kind: TexelKind,
    range: u64,
) -> Result<(TexelBuffer, Kernel)> {
    let ctx = cmd.context();
    let bytes = check_cells(ctx.info(), dims, kind)?;
    let buffer = cells_buffer(ctx, bytes)?;
    // Written through raw ranges: the host must not read it until then.
    buffer.written_by(cmd)?;
    let kernel = Kernel::new::<k::Push>(ctx, &shaders::VOLUME_CELLS)?;
    let info = ctx.info();
    let counts = cell_dims(dims);
    // One invocation per row of cells; each dispatch's rows start at a
    // multiple of the binding offset alignment (a power of two).
    let row_bytes = counts[0] * kind.bytes_per_voxel();
    let align = info.min_storage_buffer_offset_alignment.max(1);
    let rows_aligned = align / gcd(row_bytes, align);
    let per_dispatch = (range.min(info.max_storage_buffer_range) / row_bytes) / rows_aligned * rows_aligned;
    if per_dispatch == 0 {
        return Err(Error::invalid(
            "cells copy",
            format!("of volume {}x{}x{}", dims[0], dims[1], dims[2]),
            format!("{rows_aligned} rows of its cells ({row_bytes} bytes each) exceed one binding of {range} bytes (maxStorageBufferRange)"),
        ));
    }
    let rows = counts[1] * counts[2];
    let pass = timer.begin(cmd, "cells")?;
    let mut first = 0;
    while first < rows {
        let n = per_dispatch.min(rows - first);
        let groups = record::groups_linear(info, "cells copy", n, kernel.local_size()[0])?;
        let push = k::Push {
            dims: [dims[0], dims[1], dims[2], kind.constant()],
            cells: [counts[0] as u32, counts[1] as u32, counts[2] as u32, n as u32],
            first: first as u32,
            groups_x: groups[0],
        };
        let bindings = k::Bindings {
            volume_tex: Binding::Sampled(view, sampler),
            cells: Binding::StorageRange(buffer.raw, first * row_bytes, n * row_bytes),
        };
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe { kernel.dispatch(cmd, &bindings.list(), bytemuck::bytes_of(&push), groups) }?;
        first += n;
    }
    timer.end(cmd, pass);
    cmd.barrier(Access::COMPUTE_WRITE, Access::COMPUTE_READ);
    Ok((TexelBuffer::new(ctx, buffer, kind.format().0)?, kernel))
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// A one-texel buffer bound in place of a volume's cells copy where it has
/// none: the kernels' `VOLUME_CELLS` constant keeps them from reading it.
pub fn no_cells(ctx: &Context) -> Result<TexelBuffer> {
    // Written through its mapping: `record_*` calls make one, and submit nothing.
    let buffer = Buffer::host_written(ctx, "no cells", &[0u8; 16], vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER)?;
    TexelBuffer::new(ctx, buffer, vk::Format::R32G32B32A32_UINT)
}

fn cells_buffer(ctx: &Context, bytes: u64) -> Result<Buffer> {
    if bytes == 0 {
        return Err(Error::invalid("cells copy", "of 0 bytes", "the volume has no voxels"));
    }
    let usage = CELLS_USAGE | vk::BufferUsageFlags::STORAGE_BUFFER;
    Buffer::new(ctx, "volume cells", bytes, usage, MemoryLocation::GpuOnly)
}

#[cfg(test)]
pub(crate) mod tests {
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

    /// A 5x3x4 volume of each kind (a NaN among the floats), with
    /// `spacing`: odd dims for the row-wise packers' tests.
    pub(crate) fn odd_volumes(spacing: [f32; 3]) -> Vec<Volume> {
        let n = 60;
        let f32s = (0..n).map(|i| if i == 7 { f32::NAN } else { (i as f32 * 0.37).sin() });
        [
            (
                VoxelType::U8,
                VoxelData::U8((0..n).map(|i| (i * 37 % 251) as u8).collect()),
            ),
            (
                VoxelType::U16,
                VoxelData::U16((0..n).map(|i| (i * 4099 % 65521) as u16).collect()),
            ),
            (VoxelType::F32, VoxelData::F32(f32s.collect())),
        ]
        .into_iter()
        .map(|(ty, data)| Volume::new("odd", [5, 3, 4], spacing, ty, data).unwrap())
        .collect()
    }

    /// The row packer (what the device reads) against the packer that
    /// clamps every corner (the reference).
    #[test]
    fn packing_by_rows_equals_packing_by_corners() {
        // Rows of one and two voxels too: no cell between the two edge cells,
        // and one.
        let narrow = [[1, 2, 3], [2, 3, 1]].map(|dims| {
            let n = dims.iter().product::<u32>() as u8;
            Volume::new(
                "narrow",
                dims,
                [1.0; 3],
                VoxelType::U8,
                VoxelData::U8((1..=n).collect()),
            )
            .unwrap()
        });
        // Rows that end at, just after and within the unorm8 blocks of 16 cells.
        let wide = [16, 17, 18, 33, 34, 50].map(|w| {
            let dims = [w, 3, 2];
            let n = 6 * w as usize;
            let data = (0..n).map(|i| (i * 97 % 253) as u8).collect();
            Volume::new("wide", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap()
        });
        for v in odd_volumes([1.0; 3]).into_iter().chain(narrow).chain(wide) {
            let words = cells_words(&v);
            let mut packed = vec![0u8; cells_bytes(v.dims, TexelKind::of(&v.data)) as usize];
            pack_into(&v, &mut packed);
            assert_eq!(packed, bytemuck::cast_slice::<u32, u8>(&words), "{:?}", v.source_type);
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
