//! Bricked storage: the volume as a pool of bricks and a page table, with
//! the bricks whose texels are all one value left out (`glsl/common/bricks.glsl`).
//!
//! A brick is `edge`^3 voxels; its slot in the pool holds (edge + 1)^3
//! texels: its own and, on its high sides, the first layer of the next
//! brick (clamped at the volume's end), so the eight voxels of every
//! trilinear cell lie in one slot and a sample reads the table once. A
//! brick all of whose slot texels are bit-identical (NaN included) is not
//! stored: its entry points at one texel holding its value, with step 0.
//! Distinct values are stored once each, in slots after the stored bricks.
//! The pool's texels are the dense image's texels, read by the same
//! `texelFetch`, so every sample equals the dense volume's bit for bit.

use crate::error::{Error, Result};
use rayon::prelude::*;
use std::collections::HashMap;

/// Brick edge of the pool in voxels: 16. Measured on nbody:512 against 8
/// and 32 (README, "Storage"): frames cost the same within noise, the
/// pool is 0.35x, 0.43x and 0.54x dense for 8, 16 and 32, and the border
/// layer costs 42 %, 20 % and 10 % on data without constant bricks; 16
/// keeps the table 1/512 of the voxel count (8: 1/64).
pub const POOL_BRICK: u32 = 16;

/// `constant_id` of `VOLUME_BRICK` in `glsl/common/volume.glsl`.
pub const BRICK_CONSTANT_ID: u32 = 27;

/// Bit 31 of an entry's second word: the brick is one value.
const CONSTANT: u32 = 1 << 31;

/// Most images one pool spans (`volume_tex` and `pool_1` to `pool_3` in
/// glsl/common/bricks.glsl): a pool past one allocation is split.
pub const MAX_POOL_IMAGES: usize = 4;

/// `constant_id` of `POOL_IMAGES` in `glsl/common/volume.glsl`.
pub const POOL_IMAGES_CONSTANT_ID: u32 = 28;

/// What bounds one pool image: its side in texels, and its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolLimits {
    /// `maxImageDimension3D`.
    pub max_image_dim: u32,
    /// `maxMemoryAllocationSize`, and the device-local heap where smaller.
    pub max_image_bytes: u64,
    /// Bricks the table may hold: `maxTexelBufferElements`, and the
    /// shaders' signed 32-bit index.
    pub max_table_entries: u64,
}

impl PoolLimits {
    pub fn of(info: &crate::gpu::DeviceInfo) -> Self {
        let heap = if info.device_local_bytes > 0 {
            info.device_local_bytes
        } else {
            u64::MAX
        };
        PoolLimits {
            max_image_dim: info.max_image_dimension_3d,
            max_image_bytes: info.max_memory_allocation_size.min(heap),
            max_table_entries: (info.max_texel_buffer_elements as u64).min(i32::MAX as u64),
        }
    }
}

/// Where a volume's voxels live on the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Storage {
    /// One 3D image of the volume's dims.
    Dense,
    /// A pool of the bricks of `edge`^3 voxels that vary, and a page table
    /// (`PoolLayout`).
    Bricks { edge: u32 },
    /// Dense while the volume fits the device's image limits, else bricks
    /// of `POOL_BRICK`.
    #[default]
    Auto,
}

impl Storage {
    /// Bricks of the default edge.
    pub const BRICKS: Storage = Storage::Bricks { edge: POOL_BRICK };

    /// `dense`, `bricks`, `bricks:EDGE` or `auto`.
    pub fn parse(s: &str) -> Result<Self> {
        let bad = || {
            Error::invalid(
                "storage",
                s,
                "expected dense, bricks, bricks:EDGE (voxels, 1 to 4095) or auto",
            )
        };
        match s.split_once(':') {
            None if s == "dense" => Ok(Storage::Dense),
            None if s == "bricks" => Ok(Storage::BRICKS),
            None if s == "auto" => Ok(Storage::Auto),
            Some(("bricks", edge)) => match edge.parse::<u32>() {
                Ok(edge @ 1..=4095) => Ok(Storage::Bricks { edge }),
                _ => Err(bad()),
            },
            _ => Err(bad()),
        }
    }
}

