//! Decoding raw little- or big-endian voxel bytes of any supported source
//! type into stored `VoxelData`.

use super::{Volume, VoxelData};
use crate::error::{Error, Result};
use std::path::Path;

/// Voxel types lacuna reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
}

impl VoxelType {
    pub fn bytes(self) -> usize {
        match self {
            VoxelType::U8 | VoxelType::I8 => 1,
            VoxelType::U16 | VoxelType::I16 => 2,
            VoxelType::U32 | VoxelType::I32 | VoxelType::F32 => 4,
            VoxelType::F64 => 8,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            VoxelType::U8 => "uint8",
            VoxelType::I8 => "int8",
            VoxelType::U16 => "uint16",
            VoxelType::I16 => "int16",
            VoxelType::U32 => "uint32",
            VoxelType::I32 => "int32",
            VoxelType::F32 => "float32",
            VoxelType::F64 => "float64",
        }
    }

    /// The Open SciVis file-name spellings.
    pub fn from_name(s: &str) -> Option<Self> {
        Some(match s {
            "uint8" => VoxelType::U8,
            "int8" => VoxelType::I8,
            "uint16" => VoxelType::U16,
            "int16" => VoxelType::I16,
            "uint32" => VoxelType::U32,
            "int32" => VoxelType::I32,
            "float32" | "float" => VoxelType::F32,
            "float64" | "double" => VoxelType::F64,
            _ => return None,
        })
    }
}

impl std::fmt::Display for VoxelType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

fn words<const N: usize>(bytes: &[u8], little: bool) -> impl Iterator<Item = [u8; N]> + '_ {
    bytes.chunks_exact(N).map(move |c| {
        let mut w = [0u8; N];
        w.copy_from_slice(c);
        if !little {
            w.reverse();
        }
        w
    })
}

/// f32 values normalised over their finite range; NaN and infinities are
/// kept as they are (`Volume::new` stores them as no data).
fn normalized_f32(values: Vec<f64>) -> VoxelData {
    let finite = || values.iter().copied().filter(|v| v.is_finite());
    let lo = finite().fold(f64::INFINITY, f64::min);
    let hi = finite().fold(f64::NEG_INFINITY, f64::max);
    let scale = if hi > lo { 1.0 / (hi - lo) } else { 0.0 };
    let normalize = |v: f64| {
        if v.is_finite() {
            ((v - lo) * scale) as f32
        } else {
            v as f32
        }
    };
    VoxelData::F32(values.iter().map(|&v| normalize(v)).collect())
}

/// Decodes `bytes` (exactly dims x type size) into a volume.
pub fn decode(
    path: &Path,
    bytes: &[u8],
    ty: VoxelType,
    little: bool,
    dims: [u32; 3],
    spacing: [f32; 3],
) -> Result<Volume> {
    let n = super::check_dims(dims, &path.display().to_string())?;
    let expected = n * ty.bytes() as u64;
    if bytes.len() as u64 != expected {
        return Err(Error::format(
            path,
            format!(
                "holds {} bytes of voxel data but {}x{}x{} {} needs {}",
                bytes.len(),
                dims[0],
                dims[1],
                dims[2],
                ty,
                expected
            ),
        ));
    }
    let (data, range) = match ty {
        VoxelType::U8 => (VoxelData::U8(bytes.to_vec()), None),
        // Signed integers shift into the unsigned range so they stay native.
        VoxelType::I8 => (
            VoxelData::U8(bytes.iter().map(|&b| (b as i8 as i16 + 128) as u8).collect()),
            Some(-128.0),
        ),
        VoxelType::U16 => (
            VoxelData::U16(words::<2>(bytes, little).map(u16::from_le_bytes).collect()),
            None,
        ),
        VoxelType::I16 => (
            VoxelData::U16(
                words::<2>(bytes, little)
                    .map(|w| (i16::from_le_bytes(w) as i32 + 32768) as u16)
                    .collect(),
            ),
            Some(-32768.0),
        ),
        VoxelType::U32 => (
            normalized_f32(
                words::<4>(bytes, little)
                    .map(|w| u32::from_le_bytes(w) as f64)
                    .collect(),
            ),
            None,
        ),
        VoxelType::I32 => (
            normalized_f32(
                words::<4>(bytes, little)
                    .map(|w| i32::from_le_bytes(w) as f64)
                    .collect(),
            ),
            None,
        ),
        VoxelType::F32 => (
            normalized_f32(
                words::<4>(bytes, little)
                    .map(|w| f32::from_le_bytes(w) as f64)
                    .collect(),
            ),
            None,
        ),
        VoxelType::F64 => (
            normalized_f32(words::<8>(bytes, little).map(f64::from_le_bytes).collect()),
            None,
        ),
    };
    let mut volume = Volume::new(path.display().to_string(), dims, spacing, ty, data)?;
    // Report the range in source units.
    volume.value_range = match (ty, range) {
        (_, Some(offset)) => [volume.value_range[0] + offset, volume.value_range[1] + offset],
        (VoxelType::U8 | VoxelType::U16, None) => volume.value_range,
        _ => source_range(bytes, ty, little),
    };
    Ok(volume)
}

fn source_range(bytes: &[u8], ty: VoxelType, little: bool) -> [f64; 2] {
    let values: Box<dyn Iterator<Item = f64>> = match ty {
        VoxelType::U32 => Box::new(words::<4>(bytes, little).map(|w| u32::from_le_bytes(w) as f64)),
        VoxelType::I32 => Box::new(words::<4>(bytes, little).map(|w| i32::from_le_bytes(w) as f64)),
        VoxelType::F32 => Box::new(words::<4>(bytes, little).map(|w| f32::from_le_bytes(w) as f64)),
        _ => Box::new(words::<8>(bytes, little).map(f64::from_le_bytes)),
    };
    // The finite values' range (NaN and infinities are no data).
    match super::minmax(values.filter(|v| v.is_finite())) {
        (lo, hi) if lo > hi => [0.0, 0.0],
        (lo, hi) => [lo, hi],
    }
}
