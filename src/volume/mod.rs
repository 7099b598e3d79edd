//! Volumes: the `Volume` type, loaders (raw, NRRD, NIfTI), procedural
//! generators, value ranges over bricks, GPU upload, and raw export.

mod bricks;
mod cells;
mod cells_delta;
mod cells_simd;
mod channels;
mod decode;
mod delta;
mod export;
mod filter;
mod gpu;
mod gpu_cells;
mod gpu_fields;
mod gpu_pool;
mod gpu_step;
mod gradient;
mod gradient_cells;
#[cfg(feature = "loaders")]
mod nifti;
mod nrrd;
mod pattern;
mod pool;
pub mod procedural;
mod raw;
mod series;
mod slabs;
mod spec;
mod stream;

pub use bricks::{BrickGrid, APRON, BRICK};
pub use cells::{
    cells_bytes, cells_words, check_cells, host_shared, no_cells, record_pack_cells, TexelKind, CELLS_CONSTANT_ID,
    GRADIENT_CELLS_CONSTANT_ID, KIND_CONSTANT_ID,
};
pub use channels::{common_kind, stored_texel, CHANNELS_CONSTANT_ID};
pub use decode::VoxelType;
pub use delta::{StepDelta, SEGMENT};
pub use export::{
    check_raw_out, parse_export_type, raw_path, raw_suffix, write_raw, RawExport, SourceValues, EXPORT_TYPES,
};
pub use filter::{value_margin, Filter, FILTER_CONSTANT_ID, NAN_CONSTANT_ID};
pub use gpu::{check_dense, check_one_channel, resolve_storage, GpuVolume, StepMark};
pub use gradient::{gradient_texels, GRADIENT_TEXEL_BYTES};
pub use gradient_cells::{check_gradient_cells, GRADIENT_CELL_BYTES};
pub use pool::{
    BrickBox, PoolLayout, PoolLimits, PoolStats, Storage, BRICK_CONSTANT_ID, MAX_POOL_IMAGES, POOL_BRICK,
    POOL_IMAGES_CONSTANT_ID,
};
pub use raw::{parse_dims, parse_type, RawLayout};
pub use series::{check_value_range, Series, StepNorm};
pub use spec::{LoadOptions, VolumeSpec};
pub use stream::{HostPool, PoolStream, RangeAcross, StreamProgress, StreamTo};

use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;

/// Voxel values as stored on the GPU: u8 and u16 stay native (R8/R16 UNORM
/// images), every other source type becomes f32 already normalised to [0, 1].
#[derive(Clone, Debug)]
pub enum VoxelData {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
    /// Streamed into bricks (`stream.rs`): one channel's texels of 1, 2 or
    /// 4 bytes (u8, u16, f32) as the brick pool's slots; constant bricks
    /// are one value each.
    Bricks(std::sync::Arc<HostPool>),
}

