//! Volume specs: a file path, or a procedural `NAME:SIZE[:PARAM]`, or
//! several of them joined with `+` as the channels of one volume.

use super::procedural::Generator;
use super::raw::RawLayout;
use super::VoxelType;
use super::{StreamTo, Volume};
use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use std::path::{Path, PathBuf};

/// Options that apply to file loaders.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Layout of a raw file whose name does not encode it (`--dims`, `--type`).
    pub raw: Option<RawLayout>,
    /// Source values that map to a transfer function's 0 and 1, in every
    /// step and channel (`--value-range`; `StepNorm::over`); None: step
    /// 0's own range. `Series` applies it as it normalises each step;
    /// `Volume::load` does not (`StepNorm::over(..).apply` does it there).
    pub value_range: Option<[f64; 2]>,
}

/// Where a volume comes from: a file or a generator.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeSpec {
    File(PathBuf),
    Procedural {
        generator: Generator,
        dims: [u32; 3],
        param: Option<f64>,
    },
    /// Channels on one grid (`a.nii.gz+b.nii.gz`, `vessels:128+nbody:128`).
    Channels(Vec<VolumeSpec>),
}

impl VolumeSpec {
    pub fn parse(spec: &str, options: &LoadOptions) -> Result<Self> {
        let path = Path::new(spec);
        if spec.is_empty() {
            return Err(Error::invalid(
                "volume",
                spec,
                "is empty: name a file or a generator as NAME:SIZE",
            ));
        }
        check_raw_options(spec, options)?;
        if options.raw.is_some() && spec.contains('+') && !path.exists() {
            return Err(Error::invalid(
                "volume",
                spec,
                "is no file, and with --dims and --type a spec names one raw file, so '+' joins no channels: \
                 give each channel's layout in its file name (NAME_WxHxD_TYPE.raw) to join them",
            ));
        }
        if options.raw.is_some() || path.exists() {
            return Ok(VolumeSpec::File(path.to_path_buf()));
        }
        if spec.contains('+') {
            let parts: Vec<&str> = spec.split('+').collect();
            if parts.len() > super::MAX_CHANNELS || parts.iter().any(|p| p.is_empty()) {
                return Err(Error::invalid(
                    "volume",
                    spec,
                    format!(
                        "expected 1 to {} channels joined with '+', each a file or NAME:SIZE",
                        super::MAX_CHANNELS
                    ),
                ));
            }
            let channels = parts
                .iter()
                .map(|p| VolumeSpec::parse(p, options))
                .collect::<Result<Vec<_>>>()?;
            return Ok(VolumeSpec::Channels(channels));
        }
        let mut parts = spec.split(':');
        let name = parts.next().unwrap_or("");
        let looks_procedural = spec.contains(':') && !name.contains(['/', '\\', '.']);
        if !looks_procedural {
            return Ok(VolumeSpec::File(path.to_path_buf()));
        }
        let generator = Generator::from_name(name).ok_or_else(|| {
            Error::invalid(
                "volume",
                spec,
                format!(
                    "no such file, and '{name}' is not a generator ({})",
                    Generator::names().join(", ")
                ),
            )
        })?;
        let size = parts.next().unwrap_or("");
        let dims = if size.contains('x') {
            super::raw::parse_dims(size)?
        } else {
            let n: u32 = size.parse().map_err(|_| {
                Error::invalid(
                    "volume",
                    spec,
                    "expected NAME:SIZE[:PARAM] with SIZE an integer or WxHxD",
                )
            })?;
            [n; 3]
        };
        super::check_dims(dims, spec)?;
        let param = match parts.next() {
            None => None,
            Some(p) => Some(
                p.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| Error::invalid("volume", spec, format!("parameter '{p}' is not a number")))?,
            ),
        };
        if parts.next().is_some() {
            return Err(Error::invalid("volume", spec, "expected NAME:SIZE[:PARAM]"));
        }
        Ok(VolumeSpec::Procedural { generator, dims, param })
    }

    pub fn load(&self, options: &LoadOptions) -> Result<Volume> {
        self.load_within(options, None)
    }

    /// As `load`, checking sizes against `device` before allocating (see `Volume::load_within`).
    /// As `load_within`, streamed into bricks where the source comes in
    /// slabs (`Series::load_bricks`); other sources load whole.
    pub fn load_bricks(&self, options: &LoadOptions, bricks: &StreamTo) -> Result<Volume> {
        match self {
            VolumeSpec::Procedural { generator, dims, param } => generator.generate_bricks(*dims, *param, 0, bricks),
            VolumeSpec::File(path) if is_raw(path, options) => {
                if !path.exists() {
                    return Err(not_found(path));
                }
                super::raw::load_bricks(path, options.raw, bricks)
            }
            VolumeSpec::File(path) if is_nrrd(path) && path.exists() => super::nrrd::load_step_bricks(path, 0, bricks),
            #[cfg(feature = "loaders")]
            VolumeSpec::File(path) if is_nifti(path) && path.exists() => {
                super::nifti::load_step_bricks(path, 0, bricks)
            }
            _ => self.load_within(options, None),
        }
    }

    pub fn load_within(&self, options: &LoadOptions, device: Option<&DeviceInfo>) -> Result<Volume> {
        match self {
            VolumeSpec::Procedural { generator, dims, param } => {
                let [w, h, d] = dims;
                super::check_size(
                    *dims,
                    VoxelType::U8,
                    &format!("{generator:?}:{w}x{h}x{d}").to_lowercase(),
                    device,
                )?;
                generator.generate(*dims, *param)
            }
            VolumeSpec::File(path) => load_file(path, options, device),
            VolumeSpec::Channels(channels) => {
                let loaded = channels
                    .iter()
                    .map(|c| c.load_within(options, device))
                    .collect::<Result<Vec<_>>>()?;
                Volume::join(loaded)
            }
        }
    }
}