impl std::fmt::Display for Storage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Storage::Dense => f.write_str("dense"),
            Storage::Bricks { edge } if *edge == POOL_BRICK => f.write_str("bricks"),
            Storage::Bricks { edge } => write!(f, "bricks:{edge}"),
            Storage::Auto => f.write_str("auto"),
        }
    }
}

impl std::str::FromStr for Storage {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Self::parse(s)
    }
}

/// What bricked storage keeps of a volume (`PoolLayout`), for reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolStats {
    /// Brick edge in voxels.
    pub edge: u32,
    /// Bricks stored in the pool, and left out as one value.
    pub stored: u64,
    pub constant: u64,
    /// Bytes of the pool image, the brick table, and the dense image.
    pub pool_bytes: u64,
    pub table_bytes: u64,
    pub dense_bytes: u64,
    /// Images the pool spans.
    pub images: u32,
}

impl PoolStats {
    /// Pool and table bytes over the dense image's.
    pub fn ratio(&self) -> f64 {
        (self.pool_bytes + self.table_bytes) as f64 / self.dense_bytes.max(1) as f64
    }
}

impl std::fmt::Display for PoolStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        let images = match self.images {
            1 => String::new(),
            n => format!(" in {n} images"),
        };
        write!(
            f,
            "bricks of {}^3: {} stored, {} constant; pool {:.1} MiB{images} + table {:.2} MiB = {:.3}x dense ({:.1} MiB)",
            self.edge,
            self.stored,
            self.constant,
            mib(self.pool_bytes),
            mib(self.table_bytes),
            self.ratio(),
            mib(self.dense_bytes)
        )
    }
}

/// A box of bricks: `[lo, hi]`, `lo` inclusive and `hi` exclusive per axis.
pub type BrickBox = [[u32; 3]; 2];

/// The pool of one volume: which bricks are stored where, and the table.
#[derive(Clone, Debug)]
pub struct PoolLayout {
    /// Brick edge in voxels.
    pub edge: u32,
    /// The volume's dims.
    pub dims: [u32; 3],
    /// Bricks per axis.
    pub counts: [u32; 3],
    /// Per brick, x fastest: `[x | y << 16, z | image << 16 | constant << 31]`,
    /// the pool image and texel its slot (or its one value) starts at.
    pub table: Vec<[u32; 2]>,
    /// The brick each stored slot holds, in slot order.
    pub stored: Vec<u32>,
    /// The distinct values of the constant bricks, one texel each.
    pub values: Vec<Vec<u8>>,
    /// Bricks left out because they are one value.
    pub constant_bricks: u64,
    /// Slots per axis of each pool image.
    pub images: Vec<[u32; 3]>,
    /// Slots of every image but the last (a full image's).
    pub per_image: u64,
    /// Bytes per texel.
    pub texel_bytes: u64,
}

impl PoolLayout {
    /// Plans the pool of a volume of `dims` whose texels (`texel_bytes`
    /// each, x fastest) are `data`: finds the constant bricks (in parallel)
    /// and places the rest, in as many images as `limits` need (at most
    /// `MAX_POOL_IMAGES`, else an error naming the limit).
    pub fn plan(data: &[u8], dims: [u32; 3], texel_bytes: u64, edge: u32, limits: PoolLimits) -> Result<Self> {
        Self::plan_kept(data, dims, texel_bytes, edge, limits, None)
    }

