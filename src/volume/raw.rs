//! Raw volumes: Open SciVis file names (`name_WxHxD_uint8.raw`) or an explicit
//! layout from `--dims`/`--type`. Little-endian.

use super::decode::{decode, VoxelType};
use super::{StreamTo, Volume};
use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use std::path::Path;

/// Dimensions and voxel type of a raw file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RawLayout {
    pub dims: [u32; 3],
    pub ty: VoxelType,
}

/// Parses `WxHxD` (each > 0).
pub fn parse_dims(s: &str) -> Result<[u32; 3]> {
    let parts: Vec<&str> = s.split('x').collect();
    let bad = |why: &str| Error::invalid("dimensions", s, why.to_string());
    let expected = "expected WxHxD with three positive integers";
    if parts.len() != 3 {
        return Err(bad(expected));
    }
    let mut dims = [0u32; 3];
    for (d, p) in dims.iter_mut().zip(&parts) {
        *d = match p.trim().parse::<u64>() {
            Ok(n) => u32::try_from(n).map_err(|_| bad(&format!("{n} is more than a side can be ({})", u32::MAX)))?,
            Err(_) => return Err(bad(expected)),
        };
    }
    super::check_dims(dims, s)?;
    Ok(dims)
}

/// The voxel type named `s` (`--type`).
pub fn parse_type(s: &str) -> Result<VoxelType> {
    VoxelType::from_name(s).ok_or_else(|| {
        Error::invalid(
            "voxel type",
            s,
            "expected uint8, uint16, int16, float32 or float64 (also int8, uint32, int32)",
        )
    })
}

/// The layout encoded in an Open SciVis file name, e.g. `skull_256x256x256_uint8.raw`.
pub fn layout_from_name(path: &Path) -> Result<RawLayout> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    // `.raw` in any case, as the loader takes the file.
    let stem = match name.len().checked_sub(4) {
        Some(at) if name.is_char_boundary(at) && name[at..].eq_ignore_ascii_case(".raw") => &name[..at],
        _ => name,
    };
    let mut parts = stem.rsplitn(3, '_');
    let (ty, dims) = (parts.next(), parts.next());
    let (Some(ty), Some(dims)) = (ty, dims) else {
        return Err(Error::format(
            path,
            "raw file name is not name_WxHxD_type.raw; give --dims WxHxD and --type",
        ));
    };
    let dims = parse_dims(dims)
        .map_err(|e| Error::format(path, format!("raw file name's dimensions: {e}; give --dims and --type")))?;
    let ty = VoxelType::from_name(ty).ok_or_else(|| {
        Error::format(
            path,
            format!("unknown voxel type '{ty}' in file name (expected uint8, uint16, int16, float32 or float64, also int8, uint32, int32)"),
        )
    })?;
    Ok(RawLayout { dims, ty })
}

pub fn load(
    path: &Path,
    layout: Option<RawLayout>,
    spacing: Option<[f32; 3]>,
    device: Option<&DeviceInfo>,
) -> Result<Volume> {
    let layout = match layout {
        Some(l) => l,
        None => layout_from_name(path)?,
    };
    // Sizes first: the file's length against its layout, then memory, so a
    // wrong name or --dims is an error before gigabytes are read.
    let (_, len) = crate::limits::open_input(path)?;
    check_length(path, len, layout)?;
    super::check_size(layout.dims, layout.ty, &path.display().to_string(), device)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode(path, &bytes, layout.ty, true, layout.dims, spacing.unwrap_or([1.0; 3]))
}

/// As `load`, streamed into bricks (`Series::load_bricks`): the file is
/// read a slab at a time into a `PoolStream` and decoded as `load` decodes
/// it (a float file is read twice: its range first), so the host never
/// holds the dense volume, and a rank reads only its block's layers
/// (`StreamTo::across`).
pub fn load_bricks(path: &Path, layout: Option<RawLayout>, to: &StreamTo) -> Result<Volume> {
    let layout = match layout {
        Some(l) => l,
        None => layout_from_name(path)?,
    };
    let (_, len) = crate::limits::open_input(path)?;
    check_length(path, len, layout)?;
    let layer = layout.dims[0] as u64 * layout.dims[1] as u64 * layout.ty.bytes() as u64;
    let open = |z: u32| -> Result<Box<dyn std::io::Read>> {
        let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(z as u64 * layer)).map_err(|e| Error::io(path, e))?;
        Ok(Box::new(std::io::BufReader::new(file)))
    };
    let file = super::slabs::SlabFile {
        path,
        dims: layout.dims,
        ty: layout.ty,
        little: true,
        open: &open,
        tail: None,
        slab_bytes: super::slabs::SLAB_BYTES,
        negate: false,
    };
    super::slabs::stream(&file, to, path.display().to_string(), [1.0; 3])
}

/// A raw volume from memory: `name` gives the layout as a file name does
/// (`name_WxHxD_type.raw`) unless `layout` is given.
pub fn from_bytes(name: &Path, bytes: &[u8], layout: Option<RawLayout>) -> Result<Volume> {
    let layout = match layout {
        Some(l) => l,
        None => layout_from_name(name)?,
    };
    check_length(name, bytes.len() as u64, layout)?;
    super::check_size(layout.dims, layout.ty, &name.display().to_string(), None)?;
    decode(name, bytes, layout.ty, true, layout.dims, [1.0; 3])
}

fn check_length(path: &Path, len: u64, layout: RawLayout) -> Result<()> {
    let [w, h, d] = layout.dims;
    let expected =
        super::check_dims(layout.dims, &path.display().to_string())?.saturating_mul(layout.ty.bytes() as u64);
    if len != expected {
        return Err(Error::format(
            path,
            format!(
                "holds {len} bytes of voxel data but {w}x{h}x{d} {} needs {expected}",
                layout.ty
            ),
        ));
    }
    Ok(())
}
