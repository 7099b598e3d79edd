//! NIfTI-1 single files (`.nii`, `.nii.gz`): the `nifti` crate parses the
//! header; lacuna checks the volume's size from it, then decodes the voxels
//! itself, reading (or inflating) no more bytes than the header describes.

use super::decode::{decode, VoxelType};
use super::{StreamTo, Volume};
use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use nifti::{NiftiHeader, NiftiType};
use std::io::{BufRead, Read};
use std::path::Path;

pub fn load(path: &Path, device: Option<&DeviceInfo>) -> Result<Volume> {
    load_step(path, 0, device)
}

/// Step `step` of a file whose 4th dimension is time (step 0 of a 3-D
/// file), reading or inflating no further than that step's voxels.
pub fn load_step(path: &Path, step: u32, device: Option<&DeviceInfo>) -> Result<Volume> {
    parse(path, open(path)?, step, device)
}

/// The time steps of a NIfTI file (its 4th dimension; 1 for a 3-D file),
/// from its header.
pub fn steps(path: &Path) -> Result<u32> {
    let header = header(path, open(path)?)?;
    let l = layout(path, &header)?;
    // A time axis the data does not hold is refused here, not when a step
    // past the data's end is asked for.
    if l.steps > 1 {
        let [w, h, d] = l.dims;
        let voxel_bytes = w as u64 * h as u64 * d as u64 * l.ty.bytes() as u64;
        let end =
            voxel_offset(path, &header)?.saturating_add(voxel_bytes.saturating_mul(l.steps as u64 * l.channels as u64));
        let (_, len) = crate::limits::open_input(path)?;
        if gzipped(path)? {
            super::check_gzip_holds(path, len, end)?;
        } else if len < end {
            return Err(Error::format(
                path,
                format!(
                    "holds {len} bytes, but the {} time steps of {w}x{h}x{d} {} voxels ({} channel(s)) its header gives end at byte {end}",
                    l.steps, l.ty, l.channels
                ),
            ));
        }
    }
    Ok(l.steps)
}

/// The channels of a NIfTI file (its 5th dimension; 1 without one), from
/// its header.
pub fn channels(path: &Path) -> Result<u32> {
    let header = header(path, open(path)?)?;
    Ok(layout(path, &header)?.channels)
}

/// Whether the file starts with the gzip magic.
fn gzipped(path: &Path) -> Result<bool> {
    let mut magic = [0u8; 2];
    let (mut file, _) = crate::limits::open_input(path)?;
    let n = file.read(&mut magic).map_err(|e| Error::io(path, e))?;
    Ok(n == 2 && magic == [0x1f, 0x8b])
}

/// The file's bytes, inflated when it starts with the gzip magic.
fn open(path: &Path) -> Result<Box<dyn Read>> {
    // Checked as an input file (a regular one) before the open.
    let gzip = gzipped(path)?;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    Ok(match gzip {
        true => Box::new(Members::new(Box::new(std::io::BufReader::new(file)))),
        false => Box::new(std::io::BufReader::new(file)),
    })
}

/// A `.nii` from memory, or a `.nii.gz` when `bytes` start with the gzip magic.
pub fn from_bytes(origin: &Path, bytes: &[u8]) -> Result<Volume> {
    let reader: Box<dyn Read + '_> = match bytes.starts_with(&[0x1f, 0x8b]) {
        true => Box::new(Members::new(Box::new(bytes))),
        false => Box::new(bytes),
    };
    parse(origin, reader, 0, None)
}

/// Gzip members inflated one after another, as gzip(1) and Python's gzip
/// read them: each member's CRC and length are checked at its end, and
/// bytes after a member that do not start another (the zero padding some
/// tools add) end the data rather than being an error.
struct Members<'a> {
    member: Option<flate2::bufread::GzDecoder<Box<dyn BufRead + 'a>>>,
}

impl<'a> Members<'a> {
    fn new(raw: Box<dyn BufRead + 'a>) -> Self {
        Members {
            member: Some(flate2::bufread::GzDecoder::new(raw)),
        }
    }
}

impl Read for Members<'_> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while let Some(member) = self.member.as_mut() {
            let n = member.read(out)?;
            if n > 0 || out.is_empty() {
                return Ok(n);
            }
            // The member ended, checked: does another member's magic follow?
            let Some(mut raw) = self.member.take().map(|m| m.into_inner()) else {
                break;
            };
            let buf = raw.fill_buf()?;
            if buf.starts_with(&[0x1f, 0x8b]) {
                self.member = Some(flate2::bufread::GzDecoder::new(raw));
            } else if buf == [0x1f] {
                // The buffer ends between the magic's two bytes (rare): look
                // past it, and put the first back in front.
                raw.consume(1);
                if raw.fill_buf()?.first() == Some(&0x8b) {
                    let rest: Box<dyn BufRead + '_> = Box::new(std::io::Cursor::new([0x1f]).chain(raw));
                    self.member = Some(flate2::bufread::GzDecoder::new(rest));
                }
            }
        }
        Ok(0)
    }
}