impl VoxelData {
    pub fn len(&self) -> usize {
        match self {
            VoxelData::U8(v) => v.len(),
            VoxelData::U16(v) => v.len(),
            VoxelData::F32(v) => v.len(),
            VoxelData::Bricks(p) => p.layout.dims.iter().map(|&d| d as usize).product(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Least and greatest stored value (not normalised; infinities when empty).
    pub fn stored_range(&self) -> (f64, f64) {
        match self {
            VoxelData::U8(v) => minmax(v.iter().map(|&x| x as f64)),
            VoxelData::U16(v) => minmax(v.iter().map(|&x| x as f64)),
            VoxelData::F32(v) => minmax(v.iter().map(|&x| x as f64)),
            VoxelData::Bricks(p) => p.stored_range(),
        }
    }

    /// Bytes per texel: 1 (u8), 2 (u16), 4 (f32).
    pub fn texel_bytes(&self) -> u64 {
        match self {
            VoxelData::U8(_) => 1,
            VoxelData::U16(_) => 2,
            VoxelData::F32(_) => 4,
            VoxelData::Bricks(p) => p.layout.texel_bytes,
        }
    }

    /// What a stored value is divided by where the GPU samples it (UNORM
    /// u8 and u16 images: 255, 65535); 1 for floats.
    pub fn unorm_scale(&self) -> f64 {
        match self.texel_bytes() {
            1 => 255.0,
            2 => 65535.0,
            _ => 1.0,
        }
    }

    /// The stored value at index `i`: 0..255, 0..65535, or the float.
    #[inline]
    pub fn stored_at(&self, i: usize) -> f64 {
        match self {
            VoxelData::U8(v) => v[i] as f64,
            VoxelData::U16(v) => v[i] as f64,
            VoxelData::F32(v) => v[i] as f64,
            VoxelData::Bricks(p) => p.stored(p.texel_bytes_at(i)),
        }
    }

    /// The texel value the GPU reads at index `i` (UNORM for integers).
    #[inline]
    pub fn texel(&self, i: usize) -> f32 {
        match self {
            VoxelData::U8(v) => v[i] as f32 / 255.0,
            VoxelData::U16(v) => v[i] as f32 / 65535.0,
            VoxelData::F32(v) => v[i],
            VoxelData::Bricks(p) => p.decode(p.texel_bytes_at(i)),
        }
    }
}

/// A structured volume: dims voxels along x, y, z (x fastest), with spacing.
#[derive(Clone, Debug)]
pub struct Volume {
    /// Where it came from: a path or a procedural spec.
    pub name: String,
    pub dims: [u32; 3],
    /// Physical size of a voxel along each axis.
    pub spacing: [f32; 3],
    /// The voxel type of the source, before conversion to `data`.
    pub source_type: VoxelType,
    pub data: VoxelData,
    /// Minimum and maximum of the source values, in source units.
    pub value_range: [f64; 2],
    /// Texel to normalised value: `v = clamp((texel - norm[0]) * norm[1], 0, 1)`.
    pub norm: [f32; 2],
    /// The transfer function spec a generator suggests for this volume.
    pub default_tf: Option<String>,
    /// The voxels without data (NaN, stored as NaN, infinities included).
    pub no_data: NoData,
    /// Channels 2 and up (at most `MAX_CHANNELS` in all), each on this
    /// volume's grid with its own type, range and normalisation: this
    /// volume's own fields are channel 1. Empty for a one-channel volume.
    /// `Volume::join` makes them.
    pub other_channels: Vec<Volume>,
}

pub use crate::limits::MAX_CHANNELS;

/// Float voxels that hold no value, by what the source held. All are
/// stored as NaN: a sample that reads one is transparent, and value ranges
/// ignore them (README, "NaN and infinities"). An infinity is no data too:
/// no transfer function maps it, and clamping it would invent a value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoData {
    pub nan: u64,
    pub pos_inf: u64,
    pub neg_inf: u64,
}

impl NoData {
    /// Counts the non-finite values of float `data` and stores them as NaN.
    fn mark(data: &mut VoxelData) -> NoData {
        let mut counts = NoData::default();
        if let VoxelData::F32(values) = data {
            counts.mark_values(values);
        }
        counts
    }

    /// Adds the non-finite values of `values` to the counts and stores
    /// them as NaN (a slab of a streamed volume, or a whole one).
    fn mark_values(&mut self, values: &mut [f32]) {
        for v in values.iter_mut().filter(|v| !v.is_finite()) {
            match *v {
                f32::INFINITY => self.pos_inf += 1,
                f32::NEG_INFINITY => self.neg_inf += 1,
                _ => self.nan += 1,
            }
            *v = f32::NAN;
        }
    }

    pub fn total(&self) -> u64 {
        self.nan + self.pos_inf + self.neg_inf
    }
}

/// Checks that `step` is one of the `steps` time steps of the file at `path`.
fn check_file_step(path: &std::path::Path, step: u32, steps: u32) -> Result<()> {
    if step >= steps {
        return Err(Error::invalid(
            "time",
            step.to_string(),
            format!("{} has {steps} time step(s), 0 to {}", path.display(), steps - 1),
        ));
    }
    Ok(())
}

/// Deflate writes at most 1032 bytes for each byte it reads (zlib's
/// documented worst ratio), and gzip's framing only adds input.
const MAX_INFLATE_RATIO: u64 = 1032;

/// Checks that `compressed` bytes of gzip data can inflate to the `needed`
/// bytes a header describes, so a tiny file claiming a huge grid is refused
/// before a slab or a layer is allocated for it.
fn check_gzip_holds(path: &std::path::Path, compressed: u64, needed: u64) -> Result<()> {
    let most = compressed.saturating_mul(MAX_INFLATE_RATIO);
    if most < needed {
        return Err(Error::format(
            path,
            format!(
                "holds {compressed} bytes of gzip data, which inflate to at most {most} bytes, but its header describes {needed}"
            ),
        ));
    }
    Ok(())
}

/// Every spacing finite and > 0, and the physical box (dims x spacing)
/// finite in f32; `name` names the volume in the error. Within that any
/// spacing loads: one so uneven that a camera forms no finite rays is that
/// frame's error (`CameraMatrices::rays`).
pub fn check_spacing(dims: [u32; 3], spacing: [f32; 3], name: &str) -> Result<()> {
    let text = spacing.map(crate::error::number).join(" x ");
    let bad = |why: &str| Err(Error::invalid("spacing", text.clone(), format!("{name}: {why}")));
    if spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return bad("every spacing must be finite and > 0");
    }
    if (0..3).any(|a| !(dims[a] as f32 * spacing[a]).is_finite()) {
        return bad("the volume's physical size (dims x spacing) is past f32");
    }
    Ok(())
}

/// Checks dims are non-zero and their product fits memory indexing.
pub fn check_dims(dims: [u32; 3], what: &str) -> Result<u64> {
    if dims.contains(&0) {
        return Err(Error::invalid(
            "dimensions",
            format!("{}x{}x{}", dims[0], dims[1], dims[2]),
            format!("{what} has a zero dimension"),
        ));
    }
    let n = dims
        .iter()
        .try_fold(1u64, |n, &d| n.checked_mul(d as u64))
        .unwrap_or(u64::MAX);
    if n > isize::MAX as u64 / 8 {
        return Err(Error::invalid(
            "dimensions",
            format!("{}x{}x{}", dims[0], dims[1], dims[2]),
            "too many voxels to address",
        ));
    }
    Ok(n)
}

/// Bytes per voxel a volume of source type `ty` is stored with (u8 and u16
/// stay native, the rest become f32).
pub fn stored_bytes(ty: VoxelType) -> u64 {
    match ty {
        VoxelType::U8 | VoxelType::I8 => 1,
        VoxelType::U16 | VoxelType::I16 => 2,
        _ => 4,
    }
}

/// Checks a volume's size from its header, before its voxels are read or
/// made: host memory for the decode's peak (source bytes, f64 staging of
/// wider types, the stored values) and, given a device, its image limits.
pub fn check_size(dims: [u32; 3], ty: VoxelType, what: &str, device: Option<&DeviceInfo>) -> Result<()> {
    let n = check_dims(dims, what)?;
    let staging = if stored_bytes(ty) == 4 { 8 } else { 0 };
    let [w, h, d] = dims;
    crate::limits::check_host(
        format_args!("volume {what} ({w}x{h}x{d} {ty})"),
        n,
        ty.bytes() as u64 + staging + stored_bytes(ty),
    )?;
    if let Some(info) = device {
        crate::gpu::check_image3d(info, dims, stored_bytes(ty))?;
    }
    Ok(())
}

impl Volume {
    /// Builds a volume from stored values; computes the value range and the
    /// texel normalisation. `source_range` gives the range in source units
    /// (defaults to the stored range).
    pub fn new(
        name: impl Into<String>,
        dims: [u32; 3],
        spacing: [f32; 3],
        source_type: VoxelType,
        data: VoxelData,
    ) -> Result<Self> {
        let name = name.into();
        let n = check_dims(dims, &name)?;
        if data.len() as u64 != n {
            return Err(Error::invalid(
                "voxel data",
                name,
                format!("{} values for {} voxels", data.len(), n),
            ));
        }
        check_spacing(dims, spacing, &name)?;
        let mut data = data;
        let no_data = NoData::mark(&mut data);
        let (lo, hi) = match data.stored_range() {
            // Only no-data voxels: every sample is transparent.
            (lo, hi) if lo > hi => (0.0, 0.0),
            r => r,
        };
        let full = data.unorm_scale();
        let norm = if hi > lo {
            [(lo / full) as f32, (full / (hi - lo)) as f32]
        } else {
            [(lo / full) as f32, 0.0]
        };
        Ok(Volume {
            name,
            dims,
            spacing,
            source_type,
            data,
            value_range: [lo, hi],
            norm,
            default_tf: None,
            no_data,
            other_channels: Vec::new(),
        })
    }

