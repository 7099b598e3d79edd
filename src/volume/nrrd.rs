//! NRRD reader (attached or detached header; raw or gzip encoding; 3-D).
//! Honours `spacings` or the lengths of `space directions`.

use super::decode::{decode, VoxelType};
use super::Volume;
use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

fn nrrd_type(s: &str) -> Option<VoxelType> {
    Some(match s {
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => VoxelType::U8,
        "signed char" | "int8" | "int8_t" => VoxelType::I8,
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => VoxelType::U16,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => VoxelType::I16,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => VoxelType::U32,
        "int" | "signed int" | "int32" | "int32_t" => VoxelType::I32,
        "float" => VoxelType::F32,
        "double" => VoxelType::F64,
        _ => return None,
    })
}

fn numbers(path: &Path, field: &str, value: &str) -> Result<Vec<f64>> {
    value
        .split_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| Error::format(path, format!("NRRD field '{field}': '{t}' is not a number")))
        })
        .collect()
}

/// Lengths of the vectors in `space directions: (a,b,c) (d,e,f) (g,h,i)`.
fn direction_lengths(path: &Path, value: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for part in value.split(')') {
        let inner = part.trim().trim_start_matches('(');
        if inner.is_empty() {
            continue;
        }
        if inner == "none" {
            continue;
        }
        let comps: Result<Vec<f64>> = inner
            .split(',')
            .map(|t| {
                t.trim()
                    .parse::<f64>()
                    .map_err(|_| Error::format(path, format!("NRRD space directions: bad vector '({inner})'")))
            })
            .collect();
        out.push(comps?.iter().map(|c| c * c).sum::<f64>().sqrt());
    }
    Ok(out)
}

pub fn load(path: &Path, device: Option<&DeviceInfo>) -> Result<Volume> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes, true, device)
}

/// A NRRD with attached data from memory (detached data files are an error).
pub fn from_bytes(origin: &Path, bytes: &[u8]) -> Result<Volume> {
    parse(origin, bytes, false, None)
}

