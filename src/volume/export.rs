//! Raw export: any volume as an Open SciVis-named raw file
//! (`name_WxHxD_type.raw`, little-endian, x fastest) in its source units, so
//! other tools (VTK, ParaView, lacuna's own raw loader) read the voxels lacuna
//! renders.
//!
//! lacuna keeps uint8 and uint16 voxels native (int8 and int16 shifted into
//! them) and every other type as float32 normalised to [0, 1] over the source
//! range (`Volume::value_range`). [`SourceValues`] undoes that: the stored
//! range maps linearly onto `value_range`, and values of integer source types
//! are rounded to the nearest integer. uint8 and uint16 (and int8, int16)
//! sources are therefore reproduced exactly; uint32, int32, float32 and
//! float64 sources to the float32 precision lacuna kept (a relative 2^-25 of
//! the value range).

use super::{check_dims, Volume, VoxelData, VoxelType};
use crate::error::{Error, Result};
use crate::frame::{check_parent, write_atomically};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The voxel types a raw export writes.
pub const EXPORT_TYPES: [VoxelType; 3] = [VoxelType::U8, VoxelType::U16, VoxelType::F32];

/// Parses an export type: `uint8`, `uint16` or `float32`.
pub fn parse_export_type(s: &str) -> Result<VoxelType> {
    VoxelType::from_name(s)
        .filter(|t| EXPORT_TYPES.contains(t))
        .ok_or_else(|| Error::invalid("export type", s, "expected uint8, uint16 or float32"))
}

/// A volume's voxel values in source units, reconstructed from the stored
/// ones: `source = lo + (stored - stored_min) * (hi - lo) / (stored_max - stored_min)`
/// with `[lo, hi] = value_range`, rounded for integer source types.
pub struct SourceValues<'a> {
    data: &'a VoxelData,
    dims: [u32; 3],
    stored_min: f64,
    lo: f64,
    scale: f64,
    /// `scale` is half the range's (the range overflows f64's differences).
    halves: bool,
    source_type: VoxelType,
    integer: bool,
    /// How far a reconstructed float value may lie from the source value.
    tolerance: f64,
}

impl<'a> SourceValues<'a> {
    pub fn new(volume: &'a Volume) -> Self {
        let (smin, smax) = volume.data.stored_range();
        let [lo, hi] = volume.value_range;
        // A range past f64's differences (-1e308 to 1e308) is taken at half
        // scale, and each value rebuilt as lo + x + x.
        let halves = (hi - lo).is_infinite();
        let span = if halves { hi * 0.5 - lo * 0.5 } else { hi - lo };
        let scale = if smax > smin { span / (smax - smin) } else { 0.0 };
        // Float data hold the source values to f32 precision: half an ulp of
        // [0, 1] is at most 2^-25 of the range; allow twice that.
        let tolerance = match volume.data.texel_bytes() {
            4 => span.abs() * (-24f64).exp2() * if halves { 2.0 } else { 1.0 },
            _ => 0.0,
        };
        let mut values = SourceValues {
            data: &volume.data,
            dims: volume.dims,
            stored_min: smin,
            lo,
            scale,
            halves,
            source_type: volume.source_type,
            integer: false,
            tolerance,
        };
        // Integer sources stay integers unless scaled by a fraction (a
        // NIfTI's scl_slope / scl_inter): told from the values themselves,
        // as wider integer types are stored normalised.
        // Past a tolerance of a quarter every value would pass: rounding
        // could only lose a scaled value's fraction then.
        values.integer = !matches!(volume.source_type, VoxelType::F32 | VoxelType::F64)
            && tolerance < 0.25
            && (0..values.len()).all(|i| {
                let v = values.get(i);
                (v - v.round()).abs() <= tolerance
            });
        values
    }

    pub fn len(&self) -> usize {
        self.data.len()
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The source value of voxel `i` (x fastest); panics if `i >= len()`.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        let stored = self.data.stored_at(i);
        let value = match self.halves {
            true => {
                let half = (stored - self.stored_min) * self.scale;
                (self.lo + half) + half
            }
            false => self.lo + (stored - self.stored_min) * self.scale,
        };
        if self.integer {
            value.round()
        } else {
            value
        }
    }

    /// `(x, y, z)` of voxel `i`.
    pub fn voxel(&self, i: usize) -> (u64, u64, u64) {
        let (w, h) = (self.dims[0].max(1) as u64, self.dims[1].max(1) as u64);
        let i = i as u64;
        (i % w, i / w % h, i / (w * h))
    }

    /// A value as the source type prints it.
    fn show(&self, v: f64) -> String {
        if self.integer {
            format!("{v}")
        } else {
            format!("{}", v as f32)
        }
    }

