//! NIfTI-1 single files (`.nii`, `.nii.gz`): the `nifti` crate parses the
//! header; lacuna checks the volume's size from it, then decodes the voxels
//! itself, reading (or inflating) no more bytes than the header describes.

use super::decode::{decode, VoxelType};
use super::Volume;
use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use nifti::{NiftiHeader, NiftiType};
use std::io::Read;
use std::path::Path;

pub fn load(path: &Path, device: Option<&DeviceInfo>) -> Result<Volume> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes, device)
}

/// A `.nii` from memory, or a `.nii.gz` when `bytes` start with the gzip magic.
pub fn from_bytes(origin: &Path, bytes: &[u8]) -> Result<Volume> {
    parse(origin, bytes, None)
}

fn unreadable(path: &Path, e: std::io::Error) -> Error {
    Error::format(
        path,
        format!("cannot read NIfTI data (truncated or corrupt gzip?): {e}"),
    )
}

fn parse(path: &Path, bytes: &[u8], device: Option<&DeviceInfo>) -> Result<Volume> {
    let gz = bytes.starts_with(&[0x1f, 0x8b]);
    let stream = || -> Box<dyn Read + '_> {
        if gz {
            Box::new(flate2::read::MultiGzDecoder::new(bytes))
        } else {
            Box::new(bytes)
        }
    };
    let header = NiftiHeader::from_reader(stream()).map_err(|e| match e {
        nifti::NiftiError::Io(io) => unreadable(path, io),
        // The crate's index and value do not name the offending field reliably.
        nifti::NiftiError::InconsistentDim(..) => {
            Error::format(path, "NIfTI header has a zero dimension or an invalid rank")
        }
        other => Error::format(path, format!("not a readable NIfTI-1 file: {other}")),
    })?;
    if &header.magic != b"n+1\0" {
        return Err(Error::format(
            path,
            "not a single-file NIfTI-1 (magic is not 'n+1'; .hdr/.img pairs are not supported)",
        ));
    }
    let ty = voxel_type(path, &header)?;
    let rank = header.dim[0] as usize;
    if !(1..=7).contains(&rank) {
        return Err(Error::format(
            path,
            format!("NIfTI dim[0] = {rank} is not a valid rank"),
        ));
    }
    // Dimensions are signed in the format; the crate reads them unsigned.
    if header.dim[1..=rank].iter().any(|&d| d == 0 || d > i16::MAX as u16) {
        return Err(Error::format(
            path,
            "NIfTI header has a zero dimension or an invalid rank",
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
    super::check_size(dims, ty, &path.display().to_string(), device)?;
    let offset = header.vox_offset;
    if !(offset.is_finite() && (348.0..=(1u64 << 32) as f32).contains(&offset)) {
        return Err(Error::format(
            path,
            format!("NIfTI vox_offset {offset} is not a byte offset past the header"),
        ));
    }
    let offset = offset as u64;
    let voxel_bytes = dims.iter().map(|&d| d as u64).product::<u64>() * ty.bytes() as u64;
    let end = offset + voxel_bytes;
    let inflated;
    let file: &[u8] = if gz {
        let mut out = Vec::new();
        stream()
            .take(end)
            .read_to_end(&mut out)
            .map_err(|e| unreadable(path, e))?;
        inflated = out;
        &inflated
    } else {
        bytes
    };
    // Data past the voxels (none in a well-formed file) is ignored, as the crate did.
    let data = file.get(offset as usize..).unwrap_or_default();
    let data = &data[..data.len().min(voxel_bytes as usize)];
    let spacing = [1, 2, 3].map(|i| {
        let s = header.pixdim[i].abs();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    let little = header.endianness == nifti::Endianness::Little;
    let mut volume = decode(path, data, ty, little, dims, spacing)?;
    // scl_slope/scl_inter rescale linearly; normalised values are unchanged
    // for a positive slope, so only the reported range moves.
    let (slope, inter) = (header.scl_slope as f64, header.scl_inter as f64);
    if slope != 0.0 && slope.is_finite() && inter.is_finite() {
        let [a, b] = volume.value_range.map(|v| v * slope + inter);
        volume.value_range = [a.min(b), a.max(b)];
    }
    Ok(volume)
}

fn voxel_type(path: &Path, header: &NiftiHeader) -> Result<VoxelType> {
    Ok(match header.data_type() {
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
    })
}