/// The NIfTI-1 header's size: the voxels' offset is counted from the start.
const HEADER_BYTES: u64 = 348;

fn unreadable(path: &Path, e: std::io::Error) -> Error {
    Error::format(
        path,
        format!("cannot read NIfTI data (truncated or corrupt gzip?): {e}"),
    )
}

fn header(path: &Path, mut reader: impl Read) -> Result<NiftiHeader> {
    // NIfTI-2 (HCP's, nibabel's Nifti2Image) starts with its header's size
    // too: named, rather than refused as a broken NIfTI-1.
    let mut size = [0u8; 4];
    reader.read_exact(&mut size).map_err(|e| unreadable(path, e))?;
    let sizes = [i32::from_le_bytes(size), i32::from_be_bytes(size)];
    if sizes.contains(&540) {
        return Err(Error::format(
            path,
            "is NIfTI-2 (sizeof_hdr 540), and lacuna reads NIfTI-1: save it as NIfTI-1 (nibabel's Nifti1Image)",
        ));
    }
    if !sizes.contains(&(HEADER_BYTES as i32)) {
        return Err(Error::format(
            path,
            format!("not a NIfTI-1 header: its sizeof_hdr is {}, not 348", sizes[0]),
        ));
    }
    // Exactly the header's bytes, so what follows is where the caller is.
    let header = (&size[..]).chain(reader).take(HEADER_BYTES);
    NiftiHeader::from_reader(header).map_err(|e| match e {
        nifti::NiftiError::Io(io) => unreadable(path, io),
        // The crate's index and value do not name the offending field reliably.
        nifti::NiftiError::InconsistentDim(..) => {
            Error::format(path, "NIfTI header has a zero dimension or an invalid rank")
        }
        other => Error::format(path, format!("not a readable NIfTI-1 file: {other}")),
    })
}

/// A file's grid and time steps, as its header gives them.
struct Layout {
    ty: VoxelType,
    dims: [u32; 3],
    steps: u32,
    /// dim[5], NIfTI's vector (component) axis: the volume's channels.
    channels: u32,
}

fn layout(path: &Path, header: &NiftiHeader) -> Result<Layout> {
    if &header.magic != b"n+1\0" {
        return Err(Error::format(
            path,
            "not a single-file NIfTI-1 (magic is not 'n+1'; .hdr/.img pairs are not supported)",
        ));
    }
    let rank = header.dim[0] as usize;
    if !(1..=7).contains(&rank) {
        // The crate swaps a header whose rank is invalid as stored, so show
        // the value both ways (as a signed 16-bit number, as stored).
        let read = header.dim[0];
        let little = match header.endianness {
            nifti::Endianness::Little => read,
            nifti::Endianness::Big => read.swap_bytes(),
        } as i16;
        let big = (little as u16).swap_bytes() as i16;
        return Err(Error::format(
            path,
            format!("NIfTI dim[0] is {little} read little-endian and {big} big-endian: not a valid rank (1 to 7) either way"),
        ));
    }
    // After the rank: a header swapped for an invalid rank has a swapped type too.
    let ty = voxel_type(path, header)?;
    // Dimensions are signed in the format; the crate reads them unsigned.
    if header.dim[1..=rank].iter().any(|&d| d == 0 || d > i16::MAX as u16) {
        return Err(Error::format(
            path,
            "NIfTI header has a zero dimension or an invalid rank",
        ));
    }
    // The 4th dimension is time, the 5th components (channels); trailing
    // singletons are fine.
    if header.dim[6..=rank.max(5)].iter().any(|&d| d > 1) {
        return Err(Error::format(
            path,
            format!(
                "NIfTI volume has {rank} dimensions: beyond x, y, z, time and components (dim[6..]) are not supported"
            ),
        ));
    }
    let dims = [1, 2, 3].map(|i| if i <= rank { header.dim[i] as u32 } else { 1 });
    let steps = if rank >= 4 { header.dim[4] as u32 } else { 1 };
    let channels = if rank >= 5 { header.dim[5] as u32 } else { 1 };
    if channels > super::MAX_CHANNELS as u32 {
        return Err(Error::format(
            path,
            format!(
                "NIfTI dim[5] has {channels} components: a volume has 1 to {} channels",
                super::MAX_CHANNELS
            ),
        ));
    }
    Ok(Layout {
        ty,
        dims,
        steps,
        channels,
    })
}