    /// As `plan`, storing only the bricks inside `keep` (bricks `lo`
    /// inclusive to `hi` exclusive per axis): one rank's block and its
    /// ghost bricks (`crate::parallel`). A brick outside is left out as if
    /// it were one value, its first texel's: samples there are never
    /// taken, and a range over it still holds only values of the volume.
    pub fn plan_kept(
        data: &[u8],
        dims: [u32; 3],
        texel_bytes: u64,
        edge: u32,
        limits: PoolLimits,
        keep: Option<BrickBox>,
    ) -> Result<Self> {
        if data.len() as u64 != dims.iter().fold(texel_bytes, |a, &d| a * d as u64) {
            return Err(Error::invalid(
                "brick pool",
                format!("{} bytes", data.len()),
                format!(
                    "is not {}x{}x{} texels of {texel_bytes} bytes",
                    dims[0], dims[1], dims[2]
                ),
            ));
        }
        let (counts, total) = Self::check(dims, edge, limits)?;
        // The scan's per-brick value, place, entry and slot.
        crate::limits::check_host("brick table", total, 40)?;
        let tb = texel_bytes as usize;
        let one_value: Vec<Option<&[u8]>> = (0..total)
            .into_par_iter()
            .map(|b| {
                let lo = brick_origin(b, counts, edge);
                let first = texel_index(lo, dims) * tb;
                let value = &data[first..first + tb];
                if outside(keep, lo, edge) {
                    return Some(value);
                }
                let mut same = true;
                for_each_slot_row(lo, dims, edge, |start, len| {
                    same = same
                        && data[start * tb..(start + len) * tb]
                            .chunks_exact(tb)
                            .all(|t| t == value);
                });
                same.then_some(value)
            })
            .collect();
        Self::assemble(edge, dims, texel_bytes, limits, &one_value)
    }

    /// The brick grid of a volume of `dims` in bricks of `edge`, and its
    /// brick count, after the edge and table limits' checks.
    pub(super) fn check(dims: [u32; 3], edge: u32, limits: PoolLimits) -> Result<([u32; 3], u64)> {
        let max_image_dim = limits.max_image_dim;
        // Table entries hold 16-bit x and y.
        let most = max_image_dim.clamp(2, 1 << 16) - 1;
        if edge == 0 || edge > most {
            return Err(Error::invalid(
                "brick edge",
                edge.to_string(),
                format!("expected 1 to {most} voxels (a slot of edge + 1 texels fits maxImageDimension3D)"),
            ));
        }
        let longest = dims.iter().copied().max().unwrap_or(1);
        if edge > longest {
            return Err(Error::invalid(
                "brick edge",
                edge.to_string(),
                format!(
                    "is longer than the volume's longest side ({longest} voxels; `bricks` alone means bricks:{POOL_BRICK}): take bricks:EDGE with EDGE at most {longest}, or dense"
                ),
            ));
        }
        let counts = dims.map(|d| d.div_ceil(edge));
        let total = counts.iter().map(|&c| c as u64).product::<u64>();
        if total > limits.max_table_entries {
            return Err(Error::invalid(
                "brick table",
                format!("of {total} bricks of {edge}^3"),
                format!(
                    "exceeds the {} entries a table may hold (maxTexelBufferElements); take larger bricks",
                    limits.max_table_entries
                ),
            ));
        }
        Ok((counts, total))
    }