    /// A volume of several channels on one grid: `channels[0]` is channel 1.
    /// They must share dims and spacing; 1 to `MAX_CHANNELS` of them, each
    /// itself one channel.
    pub fn join(channels: Vec<Volume>) -> Result<Volume> {
        let names: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
        let name = names.join("+");
        if channels.is_empty() || channels.len() > MAX_CHANNELS {
            return Err(Error::invalid(
                "channels",
                name,
                format!("{} channels: a volume has 1 to {MAX_CHANNELS}", channels.len()),
            ));
        }
        let mut channels = channels.into_iter();
        let Some(mut first) = channels.next() else {
            return Err(Error::invalid("channels", name, "no channel"));
        };
        if first.channel_count() > 1 {
            return Err(Error::invalid(
                "channels",
                name,
                "each joined volume must be one channel",
            ));
        }
        for (i, c) in channels.enumerate() {
            let [w, h, d] = c.dims;
            let [w0, h0, d0] = first.dims;
            if c.dims != first.dims {
                return Err(Error::invalid(
                    "channels",
                    c.name.clone(),
                    format!(
                        "channel {} is {w}x{h}x{d} where channel 1 ({}) is {w0}x{h0}x{d0}: channels share one grid",
                        i + 2,
                        first.name
                    ),
                ));
            }
            if c.spacing != first.spacing {
                return Err(Error::invalid(
                    "channels",
                    c.name.clone(),
                    format!(
                        "channel {} has spacing {:?} where channel 1 ({}) has {:?}: channels share one grid",
                        i + 2,
                        c.spacing,
                        first.name,
                        first.spacing
                    ),
                ));
            }
            if c.channel_count() > 1 {
                return Err(Error::invalid(
                    "channels",
                    c.name.clone(),
                    "each joined volume must be one channel",
                ));
            }
            first.other_channels.push(c);
        }
        first.name = name;
        Ok(first)
    }

