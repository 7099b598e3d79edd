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

pub(super) fn words<const N: usize>(bytes: &[u8], little: bool) -> impl Iterator<Item = [u8; N]> + '_ {
    bytes.chunks_exact(N).map(move |c| {
        let mut w = [0u8; N];
        w.copy_from_slice(c);
        if !little {
            w.reverse();
        }
        w
    })
}

/// Negates raw voxels of `ty` in place, within their type: the bitwise
/// complement of an integer (`MAX - x` unsigned, `-1 - x` signed), the
/// sign of a float (NaN stays NaN). A NIfTI's negative `scl_slope` is then
/// a positive one (`nifti::Scaling`), so every later step sees values that
/// grow with the data's own.
pub(super) fn negate_raw(bytes: &mut [u8], ty: VoxelType, little: bool) {
    match ty {
        VoxelType::F32 | VoxelType::F64 => {
            let n = ty.bytes();
            let sign = if little { n - 1 } else { 0 };
            bytes.chunks_exact_mut(n).for_each(|w| w[sign] ^= 0x80);
        }
        _ => bytes.iter_mut().for_each(|b| *b = !*b),
    }
}

/// A signed byte shifted into the unsigned range, so it stays native.
pub(super) fn shifted_i8(b: u8) -> u8 {
    (b as i8 as i16 + 128) as u8
}

/// A signed 16-bit word (little-endian bytes) shifted into the unsigned range.
pub(super) fn shifted_i16(w: [u8; 2]) -> u16 {
    (i16::from_le_bytes(w) as i32 + 32768) as u16
}

/// The values of a wide type (uint32, int32, float32, float64) as f64.
pub(super) fn wide_values(bytes: &[u8], ty: VoxelType, little: bool) -> Box<dyn Iterator<Item = f64> + '_> {
    match ty {
        VoxelType::U32 => Box::new(words::<4>(bytes, little).map(|w| u32::from_le_bytes(w) as f64)),
        VoxelType::I32 => Box::new(words::<4>(bytes, little).map(|w| i32::from_le_bytes(w) as f64)),
        VoxelType::F32 => Box::new(words::<4>(bytes, little).map(|w| f32::from_le_bytes(w) as f64)),
        _ => Box::new(words::<8>(bytes, little).map(f64::from_le_bytes)),
    }
}

/// The least and greatest finite value (`(inf, -inf)` where none is).
pub(super) fn finite_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    super::minmax(values.filter(|v| v.is_finite()))
}

/// A wide type's range in source units, as volumes report it: [0, 0]
/// where no value is finite.
pub(super) fn source_units((lo, hi): (f64, f64)) -> [f64; 2] {
    if lo > hi {
        [0.0, 0.0]
    } else {
        [lo, hi]
    }
}

/// Wide values normalised as f32 over the finite range `(lo, hi)`; NaN and
/// infinities kept as they are (`Volume::new` stores them as no data).
/// A range whose difference or reciprocal overflows (-1e308 to 1e308, or
/// subnormal values) is divided by `span_ratio`, which would otherwise turn
/// finite voxels into NaN.
pub(super) fn normalizer((lo, hi): (f64, f64)) -> impl Fn(f64) -> f32 {
    let scale = if hi > lo { 1.0 / (hi - lo) } else { 0.0 };
    let exact = !(hi - lo).is_infinite() && scale.is_finite();
    move |v: f64| match (v.is_finite(), exact) {
        (false, _) => v as f32,
        (true, true) => ((v - lo) * scale) as f32,
        (true, false) => span_ratio([lo, v], [lo, hi]) as f32,
    }
}

/// `(a1 - a0) / (b1 - b0)`, at half scale where a difference overflows
/// f64 (values from -1e308 to 1e308), which would otherwise give NaN.
pub(super) fn span_ratio(a: [f64; 2], b: [f64; 2]) -> f64 {
    match (a[1] - a[0]).is_infinite() || (b[1] - b[0]).is_infinite() {
        true => (a[1] * 0.5 - a[0] * 0.5) / (b[1] * 0.5 - b[0] * 0.5),
        false => (a[1] - a[0]) / (b[1] - b[0]),
    }
}

/// f32 values normalised over their finite range.
fn normalized_f32(values: Vec<f64>) -> VoxelData {
    let normalize = normalizer(finite_range(values.iter().copied()));
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
        VoxelType::I8 => (
            VoxelData::U8(bytes.iter().map(|&b| shifted_i8(b)).collect()),
            Some(-128.0),
        ),
        VoxelType::U16 => (
            VoxelData::U16(words::<2>(bytes, little).map(u16::from_le_bytes).collect()),
            None,
        ),
        VoxelType::I16 => (
            VoxelData::U16(words::<2>(bytes, little).map(shifted_i16).collect()),
            Some(-32768.0),
        ),
        _ => (normalized_f32(wide_values(bytes, ty, little).collect()), None),
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
    // The finite values' range (NaN and infinities are no data).
    source_units(finite_range(wide_values(bytes, ty, little)))
}

#[cfg(test)]
mod tests {
    use super::normalizer;

    #[test]
    fn ranges_past_f64_and_subnormal_ranges_normalise_to_finite_values() {
        let wide = normalizer((-1e308, 1e308));
        assert_eq!([wide(-1e308), wide(0.0), wide(1e308)], [0.0, 0.5, 1.0]);
        let narrow = normalizer((1e-320, 5e-318));
        let (lo, hi) = (narrow(1e-320), narrow(5e-318));
        assert!((lo, hi) == (0.0, 1.0), "{lo} {hi}");
        assert!((narrow(2.5e-318) - 0.5).abs() < 0.01);
        let plain = normalizer((2.0, 6.0));
        assert_eq!([plain(2.0), plain(3.0), plain(6.0)], [0.0, 0.25, 1.0]);
        assert!(plain(f64::NAN).is_nan() && wide(f64::INFINITY) == f32::INFINITY);
    }
}