    /// Places the bricks: per brick, `one_value` is its one value (left
    /// out) or None (stored in the next slot, in brick order).
    pub(super) fn assemble(
        edge: u32,
        dims: [u32; 3],
        texel_bytes: u64,
        limits: PoolLimits,
        one_value: &[Option<&[u8]>],
    ) -> Result<Self> {
        let counts = dims.map(|d| d.div_ceil(edge));
        let mut values: Vec<Vec<u8>> = Vec::new();
        let mut value_index: HashMap<&[u8], u32> = HashMap::new();
        let mut stored = Vec::new();
        // Which slot or value each brick takes, before the slot grid is known.
        let mut place: Vec<(bool, u32)> = Vec::with_capacity(one_value.len());
        for (b, v) in one_value.iter().enumerate() {
            match v {
                Some(v) => {
                    let next = values.len() as u32;
                    let k = *value_index.entry(v).or_insert_with(|| {
                        values.push(v.to_vec());
                        next
                    });
                    place.push((true, k));
                }
                None => {
                    place.push((false, stored.len() as u32));
                    stored.push(b as u32);
                }
            }
        }
        let slot = (edge + 1) as u64;
        let value_slots = (values.len() as u64).div_ceil(slot.pow(3));
        let slot_count = (stored.len() as u64 + value_slots).max(1);
        let (images, per_image) = image_grids(slot_count, edge, texel_bytes, limits)?;
        let mut layout = PoolLayout {
            edge,
            dims,
            counts,
            table: Vec::new(),
            stored,
            constant_bricks: one_value.iter().filter(|v| v.is_some()).count() as u64,
            values,
            images,
            per_image,
            texel_bytes,
        };
        layout.table = place
            .iter()
            .map(|&(constant, k)| {
                let (image, at) = if constant {
                    layout.value_texel(k)
                } else {
                    layout.slot_origin(k as u64)
                };
                [
                    at[0] | at[1] << 16,
                    at[2] | image << 16 | if constant { CONSTANT } else { 0 },
                ]
            })
            .collect();
        Ok(layout)
    }

    /// Pool image `k`'s extent in texels.
    pub fn extent(&self, k: usize) -> [u32; 3] {
        self.images[k].map(|s| s * (self.edge + 1))
    }

    /// Bytes of pool image `k`.
    pub fn image_bytes(&self, k: usize) -> u64 {
        self.extent(k).iter().fold(self.texel_bytes, |acc, &e| acc * e as u64)
    }

    pub fn pool_bytes(&self) -> u64 {
        (0..self.images.len()).map(|k| self.image_bytes(k)).sum()
    }

    pub fn table_bytes(&self) -> u64 {
        self.table.len() as u64 * 8
    }

    /// The dense image's bytes, for the ratio.
    pub fn dense_bytes(&self) -> u64 {
        self.dims.iter().fold(self.texel_bytes, |acc, &e| acc * e as u64)
    }

    /// The pool in numbers.
    pub fn stats(&self) -> PoolStats {
        PoolStats {
            edge: self.edge,
            stored: self.stored.len() as u64,
            constant: self.constant_bricks,
            pool_bytes: self.pool_bytes(),
            table_bytes: self.table_bytes(),
            dense_bytes: self.dense_bytes(),
            images: self.images.len() as u32,
        }
    }

    /// The pool `volume` would take in bricks of `edge` within `limits`.
    pub fn of_volume(volume: &super::Volume, edge: u32, limits: PoolLimits) -> Result<Self> {
        let (kind, n) = (super::channels::common_kind(volume), volume.channel_count());
        let texel = super::channels::texel_bytes(kind, n);
        Self::plan(&super::channels::texel_data(volume), volume.dims, texel, edge, limits)
    }

    /// The image and first texel of slot `s`.
    fn slot_origin(&self, s: u64) -> (u32, [u32; 3]) {
        let (k, s) = ((s / self.per_image) as usize, s % self.per_image);
        let [gx, gy, _] = self.images[k].map(|g| g as u64);
        let e = self.edge + 1;
        (k as u32, [s % gx, s / gx % gy, s / (gx * gy)].map(|c| c as u32 * e))
    }

    /// The texel holding distinct value `k`: value slots follow the stored
    /// bricks' slots, (edge + 1)^3 values each, x fastest.
    fn value_texel(&self, k: u32) -> (u32, [u32; 3]) {
        let e = (self.edge + 1) as u64;
        let (k, per) = (k as u64, e * e * e);
        let (image, o) = self.slot_origin(self.stored.len() as u64 + k / per);
        let r = k % per;
        let local = [r % e, r / e % e, r / (e * e)].map(|c| c as u32);
        (image, [o[0] + local[0], o[1] + local[1], o[2] + local[2]])
    }