fn parse(path: &Path, mut reader: Box<dyn Read + '_>, step: u32, device: Option<&DeviceInfo>) -> Result<Volume> {
    let header = header(path, &mut reader)?;
    let l = layout(path, &header)?;
    super::check_file_step(path, step, l.steps)?;
    let (ty, dims, steps, channels) = (l.ty, l.dims, l.steps, l.channels);
    for _ in 0..channels {
        super::check_size(dims, ty, &path.display().to_string(), device)?;
    }
    let offset = voxel_offset(path, &header)?;
    let voxel_bytes = dims.iter().map(|&d| d as u64).product::<u64>() * ty.bytes() as u64;
    // Each channel's block of this step (x, y, z, then time, then
    // components, slowest): skip to it and read it, in file order.
    let mut at = HEADER_BYTES;
    let mut blocks = Vec::new();
    for c in 0..channels as u64 {
        let start = offset as u64 + (c * steps as u64 + step as u64) * voxel_bytes;
        let skip = start - at;
        let skipped =
            std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink()).map_err(|e| unreadable(path, e))?;
        let mut data = Vec::new();
        if skipped == skip {
            (&mut reader)
                .take(voxel_bytes)
                .read_to_end(&mut data)
                .map_err(|e| unreadable(path, e))?;
        }
        // A short block of a step of several is named by its step (and
        // channel): the file ends before it.
        if data.len() as u64 != voxel_bytes && (steps > 1 || channels > 1) {
            let [w, h, d] = dims;
            return Err(Error::format(
                path,
                format!(
                    "ends before time step {step} (0 to {}) of channel {} of {channels}: it holds {} of that block's {voxel_bytes} bytes ({w}x{h}x{d} {ty})",
                    steps - 1,
                    c + 1,
                    data.len()
                ),
            ));
        }
        at = start + data.len() as u64;
        blocks.push(data);
    }
    // Data past the voxels (none in a well-formed file) is ignored, as the
    // crate did; a gzip file's trailer is checked where the last step ends.
    if step + 1 == steps && blocks.last().is_some_and(|b| b.len() as u64 == voxel_bytes) {
        meet_the_trailer(path, &mut reader)?;
    }
    let little = header.endianness == nifti::Endianness::Little;
    let scaling = scaling(&header, ty);
    let mut volumes = Vec::new();
    for (c, data) in blocks.iter_mut().enumerate() {
        if scaling.is_some_and(|s| s.negate) {
            super::decode::negate_raw(data, ty, little);
        }
        let mut volume = decode(path, data, ty, little, dims, spacing(&header))?;
        rescale_range(&mut volume, scaling);
        if channels > 1 {
            volume.name = format!("{}[{c}]", path.display());
        }
        volumes.push(volume);
    }
    if volumes.len() == 1 {
        return Ok(volumes.remove(0));
    }
    let mut joined = Volume::join(volumes)?;
    joined.name = path.display().to_string();
    Ok(joined)
}

/// Reads a byte past the last step's voxels, so a `.nii.gz`'s decoder
/// reaches its trailer and checks the CRC and length of what it inflated
/// (a corrupt file is an error, not a silently wrong volume).
fn meet_the_trailer(path: &Path, reader: &mut dyn Read) -> Result<()> {
    let mut byte = [0u8; 1];
    reader.read(&mut byte).map_err(|e| unreadable(path, e))?;
    Ok(())
}

/// Where the voxels start: `vox_offset`, checked.
fn voxel_offset(path: &Path, header: &NiftiHeader) -> Result<u64> {
    let offset = header.vox_offset;
    if !(offset.is_finite() && (348.0..=(1u64 << 32) as f32).contains(&offset)) {
        return Err(Error::format(
            path,
            format!("NIfTI vox_offset {offset} is not a byte offset past the header"),
        ));
    }
    Ok(offset as u64)
}

/// `pixdim[1..=3]`, 1 where one is not a positive number.
fn spacing(header: &NiftiHeader) -> [f32; 3] {
    [1, 2, 3].map(|i| {
        let s = header.pixdim[i].abs();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    })
}

/// A NIfTI's `scl_slope` / `scl_inter` (value = slope x raw + inter), with
/// a positive slope: a negative one is read as its negation over the raw
/// voxels negated within their type (`decode::negate_raw`: raw = k - raw'),
/// and the intercept moved to match (inter + slope x k), so the volume's
/// values grow with what lacuna stores and its normalisation stays
/// increasing.
#[derive(Clone, Copy)]
struct Scaling {
    negate: bool,
    slope: f64,
    inter: f64,
}