    /// How many channels it has (1 to `MAX_CHANNELS`).
    pub fn channel_count(&self) -> usize {
        1 + self.other_channels.len()
    }

    /// Channel `c` (0-based; 0 is this volume's own data) as a one-channel
    /// volume: its data, type, range and normalisation.
    ///
    /// # Panics
    /// If `c >= channel_count()`, as indexing a slice does.
    pub fn channel(&self, c: usize) -> &Volume {
        if c == 0 {
            self
        } else {
            &self.other_channels[c - 1]
        }
    }

    /// Channel `c`'s own name: channel 1's data is this volume's, whose
    /// name `join` made every channel's, joined with `+`; a file of several
    /// channels names them `FILE[c]`, and channel 1 `FILE[0]` likewise.
    ///
    /// # Panics
    /// If `c >= channel_count()`, as `channel` does.
    pub fn channel_name(&self, c: usize) -> String {
        if c > 0 {
            return self.other_channels[c - 1].name.clone();
        }
        let others: String = self.other_channels.iter().map(|o| format!("+{}", o.name)).collect();
        let components = self
            .other_channels
            .first()
            .is_some_and(|o| o.name == format!("{}[1]", self.name));
        match self.name.strip_suffix(&others) {
            Some(own) if !others.is_empty() => own.to_string(),
            _ if components => format!("{}[0]", self.name),
            _ => self.name.clone(),
        }
    }

    /// Every channel, channel 1 first.
    pub fn channels(&self) -> impl Iterator<Item = &Volume> {
        std::iter::once(self).chain(self.other_channels.iter())
    }

    /// Each channel's suggested transfer function (a generator's, else
    /// `ramp:0:1`), one per channel.
    pub fn default_transfer_function(&self) -> Result<crate::tf::TransferFunction> {
        let spec = |c: &Volume| c.default_tf.clone().unwrap_or_else(|| "ramp:0:1".into());
        if self.channel_count() == 1 {
            return crate::tf::TransferFunction::parse(&spec(self));
        }
        let tfs = self
            .channels()
            .map(|c| crate::tf::TransferFunction::parse(&spec(c)))
            .collect::<Result<Vec<_>>>()?;
        crate::tf::TransferFunction::per_channel(tfs)
    }

