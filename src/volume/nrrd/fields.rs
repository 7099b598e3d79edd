//! A NRRD header's field values: the type names, number lists, the
//! lengths of `space directions` and `data file: LIST`.

use super::super::decode::VoxelType;
use crate::error::{Error, Result};
use std::path::Path;

pub(super) fn nrrd_type(s: &str) -> Option<VoxelType> {
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

pub(super) fn numbers(path: &Path, field: &str, value: &str) -> Result<Vec<f64>> {
    value
        .split_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| Error::format(path, format!("NRRD field '{field}': '{t}' is not a number")))
        })
        .collect()
}

/// Whether a `data file` value is `LIST` (its files on the lines after it,
/// or `LIST` and a subdimension), not a file whose name starts so.
pub(super) fn is_list(value: &str) -> bool {
    value == "LIST" || value.starts_with("LIST ")
}

/// Lengths of the vectors in `space directions: (a,b,c) (d,e,f) (g,h,i)`.
pub(super) fn direction_lengths(path: &Path, value: &str) -> Result<Vec<Option<f64>>> {
    let bad = |what: &str| Error::format(path, format!("NRRD space directions: bad vector '{what}'"));
    let mut out = Vec::new();
    let mut rest = value.trim_start();
    // Each axis is `none` (a non-spatial axis, anywhere: Slicer writes a
    // vector axis first) or a parenthesised vector.
    while !rest.is_empty() {
        if let Some(after) = rest.strip_prefix("none") {
            out.push(None);
            rest = after.trim_start();
            continue;
        }
        let Some(open) = rest.strip_prefix('(') else {
            return Err(bad(rest.split_whitespace().next().unwrap_or(rest)));
        };
        let Some(close) = open.find(')') else {
            return Err(bad(rest));
        };
        let inner = &open[..close];
        let comps: Result<Vec<f64>> = inner
            .split(',')
            .map(|t| t.trim().parse::<f64>().map_err(|_| bad(&format!("({inner})"))))
            .collect();
        out.push(Some(comps?.iter().map(|c| c * c).sum::<f64>().sqrt()));
        rest = open[close + 1..].trim_start();
    }
    Ok(out)
}
