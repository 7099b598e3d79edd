//! NRRD reader (attached or detached header; raw or gzip encoding; 3-D).
//! Honours `spacings` or the lengths of `space directions`.

use super::decode::{decode, VoxelType};
use super::Volume;
use crate::error::{Error, Result};
use std::collections::HashMap;
#[cfg(feature = "loaders")]
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

pub fn load(path: &Path) -> Result<Volume> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
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
    let dims = [sizes[0] as u32, sizes[1] as u32, sizes[2] as u32];
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

    let datafile = get("data file").or_else(|| get("datafile"));
    let (source, raw): (PathBuf, Vec<u8>) = match datafile {
        Some(name) => {
            if name.starts_with("LIST") || name.contains('%') {
                return Err(Error::format(
                    path,
                    "NRRD multi-file data ('LIST' or format patterns) is not supported",
                ));
            }
            let data_path = path.parent().unwrap_or(Path::new(".")).join(name);
            let raw = std::fs::read(&data_path).map_err(|e| Error::io(&data_path, e))?;
            (data_path, raw)
        }
        None => {
            if !ended {
                return Err(Error::format(path, "NRRD header has no blank line before the data"));
            }
            (path.to_path_buf(), bytes[pos.min(bytes.len())..].to_vec())
        }
    };
    let skip: usize = get("byte skip").map_or(Ok(0), |s| {
        s.parse()
            .map_err(|_| Error::format(path, "NRRD 'byte skip' must be >= 0"))
    })?;
    let encoding = require("encoding")?;
    let payload = match encoding {
        "raw" => raw.get(skip..).unwrap_or_default().to_vec(),
        #[cfg(not(feature = "loaders"))]
        "gzip" | "gz" => {
            return Err(Error::format(
                path,
                "gzip-encoded NRRD needs lacuna's `loaders` cargo feature",
            ))
        }
        #[cfg(feature = "loaders")]
        "gzip" | "gz" => {
            let mut out = Vec::new();
            flate2::read::MultiGzDecoder::new(raw.as_slice())
                .read_to_end(&mut out)
                .map_err(|e| Error::format(&source, format!("corrupt gzip data: {e}")))?;
            out.get(skip..).unwrap_or_default().to_vec()
        }
        other => {
            return Err(Error::format(
                path,
                format!("NRRD encoding '{other}' is not supported (raw, gzip)"),
            ))
        }
    };
    let mut volume = decode(&source, &payload, ty, little, dims, spacing)?;
    volume.name = path.display().to_string();
    Ok(volume)
}