/// The file's scaling; None where it scales nothing (slope 0, as the
/// format says, or not finite). A non-finite intercept is 0, as
/// nifti_clib reads it: the slope still applies.
fn scaling(header: &NiftiHeader, ty: VoxelType) -> Option<Scaling> {
    let slope = header.scl_slope as f64;
    let inter = match header.scl_inter as f64 {
        i if i.is_finite() => i,
        _ => 0.0,
    };
    if slope == 0.0 || !slope.is_finite() {
        return None;
    }
    if slope > 0.0 {
        return Some(Scaling {
            negate: false,
            slope,
            inter,
        });
    }
    // raw = k - raw' for the complement (unsigned: MAX, signed: -1) and
    // the sign flip (floats: 0).
    let k = match ty {
        VoxelType::U8 => u8::MAX as f64,
        VoxelType::U16 => u16::MAX as f64,
        VoxelType::U32 => u32::MAX as f64,
        VoxelType::I8 | VoxelType::I16 | VoxelType::I32 => -1.0,
        VoxelType::F32 | VoxelType::F64 => 0.0,
    };
    Some(Scaling {
        negate: true,
        slope: -slope,
        inter: inter + slope * k,
    })
}

/// The value range in scaled units: normalised values are unchanged by a
/// positive slope, so only the reported range moves.
fn rescale_range(volume: &mut Volume, scaling: Option<Scaling>) {
    if let Some(Scaling { slope, inter, .. }) = scaling {
        volume.value_range = volume.value_range.map(|v| v * slope + inter);
    }
}

/// The grid and type of a one-channel NIfTI (from its header); None for
/// one with channels or a header that does not parse.
pub fn streamed_layout(path: &Path) -> Option<([u32; 3], VoxelType)> {
    let l = layout(path, &header(path, open(path).ok()?).ok()?).ok()?;
    (l.channels == 1).then_some((l.dims, l.ty))
}

/// Step `step` of a one-channel NIfTI streamed into bricks as `to` says
/// (`slabs.rs`): a `.nii` read from its first needed layer on, a `.nii.gz`
/// inflated on the fly, so the host never holds the dense volume. A file
/// with channels loads whole.
pub fn load_step_bricks(path: &Path, step: u32, to: &StreamTo) -> Result<Volume> {
    let header = header(path, open(path)?)?;
    let l = layout(path, &header)?;
    if l.channels > 1 {
        return load_step(path, step, None);
    }
    super::check_file_step(path, step, l.steps)?;
    let (ty, dims) = (l.ty, l.dims);
    let layer = dims[0] as u64 * dims[1] as u64 * ty.bytes() as u64;
    let voxel_bytes = layer * dims[2] as u64;
    let first = voxel_offset(path, &header)? + step as u64 * voxel_bytes;
    let gzip = gzipped(path)?;
    // A short file is found before a layer is read.
    let (_, len) = crate::limits::open_input(path)?;
    if gzip {
        super::check_gzip_holds(path, len, first + voxel_bytes)?;
    } else if len < first + voxel_bytes {
        return Err(Error::format(
            path,
            format!(
                "holds {len} bytes, but step {step} of its {}x{}x{} {ty} voxels ends at byte {}",
                dims[0],
                dims[1],
                dims[2],
                first + voxel_bytes
            ),
        ));
    }
    let open_at = |z: u32| -> Result<Box<dyn Read>> {
        let at = first + z as u64 * layer;
        if !gzip {
            let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
            std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(at)).map_err(|e| Error::io(path, e))?;
            return Ok(Box::new(std::io::BufReader::new(file)));
        }
        let mut reader = open(path)?;
        let skipped =
            std::io::copy(&mut (&mut reader).take(at), &mut std::io::sink()).map_err(|e| unreadable(path, e))?;
        if skipped < at {
            return Err(Error::format(
                path,
                format!("holds {skipped} bytes of inflated data, but step {step} starts past byte {at}"),
            ));
        }
        Ok(reader)
    };
    let trailer = |reader: &mut dyn Read| meet_the_trailer(path, reader);
    let scaling = scaling(&header, ty);
    let file = super::slabs::SlabFile {
        path,
        dims,
        ty,
        little: header.endianness == nifti::Endianness::Little,
        open: &open_at,
        tail: (step + 1 == l.steps).then_some(&trailer as &super::slabs::TailCheck),
        slab_bytes: super::slabs::SLAB_BYTES,
        negate: scaling.is_some_and(|s| s.negate),
    };
    let mut volume = super::slabs::stream(&file, to, path.display().to_string(), spacing(&header))?;
    rescale_range(&mut volume, scaling);
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