/// Refuses raw options (`--dims`, `--type`) for a file (or a pattern of
/// files) whose header gives the grid and type, and for a generator.
pub(super) fn check_raw_options(spec: &str, options: &LoadOptions) -> Result<()> {
    let path = Path::new(spec);
    let generator = || spec.contains(':') && Generator::from_name(spec.split(':').next().unwrap_or("")).is_some();
    let why = match () {
        _ if options.raw.is_none() => return Ok(()),
        _ if is_nrrd(path) || is_nifti(path) => "this file's header gives its grid and type",
        _ if !path.exists() && generator() => "this names a generator",
        _ => return named_layout_agrees(spec, options),
    };
    Err(Error::invalid(
        "volume",
        spec,
        format!("--dims and --type describe a raw file, and {why}"),
    ))
}

/// A raw file whose name gives its layout (`v_12x10x8_uint8.raw`) is that
/// layout: `--dims` and `--type` may repeat it, not replace it unseen.
fn named_layout_agrees(spec: &str, options: &LoadOptions) -> Result<()> {
    let (Some(given), Ok(named)) = (options.raw, super::raw::layout_from_name(Path::new(spec))) else {
        return Ok(());
    };
    if (given.dims, given.ty) == (named.dims, named.ty) {
        return Ok(());
    }
    let show = |l: RawLayout| format!("{}x{}x{} {}", l.dims[0], l.dims[1], l.dims[2], l.ty);
    Err(Error::invalid(
        "volume",
        spec,
        format!(
            "its name gives {}, and --dims and --type say {}: rename the file, or leave the flags out",
            show(named),
            show(given)
        ),
    ))
}

fn is_raw(path: &Path, options: &LoadOptions) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_lowercase();
    options.raw.is_some() || name.ends_with(".raw")
}

pub(super) fn is_nifti(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_lowercase();
    name.ends_with(".nii") || name.ends_with(".nii.gz")
}

pub(super) fn is_nrrd(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_lowercase();
    name.ends_with(".nrrd") || name.ends_with(".nhdr")
}

fn not_found(path: &Path) -> Error {
    Error::io(
        path,
        std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory"),
    )
}

fn load_file(path: &Path, options: &LoadOptions, device: Option<&DeviceInfo>) -> Result<Volume> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_lowercase();
    if is_raw(path, options) {
        if !path.exists() {
            return Err(not_found(path));
        }
        return super::raw::load(path, options.raw, None, device);
    }
    if is_nrrd(path) {
        return super::nrrd::load(path, device);
    }
    if name.ends_with(".nii") || name.ends_with(".nii.gz") {
        #[cfg(feature = "loaders")]
        return super::nifti::load(path, device);
        #[cfg(not(feature = "loaders"))]
        return Err(Error::format(
            path,
            "NIfTI volumes need lacuna's `loaders` cargo feature",
        ));
    }
    if !path.exists() {
        return Err(not_found(path));
    }
    Err(Error::format(
        path,
        "unknown volume format (expected .raw, .nrrd, .nhdr, .nii, .nii.gz, or NAME:SIZE for a generator)",
    ))
}