    /// The integer `ty` stores for `value`, if it holds it (float sources
    /// within their precision of an integer).
    fn integer_in(&self, value: f64, ty: VoxelType) -> Option<f64> {
        let max = match ty {
            VoxelType::U8 => 255.0,
            VoxelType::U16 => 65535.0,
            _ => return None,
        };
        let n = value.round();
        ((value - n).abs() <= self.tolerance && (0.0..=max).contains(&n)).then_some(n)
    }

    /// The first voxel whose value `ty` cannot hold, with the reason.
    fn first_misfit(&self, ty: VoxelType) -> Option<(usize, String)> {
        (0..self.len()).find_map(|i| {
            let v = self.get(i);
            let why = if v.is_nan() && ty == VoxelType::F32 {
                // No data stays NaN (infinities were stored as NaN).
                return None;
            } else if v.is_nan() {
                format!("without data (NaN), which {ty} cannot hold")
            } else if !v.is_finite() {
                "not a finite number".to_string()
            } else if ty == VoxelType::F32 && (v as f32).is_infinite() {
                format!("{v:e}, beyond float32's largest magnitude {:e}", f32::MAX)
            } else if ty == VoxelType::F32 || self.integer_in(v, ty).is_some() {
                return None;
            } else if (v - v.round()).abs() > self.tolerance {
                format!("{}, not an integer", self.show(v))
            } else {
                let max = if ty == VoxelType::U8 { 255 } else { 65535 };
                format!("{}, outside {ty}'s range 0 to {max}", self.show(v))
            };
            Some((i, why))
        })
    }

    /// The export type: `requested` if it holds every value, else an error
    /// naming the first voxel it cannot hold. Without a request: the source
    /// type if it is uint8, uint16 or float32 and holds every value (a
    /// NIfTI's scaling can take them past it), else the smallest of those
    /// that does (float32 holds integers exactly up to 2^24).
    pub fn export_type(&self, requested: Option<VoxelType>) -> Result<VoxelType> {
        if let Some((i, why)) = self.first_misfit(VoxelType::F32) {
            let (x, y, z) = self.voxel(i);
            return Err(Error::invalid(
                "voxel",
                format!("({x}, {y}, {z})"),
                format!("{why}; a raw file cannot hold it"),
            ));
        }
        let smallest = || {
            EXPORT_TYPES
                .into_iter()
                .find(|&t| self.first_misfit(t).is_none())
                .unwrap_or(VoxelType::F32)
        };
        let Some(ty) = requested else {
            return Ok(
                if EXPORT_TYPES.contains(&self.source_type) && self.first_misfit(self.source_type).is_none() {
                    self.source_type
                } else {
                    smallest()
                },
            );
        };
        if !EXPORT_TYPES.contains(&ty) {
            return Err(Error::invalid(
                "export type",
                ty.name(),
                "expected uint8, uint16 or float32",
            ));
        }
        match self.first_misfit(ty) {
            None => Ok(ty),
            Some((i, why)) => {
                let (x, y, z) = self.voxel(i);
                Err(Error::invalid(
                    "export type",
                    ty.name(),
                    format!("voxel ({x}, {y}, {z}) is {why}; {} holds every value", smallest()),
                ))
            }
        }
    }

    /// Appends voxels `range` encoded as `ty`, little-endian; the type must
    /// hold them (see `export_type`).
    fn encode(&self, range: std::ops::Range<usize>, ty: VoxelType, out: &mut Vec<u8>) {
        for i in range {
            let v = self.get(i);
            match ty {
                VoxelType::U8 => out.push(self.integer_in(v, ty).unwrap_or(0.0) as u8),
                VoxelType::U16 => out.extend((self.integer_in(v, ty).unwrap_or(0.0) as u16).to_le_bytes()),
                _ => out.extend((v as f32).to_le_bytes()),
            }
        }
    }
}

/// The Open SciVis suffix `_WxHxD_type.raw`.
pub fn raw_suffix(dims: [u32; 3], ty: VoxelType) -> String {
    format!("_{}x{}x{}_{}.raw", dims[0], dims[1], dims[2], ty.name())
}

/// The path a raw export of `dims` voxels of `ty` writes for `out`: `out`
/// itself if it ends in `.raw` and is the Open SciVis name
/// (`name_WxHxD_type.raw`, else an error naming the expected name), or
/// `out` as a stem with `_WxHxD_type.raw` appended.
pub fn raw_path(out: &Path, dims: [u32; 3], ty: VoxelType) -> Result<PathBuf> {
    let name = out
        .file_name()
        .and_then(|n| n.to_str())
        .filter(|n| !n.is_empty())
        .ok_or_else(|| Error::invalid("output", out.display().to_string(), "has no file name"))?;
    let suffix = raw_suffix(dims, ty);
    if !name.to_ascii_lowercase().ends_with(".raw") {
        return Ok(out.with_file_name(format!("{name}{suffix}")));
    }
    if name.len() > suffix.len() && name.ends_with(&suffix) {
        return Ok(out.to_path_buf());
    }
    // Suggest the name with its own stem, dropping a wrong `_WxHxD_type`.
    let mut bare = &name[..name.len() - 4];
    // A doubled extension (`v.raw.raw`) is one.
    while bare.len() >= 4
        && bare.is_char_boundary(bare.len() - 4)
        && bare[bare.len() - 4..].eq_ignore_ascii_case(".raw")
    {
        bare = &bare[..bare.len() - 4];
    }
    let parts: Vec<&str> = bare.rsplitn(3, '_').collect();
    let stem = match parts.as_slice() {
        [ty, dims, stem] if VoxelType::from_name(ty).is_some() && super::parse_dims(dims).is_ok() => *stem,
        _ => bare,
    };
    let stem = if stem.is_empty() { "volume" } else { stem };
    Err(Error::invalid(
        "output name",
        name,
        format!(
            "must be {stem}{suffix} (the Open SciVis name_WxHxD_type.raw of {}x{}x{} {ty})",
            dims[0], dims[1], dims[2]
        ),
    ))
}