    /// Writes pool image `k`'s texels (x fastest, `image_bytes(k)` long)
    /// from the volume's `data`, one pool plane per task.
    pub fn fill(&self, k: usize, data: &[u8], out: &mut [u8]) {
        let tb = self.texel_bytes as usize;
        self.fill_with(k, 0, out, |_, b, ly, lz, dst| {
            let lo = brick_origin(b as u64, self.counts, self.edge);
            let v = [lo[0], lo[1] + ly, lo[2] + lz].map(|c| c as u64);
            copy_row(data, self.dims, tb, v, dst);
        });
    }

    /// As `fill`, from texel plane `first_plane` of the image on (`out`
    /// whole planes), the stored slots' rows from `stored_row(slot, brick,
    /// ly, lz, dst)`: the slot's texel row (ly, lz), edge + 1 texels.
    pub fn fill_with(
        &self,
        k: usize,
        first_plane: u32,
        out: &mut [u8],
        stored_row: impl Fn(u64, u32, u32, u32, &mut [u8]) + Sync,
    ) {
        let [ex, ey, _] = self.extent(k);
        let [gx, gy, _] = self.images[k];
        let tb = self.texel_bytes as usize;
        let e = self.edge + 1;
        let plane = ex as usize * ey as usize * tb;
        let per_slot = (e as usize).pow(3);
        let first_slot = k as u64 * self.per_image;
        out.par_chunks_mut(plane).enumerate().for_each(|(pz, out)| {
            let pz = pz as u32 + first_plane;
            let (sz, lz) = (pz / e, pz % e);
            for sy in 0..gy {
                for sx in 0..gx {
                    let s = first_slot + sx as u64 + gx as u64 * (sy as u64 + gy as u64 * sz as u64);
                    for ly in 0..e {
                        let row = ((sy * e + ly) as usize * ex as usize + (sx * e) as usize) * tb;
                        let dst = &mut out[row..row + e as usize * tb];
                        if let Some(&b) = self.stored.get(s as usize) {
                            stored_row(s, b, ly, lz, dst);
                        } else {
                            let (lz, ly, e) = (lz as usize, ly as usize, e as usize);
                            let first = (s as usize - self.stored.len()) * per_slot + lz * e * e + ly * e;
                            for (lx, t) in dst.chunks_exact_mut(tb).enumerate() {
                                if let Some(v) = self.values.get(first + lx) {
                                    t.copy_from_slice(v);
                                }
                            }
                        }
                    }
                }
            }
        });
    }
}

/// The first voxel of brick `b` (x fastest).
/// Whether the brick at voxel `lo` lies outside `keep` (None keeps all).
pub(super) fn outside(keep: Option<BrickBox>, lo: [u32; 3], edge: u32) -> bool {
    keep.is_some_and(|[klo, khi]| {
        (0..3).any(|a| {
            let c = lo[a] / edge;
            c < klo[a] || c >= khi[a]
        })
    })
}

pub(super) fn brick_origin(b: u64, counts: [u32; 3], edge: u32) -> [u32; 3] {
    let [cx, cy, _] = counts.map(|c| c as u64);
    [(b % cx) as u32, (b / cx % cy) as u32, (b / (cx * cy)) as u32].map(|c| c * edge)
}

fn texel_index(v: [u32; 3], dims: [u32; 3]) -> usize {
    (v[0] as usize) + dims[0] as usize * (v[1] as usize + dims[1] as usize * v[2] as usize)
}

