//! NIfTI-1 (`.nii`, `.nii.gz`) through the `nifti` crate; pixdim gives spacing.

use super::decode::{decode, VoxelType};
use super::Volume;
use crate::error::{Error, Result};
use nifti::{NiftiObject, NiftiType, ReaderOptions};
use std::path::Path;

pub fn load(path: &Path) -> Result<Volume> {
    if let Err(e) = std::fs::metadata(path) {
        return Err(Error::io(path, e));
    }
    let object = ReaderOptions::new().read_file(path).map_err(|e| match e {
        nifti::NiftiError::Io(io) if io.kind() == std::io::ErrorKind::NotFound => Error::io(path, io),
        nifti::NiftiError::Io(io) => Error::format(
            path,
            format!("cannot read NIfTI data (truncated or corrupt gzip?): {io}"),
        ),
        // The crate's index and value do not name the offending field reliably.
        nifti::NiftiError::InconsistentDim(..) => {
            Error::format(path, "NIfTI header has a zero dimension or an invalid rank")
        }
        nifti::NiftiError::UnsupportedDataType(t) => {
            Error::format(path, format!("NIfTI datatype {t:?} is not supported"))
        }
        other => Error::format(path, format!("not a readable NIfTI-1 file: {other}")),
    })?;
    let header = object.header().clone();
    let ty = match header.data_type() {
        Ok(NiftiType::Uint8) => VoxelType::U8,
        Ok(NiftiType::Int8) => VoxelType::I8,
        Ok(NiftiType::Uint16) => VoxelType::U16,
        Ok(NiftiType::Int16) => VoxelType::I16,
        Ok(NiftiType::Uint32) => VoxelType::U32,
        Ok(NiftiType::Int32) => VoxelType::I32,
        Ok(NiftiType::Float32) => VoxelType::F32,
        Ok(NiftiType::Float64) => VoxelType::F64,
        Ok(other) => {
            return Err(Error::format(
                path,
                format!("NIfTI datatype {other:?} ({}) is not supported", header.datatype),
            ))
        }
        Err(_) => {
            return Err(Error::format(
                path,
                format!("NIfTI datatype code {} is not supported", header.datatype),
            ))
        }
    };
    let rank = header.dim[0] as usize;
    if !(1..=7).contains(&rank) {
        return Err(Error::format(
            path,
            format!("NIfTI dim[0] = {rank} is not a valid rank"),
        ));
    }
    // Trailing singleton dimensions (a 3-D volume stored as 4-D with t = 1) are fine.
    if header.dim[4..=rank.max(3)].iter().any(|&d| d > 1) {
        return Err(Error::format(
            path,
            format!("NIfTI volume has {rank} dimensions with more than one 3-D frame"),
        ));
    }
    let dims = [1, 2, 3].map(|i| if i <= rank { header.dim[i] as u32 } else { 1 });
    let spacing = [1, 2, 3].map(|i| {
        let s = header.pixdim[i].abs();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    let little = header.endianness == nifti::Endianness::Little;
    let raw = object.into_volume().into_raw_data();
    let mut volume = decode(path, &raw, ty, little, dims, spacing)?;
    // scl_slope/scl_inter rescale linearly; normalised values are unchanged
    // for a positive slope, so only the reported range moves.
    let (slope, inter) = (header.scl_slope as f64, header.scl_inter as f64);
    if slope != 0.0 && slope.is_finite() && inter.is_finite() {
        let [a, b] = volume.value_range.map(|v| v * slope + inter);
        volume.value_range = [a.min(b), a.max(b)];
    }
    Ok(volume)
}