/// Parses the header of `bytes`, checks the volume's size, then reads its
/// data: attached, or (when `detached` allows) from the named file.
fn parse(path: &Path, bytes: &[u8], detached: bool, device: Option<&DeviceInfo>) -> Result<Volume> {
    if !bytes.starts_with(b"NRRD000") {
        return Err(Error::format(path, "not a NRRD file (no NRRD000x magic)"));
    }
    // The header ends at the first empty line (attached data follows it).
    let mut fields: HashMap<String, String> = HashMap::new();
    let mut pos = 0usize;
    let mut first = true;
    let mut ended = false;
    while pos < bytes.len() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let line = String::from_utf8_lossy(&bytes[pos..end])
            .trim_end_matches('\r')
            .to_string();
        pos = end + 1;
        if first {
            first = false;
            continue;
        }
        if line.is_empty() {
            ended = true;
            break;
        }
        if line.starts_with('#') || line.contains(":=") {
            continue;
        }
        let Some((k, v)) = line.split_once(':') else {
            return Err(Error::format(path, format!("NRRD header line without ':': '{line}'")));
        };
        fields.insert(k.trim().to_lowercase(), v.trim().to_string());
    }
    let get = |k: &str| fields.get(k).map(String::as_str);
    let require = |k: &str| get(k).ok_or_else(|| Error::format(path, format!("NRRD header has no '{k}' field")));

    let ty_name = require("type")?;
    let ty =
        nrrd_type(ty_name).ok_or_else(|| Error::format(path, format!("NRRD type '{ty_name}' is not supported")))?;
    let dimension: usize = require("dimension")?
        .parse()
        .map_err(|_| Error::format(path, "NRRD 'dimension' is not an integer"))?;
    let sizes = numbers(path, "sizes", require("sizes")?)?;
    if dimension != 3 || sizes.len() != 3 {
        return Err(Error::format(
            path,
            format!("NRRD has dimension {dimension}; lacuna reads 3-D scalar volumes"),
        ));
    }
    let mut dims = [0u32; 3];
    for (d, &size) in dims.iter_mut().zip(&sizes) {
        if !(size.fract() == 0.0 && (1.0..=u32::MAX as f64).contains(&size)) {
            return Err(Error::format(
                path,
                format!("NRRD size '{size}' is not a positive 32-bit integer"),
            ));
        }
        *d = size as u32;
    }
    super::check_size(dims, ty, &path.display().to_string(), device)?;
    let little = match get("endian") {
        None | Some("little") => true,
        Some("big") => false,
        Some(e) => return Err(Error::format(path, format!("NRRD endian '{e}' is not little or big"))),
    };
    let spacing = if let Some(s) = get("spacings") {
        numbers(path, "spacings", s)?
    } else if let Some(d) = get("space directions") {
        direction_lengths(path, d)?
    } else {
        vec![1.0; 3]
    };
    let spacing = match spacing.as_slice() {
        [x, y, z] if [x, y, z].iter().all(|v| v.is_finite() && **v > 0.0) => [*x as f32, *y as f32, *z as f32],
        _ => return Err(Error::format(path, "NRRD spacings must be three positive numbers")),
    };

    let skip: u64 = get("byte skip").map_or(Ok(0), |s| {
        s.parse()
            .map_err(|_| Error::format(path, "NRRD 'byte skip' must be >= 0"))
    })?;
    let gzip = match require("encoding")? {
        "raw" => false,
        "gzip" | "gz" => true,
        other => {
            return Err(Error::format(
                path,
                format!("NRRD encoding '{other}' is not supported (raw, gzip)"),
            ))
        }
    };
    // The bytes the header describes: nothing reads or inflates beyond them
    // (one more tells a longer input), so no input expands without bound.
    let wanted = skip.saturating_add(dims.iter().map(|&d| d as u64).product::<u64>() * ty.bytes() as u64);
    let datafile = get("data file").or_else(|| get("datafile"));
    let (source, raw): (PathBuf, Cow<[u8]>) = match datafile {
        Some(name) => {
            if !detached {
                return Err(Error::format(
                    path,
                    format!("NRRD data file '{name}' is detached; load the header from its path"),
                ));
            }
            if name.starts_with("LIST") || name.contains('%') {
                return Err(Error::format(
                    path,
                    "NRRD multi-file data ('LIST' or format patterns) is not supported",
                ));
            }
            let data_path = path.parent().unwrap_or(Path::new(".")).join(name);
            // Deflate's worst case grows data by well under 1 %.
            let limit = if gzip {
                wanted.saturating_mul(2).saturating_add(1 << 16)
            } else {
                wanted
            };
            let raw = read_at_most(&data_path, limit)?;
            (data_path, Cow::Owned(raw))
        }
        None => {
            if !ended {
                return Err(Error::format(path, "NRRD header has no blank line before the data"));
            }
            (path.to_path_buf(), Cow::Borrowed(&bytes[pos.min(bytes.len())..]))
        }
    };
    let inflated;
    let data: &[u8] = if gzip {
        inflated = inflate(&source, &raw, wanted)?;
        &inflated
    } else {
        &raw
    };
    let payload = data.get(skip.min(usize::MAX as u64) as usize..).unwrap_or_default();
    let mut volume = decode(&source, payload, ty, little, dims, spacing)?;
    volume.name = path.display().to_string();
    Ok(volume)
}

/// Reads `path`, or fails (without reading on) when it holds more than
/// `limit` bytes; its exact length is then checked by `decode`.
fn read_at_most(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut out = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| Error::io(path, e))?;
    if out.len() as u64 > limit {
        return Err(Error::format(
            path,
            format!("holds more than the {limit} bytes the NRRD header describes"),
        ));
    }
    Ok(out)
}

/// Inflates gzip data, no further than `wanted` bytes and one more.
#[cfg(feature = "loaders")]
fn inflate(source: &Path, raw: &[u8], wanted: u64) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(raw)
        .take(wanted.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| Error::format(source, format!("corrupt gzip data: {e}")))?;
    Ok(out)
}

#[cfg(not(feature = "loaders"))]
fn inflate(source: &Path, _: &[u8], _: u64) -> Result<Vec<u8>> {
    Err(Error::format(
        source,
        "gzip-encoded NRRD needs lacuna's `loaders` cargo feature",
    ))
}