/// Calls `row(first texel, texels)` for each x-row of the slot of the brick
/// at `lo` that lies in the volume (the slot's texels past the volume's end
/// repeat its last voxels, so they add no value of their own).
fn for_each_slot_row(lo: [u32; 3], dims: [u32; 3], edge: u32, mut row: impl FnMut(usize, usize)) {
    let hi = [0, 1, 2].map(|a| (lo[a] + edge).min(dims[a] - 1));
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            row(texel_index([lo[0], y, z], dims), (hi[0] - lo[0] + 1) as usize);
        }
    }
}

/// One slot row: the volume's texels from voxel `v` along x, each index
/// clamped to the volume as the dense image's clamp-to-edge reads them.
fn copy_row(data: &[u8], dims: [u32; 3], tb: usize, v: [u64; 3], dst: &mut [u8]) {
    let [w, h, d] = dims.map(|c| c as u64);
    let (y, z) = (v[1].min(h - 1), v[2].min(d - 1));
    let base = ((y + h * z) * w) as usize;
    for (lx, t) in dst.chunks_exact_mut(tb).enumerate() {
        let x = (v[0] + lx as u64).min(w - 1) as usize;
        t.copy_from_slice(&data[(base + x) * tb..(base + x + 1) * tb]);
    }
}

/// The slot grid of `count` slots: near a cube, so the last, partly filled
/// layer wastes little; None where a side would pass `per_axis`.
fn slot_grid(count: u64, per_axis: u64) -> Option<[u64; 3]> {
    let gx = ((count as f64).cbrt().ceil() as u64).clamp(1, per_axis);
    let gy = ((count.div_ceil(gx) as f64).sqrt().ceil() as u64).clamp(1, per_axis);
    let gz = count.div_ceil(gx * gy);
    (gz <= per_axis).then_some([gx, gy, gz])
}

/// The slot grids of the pool images holding `count` slots of (edge + 1)^3
/// texels within `limits`, and the slots of a full image: one image while
/// it fits, else full images of the most slots one may hold, then the rest.
fn image_grids(count: u64, edge: u32, texel_bytes: u64, limits: PoolLimits) -> Result<(Vec<[u32; 3]>, u64)> {
    let slot_bytes = ((edge + 1) as u64).pow(3) * texel_bytes;
    // Table entries hold 16-bit x and y.
    let per_axis = (limits.max_image_dim.min(1 << 16) / (edge + 1)).max(1) as u64;
    let fits = |g: [u64; 3]| g.iter().product::<u64>() * slot_bytes <= limits.max_image_bytes;
    let to_u32 = |g: [u64; 3]| g.map(|c| c as u32);
    if let Some(g) = slot_grid(count, per_axis).filter(|&g| fits(g)) {
        return Ok((vec![to_u32(g)], g.iter().product()));
    }
    // A full image: the most slots within both limits, rounded down per axis.
    let most = (limits.max_image_bytes / slot_bytes).min(per_axis.pow(3)).max(1);
    let gx = ((most as f64).cbrt().floor() as u64).clamp(1, per_axis);
    let gy = (((most / gx) as f64).sqrt().floor() as u64).clamp(1, per_axis);
    let gz = (most / (gx * gy)).clamp(1, per_axis);
    let full = [gx, gy, gz];
    let per_image = full.iter().product::<u64>();
    let images = count.div_ceil(per_image);
    if images > MAX_POOL_IMAGES as u64 || !fits(full) {
        return Err(Error::invalid(
            "brick pool",
            format!("of {} bytes", count * slot_bytes),
            format!(
                "needs {images} 3D images of at most {} bytes (maxMemoryAllocationSize, device-local heap) and {} texels a side (maxImageDimension3D); one pool spans at most {MAX_POOL_IMAGES}",
                limits.max_image_bytes, limits.max_image_dim
            ),
        ));
    }
    let mut grids = vec![to_u32(full); images as usize - 1];
    let rest = count - per_image * (images - 1);
    grids.push(to_u32(slot_grid(rest, per_axis).filter(|&g| fits(g)).unwrap_or(full)));
    Ok((grids, per_image))
}
