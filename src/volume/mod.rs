//! Volumes: the `Volume` type, loaders (raw, NRRD, NIfTI), procedural
//! generators, value ranges over bricks, GPU upload, and raw export.

mod bricks;
mod decode;
mod export;
mod filter;
mod gpu;
#[cfg(feature = "loaders")]
mod nifti;
mod nrrd;
pub mod procedural;
mod raw;
mod spec;

pub use bricks::{BrickGrid, BRICK};
pub use decode::VoxelType;
pub use export::{
    check_raw_out, parse_export_type, raw_path, raw_suffix, write_raw, RawExport, SourceValues, EXPORT_TYPES,
};
pub use filter::{Filter, FILTER_CONSTANT_ID};
pub use gpu::GpuVolume;
pub use raw::{parse_dims, parse_type, RawLayout};
pub use spec::{LoadOptions, VolumeSpec};

use crate::error::{Error, Result};

/// Voxel values as stored on the GPU: u8 and u16 stay native (R8/R16 UNORM
/// images), every other source type becomes f32 already normalised to [0, 1].
#[derive(Clone, Debug)]
pub enum VoxelData {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl VoxelData {
    pub fn len(&self) -> usize {
        match self {
            VoxelData::U8(v) => v.len(),
            VoxelData::U16(v) => v.len(),
            VoxelData::F32(v) => v.len(),
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
        }
    }

    /// The texel value the GPU reads at index `i` (UNORM for integers).
    #[inline]
    pub fn texel(&self, i: usize) -> f32 {
        match self {
            VoxelData::U8(v) => v[i] as f32 / 255.0,
            VoxelData::U16(v) => v[i] as f32 / 65535.0,
            VoxelData::F32(v) => v[i],
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
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    if n > isize::MAX as u64 / 8 {
        return Err(Error::invalid(
            "dimensions",
            format!("{}x{}x{}", dims[0], dims[1], dims[2]),
            "too many voxels to address",
        ));
    }
    Ok(n)
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
        if spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::invalid(
                "spacing",
                format!("{spacing:?}"),
                "every spacing must be finite and > 0",
            ));
        }
        let (lo, hi) = data.stored_range();
        let full = match &data {
            VoxelData::U8(_) => 255.0,
            VoxelData::U16(_) => 65535.0,
            VoxelData::F32(_) => 1.0,
        };
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
        })
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
        match self.data {
            VoxelData::U8(_) => 1,
            VoxelData::U16(_) => 2,
            VoxelData::F32(_) => 4,
        }
    }

    /// Loads a volume spec: a file path or a procedural `NAME:SIZE[:PARAM]`.
    pub fn load(spec: &str, options: &LoadOptions) -> Result<Self> {
        VolumeSpec::parse(spec, options)?.load(options)
    }
}

fn minmax(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}