    /// Its fields agree, as every loader and generator makes them (they
    /// are public, so a caller can build one that does not): each
    /// channel's voxels fill the grid, the spacing makes a finite box, and
    /// the channels are at most `MAX_CHANNELS`. Uploads check it first.
    pub fn check(&self) -> Result<()> {
        check_dims(self.dims, &self.name)?;
        check_spacing(self.dims, self.spacing, &self.name)?;
        let n = self.voxel_count();
        if self.channel_count() > MAX_CHANNELS {
            return Err(Error::invalid(
                "volume",
                self.name.clone(),
                format!("has {} channels, at most {MAX_CHANNELS}", self.channel_count()),
            ));
        }
        for (k, c) in self.channels().enumerate() {
            if c.dims != self.dims || c.data.len() as u64 != n {
                return Err(Error::invalid(
                    "volume",
                    self.name.clone(),
                    format!(
                        "channel {} holds {} voxels on a {}x{}x{} grid, where the volume's {}x{}x{} needs {n}",
                        k + 1,
                        c.data.len(),
                        c.dims[0],
                        c.dims[1],
                        c.dims[2],
                        self.dims[0],
                        self.dims[1],
                        self.dims[2]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Voxels without data, over every channel.
    pub fn no_data_total(&self) -> u64 {
        self.channels().map(|c| c.no_data.total()).sum()
    }

    pub fn voxel_count(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    #[inline]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        (x as usize) + self.dims[0] as usize * (y as usize + self.dims[1] as usize * z as usize)
    }

    /// Normalised value of voxel (x, y, z), exactly as the GPU computes it.
    #[inline]
    pub fn value(&self, x: u32, y: u32, z: u32) -> f32 {
        self.normalize(self.data.texel(self.index(x, y, z)))
    }

    #[inline]
    pub fn normalize(&self, texel: f32) -> f32 {
        ((texel - self.norm[0]) * self.norm[1]).clamp(0.0, 1.0)
    }

    /// Physical extent (dims x spacing).
    pub fn extent(&self) -> [f32; 3] {
        [0, 1, 2].map(|a| self.dims[a] as f32 * self.spacing[a])
    }

    /// Bytes per stored voxel.
    pub fn texel_bytes(&self) -> u64 {
        self.data.texel_bytes()
    }

    /// Loads a volume spec: a file path or a procedural `NAME:SIZE[:PARAM]`.
    pub fn load(spec: &str, options: &LoadOptions) -> Result<Self> {
        Self::load_within(spec, options, None)
    }

    /// As `load`, checking the volume's size against `device`'s limits (and
    /// host memory) from its spec or header, before any voxel is read or made.
    pub fn load_within(spec: &str, options: &LoadOptions, device: Option<&DeviceInfo>) -> Result<Self> {
        VolumeSpec::parse(spec, options)?.load_within(options, device)
    }

    /// A raw volume from memory; `name` gives the layout as a file name
    /// does (`name_WxHxD_type.raw`) unless `layout` is given.
    pub fn from_raw_bytes(name: &str, bytes: &[u8], layout: Option<RawLayout>) -> Result<Self> {
        raw::from_bytes(std::path::Path::new(name), bytes, layout)
    }

    /// A NRRD volume (`.nrrd` with attached data, raw or gzip) from memory;
    /// `origin` names it in errors. Detached data files need `load`.
    pub fn from_nrrd_bytes(origin: &str, bytes: &[u8]) -> Result<Self> {
        nrrd::from_bytes(std::path::Path::new(origin), bytes)
    }

    /// A NIfTI-1 single-file volume (`.nii`, or `.nii.gz` when `bytes` are gzip) from memory.
    #[cfg(feature = "loaders")]
    pub fn from_nifti_bytes(origin: &str, bytes: &[u8]) -> Result<Self> {
        nifti::from_bytes(std::path::Path::new(origin), bytes)
    }
}

fn minmax(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}