/// Fails when `out` cannot name a raw export: an existing folder, a name
/// ending in a path separator, or a folder that does not exist.
pub fn check_raw_out(out: &Path) -> Result<()> {
    let ends_in_separator = out
        .as_os_str()
        .to_str()
        .is_some_and(|s| s.ends_with(std::path::is_separator));
    if out.is_dir() || ends_in_separator {
        return Err(Error::invalid(
            "output",
            out.display().to_string(),
            "is a folder; give a file stem (DIR/NAME) or an Open SciVis name (DIR/NAME_WxHxD_type.raw)",
        ));
    }
    // A stem gets `_WxHxD_type.raw`; a name that asks for another format
    // would get a raw file under a misleading name.
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if let Some(ext) = OTHER_FORMATS.iter().find(|e| name.ends_with(*e)) {
        return Err(Error::invalid(
            "output",
            out.display().to_string(),
            format!("export writes raw files, not {ext}; give a file stem (DIR/NAME) or an Open SciVis name (DIR/NAME_WxHxD_type.raw)"),
        ));
    }
    check_parent(out)
}

/// Output names export refuses: formats it does not write.
const OTHER_FORMATS: [&str; 7] = [".nrrd", ".nhdr", ".nii", ".nii.gz", ".gz", ".exr", ".png"];

/// What [`write_raw`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct RawExport {
    pub path: PathBuf,
    pub ty: VoxelType,
    pub bytes: u64,
    /// How far an exported value may lie from the source's: 0 where every
    /// value is the source's own; for values kept normalised in f32
    /// (float32, float64, a fractionally scaled integer file), half an ulp
    /// of [0, 1] in source units, (max - min) x 2^-24: a value much nearer
    /// 0 than the range is wide keeps none of its digits.
    pub within: f64,
}

/// Voxels encoded per write (bounded memory for any volume size).
const CHUNK: usize = 1 << 20;

/// Writes `volume` as a raw file for `out` (see [`raw_path`]) in `ty` (see
/// [`SourceValues::export_type`]), atomically: on any error nothing is left
/// on disk. Spacing is not stored in a raw file.
pub fn write_raw(volume: &Volume, out: &Path, ty: Option<VoxelType>) -> Result<RawExport> {
    check_raw_out(out)?;
    // A raw file holds one channel: writing the first alone would lose data.
    if volume.channel_count() > 1 {
        return Err(Error::invalid(
            "volume",
            volume.name.clone(),
            format!(
                "has {} channels and a raw file holds one: export each channel's source alone",
                volume.channel_count()
            ),
        ));
    }
    let n = check_dims(volume.dims, &volume.name)?;
    if volume.data.len() as u64 != n {
        return Err(Error::invalid(
            "voxel data",
            volume.name.clone(),
            format!("{} values for {} voxels", volume.data.len(), n),
        ));
    }
    let values = SourceValues::new(volume);
    let ty = values.export_type(ty)?;
    let bytes = n
        .checked_mul(ty.bytes() as u64)
        .ok_or_else(|| Error::invalid("dimensions", volume.name.clone(), "too many bytes to address"))?;
    let path = raw_path(out, volume.dims, ty)?;
    if path.is_dir() {
        return Err(Error::invalid("output", path.display().to_string(), "is a folder"));
    }
    write_atomically(&path, |tmp| {
        let io = |e| Error::io(&path, e);
        let mut file = std::fs::File::create(tmp).map_err(io)?;
        let mut buf = Vec::with_capacity(CHUNK.min(values.len()) * ty.bytes());
        for start in (0..values.len()).step_by(CHUNK) {
            buf.clear();
            values.encode(start..(start + CHUNK).min(values.len()), ty, &mut buf);
            file.write_all(&buf).map_err(io)?;
        }
        file.sync_all().map_err(io)
    })?;
    let within = match values.integer {
        true => 0.0,
        false => values.tolerance,
    };
    Ok(RawExport {
        path,
        ty,
        bytes,
        within,
    })
}
