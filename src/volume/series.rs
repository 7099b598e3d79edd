//! Time series: a volume spec that names several steps on one grid.
//!
//! - a printf pattern of files (`run_%04d_64x64x64_float32.raw`): the steps
//!   are the numbers that exist, which must run without a gap; step K is
//!   the file numbered first + K;
//! - a NIfTI file whose 4th dimension is time, or a NRRD whose last axis is;
//! - a generator, which animates over `procedural::STEPS` steps;
//! - anything else is one step.
//!
//! Every step is normalised as step 0 is (`Volume::norm`), so a transfer
//! function means the same values in every step; values beyond step 0's
//! range clamp, as the sampler clamps. Every step must have step 0's
//! dimensions and voxel type.

use super::decode::span_ratio;
use super::pattern::{one_step, Pattern};
use super::procedural::{self, Generator};
#[cfg(feature = "loaders")]
use super::spec::is_nifti;
use super::spec::{is_nrrd, LoadOptions, VolumeSpec};
use super::{PoolLimits, Storage, StreamProgress, StreamTo, Volume, VoxelType, POOL_BRICK};
use crate::error::{number, Error, Result};
use crate::gpu::DeviceInfo;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A volume spec's steps, loaded one at a time.
pub struct Series {
    spec: String,
    source: Source,
    options: LoadOptions,
    /// Step 0's grid, type and normalisation, once a step has been loaded.
    first: OnceLock<StepNorm>,
}

/// How every step of a series is normalised: as its step 0 (`of`), so a
/// transfer function means the same values in every step. A host that
/// makes its own steps (a running simulation) normalises each with
/// `apply`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepNorm {
    dims: [u32; 3],
    spacing: [f32; 3],
    ty: VoxelType,
    channels: usize,
    /// Step 0's normalisation of integer texels (stored as they are).
    norm: [f32; 2],
    /// Step 0's range in source units: float texels are stored normalised
    /// to their own step's range, and are mapped back onto this one.
    range: [f64; 2],
    /// How step 0's integer texels map to source units (`source_affine`),
    /// which every integer step must share: `norm` is applied to them as
    /// they are.
    affine: Option<[f64; 2]>,
    /// Step 0 held one value throughout: `range` and `norm` were chosen,
    /// not measured (`of`).
    constant: bool,
    /// `range` was given (`over`), not step 0's: an integer step's norm
    /// comes from its own scaling, so a step 0 of one value (no scaling
    /// to tell) maps later steps right.
    given: bool,
}

/// `[k, c]` with source value = k x stored + c for a volume of integer
/// texels (a scaled NIfTI's slope and intercept, int8's shift); None for
/// float texels or a volume of one stored value (no slope to tell).
fn source_affine(v: &Volume) -> Option<[f64; 2]> {
    if v.data.texel_bytes() == 4 {
        return None;
    }
    let (smin, smax) = v.data.stored_range();
    let [lo, hi] = v.value_range;
    (smax > smin).then(|| {
        let k = (hi - lo) / (smax - smin);
        [k, lo - smin * k]
    })
}

enum Source {
    /// One step.
    Still(VolumeSpec),
    Generator {
        generator: Generator,
        dims: [u32; 3],
        param: Option<f64>,
    },
    /// The files of a pattern, step K at index K.
    Files(Vec<PathBuf>),
    #[cfg(feature = "loaders")]
    Nifti {
        path: PathBuf,
        steps: u32,
    },
    Nrrd {
        path: PathBuf,
        steps: u32,
    },
    /// Channels joined with `+`, each a series of its own (normalised as
    /// its own step 0); a one-step channel stands in every step.
    Channels(Vec<Series>),
}

impl Series {
    /// The steps `spec` names (see the module's doc); files are listed and
    /// headers read, no voxels.
    pub fn open(spec: &str, options: &LoadOptions) -> Result<Series> {
        let source = if spec.contains('+') && options.raw.is_none() && !Path::new(spec).exists() {
            // Each channel's spec, checked as a volume spec first.
            VolumeSpec::parse(spec, options)?;
            let channels = spec
                .split('+')
                .map(|part| Series::open(part, options))
                .collect::<Result<Vec<_>>>()?;
            let mut steps = channels.iter().map(|c| c.steps()).filter(|&n| n > 1);
            if let Some(n) = steps.next() {
                if let Some(m) = steps.find(|&m| m != n) {
                    return Err(Error::invalid(
                        "volume",
                        spec,
                        format!("its channels have {n} and {m} time steps: every channel with steps must have as many"),
                    ));
                }
            }
            Source::Channels(channels)
        } else if let Some(pattern) = Pattern::parse(spec) {
            super::spec::check_raw_options(spec, options)?;
            let files = pattern.files()?;
            one_step(&files[0])?;
            Source::Files(files)
        } else {
            match VolumeSpec::parse(spec, options)? {
                VolumeSpec::Procedural { generator, dims, param } => Source::Generator { generator, dims, param },
                VolumeSpec::File(path) if is_nrrd(&path) && path.exists() => {
                    let steps = super::nrrd::steps(&path)?;
                    Source::Nrrd { path, steps }
                }
                #[cfg(feature = "loaders")]
                VolumeSpec::File(path) if is_nifti(&path) && path.exists() => {
                    let steps = super::nifti::steps(&path)?;
                    Source::Nifti { path, steps }
                }
                still => Source::Still(still),
            }
        };
        Ok(Series {
            spec: spec.to_string(),
            source,
            options: options.clone(),
            first: OnceLock::new(),
        })
    }

    /// A note for a series whose step 0, once loaded, held one value
    /// throughout: every step is normalised as step 0, over a range that
    /// value could not give (`StepNorm::of`). None otherwise.
    pub fn norm_note(&self) -> Option<String> {
        if let Source::Channels(parts) = &self.source {
            return parts.iter().find_map(Series::norm_note);
        }
        let note = self.first.get()?.constant_note()?;
        (self.steps() > 1).then(|| format!("{}: {note}", self.spec))
    }

    /// How many steps it has (at least 1).
    pub fn steps(&self) -> u32 {
        match &self.source {
            Source::Still(_) => 1,
            Source::Generator { .. } => procedural::STEPS,
            Source::Files(files) => files.len() as u32,
            #[cfg(feature = "loaders")]
            Source::Nifti { steps, .. } => *steps,
            Source::Channels(channels) => channels.iter().map(|c| c.steps()).max().unwrap_or(1),
            Source::Nrrd { steps, .. } => *steps,
        }
    }

    /// Its channels where the spec or a header tells them, no voxel read:
    /// generators and raw files have one, a NIfTI or NRRD what its header
    /// says, a `+` join the sum of its parts.
    pub fn channels_known(&self) -> Option<usize> {
        match &self.source {
            Source::Channels(parts) => parts.iter().map(Series::channels_known).sum(),
            Source::Generator { .. } | Source::Still(VolumeSpec::Procedural { .. }) => Some(1),
            #[cfg(feature = "loaders")]
            Source::Nifti { path, .. } => super::nifti::channels(path).ok().map(|c| c as usize),
            Source::Nrrd { path, .. } => super::nrrd::channels(path).ok().map(|c| c as usize),
            Source::Still(VolumeSpec::File(path)) => self.raw_layout(path).map(|_| 1),
            Source::Files(files) => self.raw_layout(&files[0]).map(|_| 1),
            _ => None,
        }
    }

    /// An error (the file's I/O error) where a file the spec names is
    /// missing: found before a long run reaches the volume.
    pub fn check_files(&self) -> Result<()> {
        let exists = |path: &Path| match std::fs::metadata(path) {
            Ok(_) => Ok(()),
            Err(e) => Err(Error::io(path, e)),
        };
        match &self.source {
            Source::Channels(parts) => parts.iter().try_for_each(Series::check_files),
            Source::Still(VolumeSpec::File(path)) => exists(path),
            Source::Files(files) => files.iter().try_for_each(|f| exists(f)),
            _ => Ok(()),
        }
    }

    /// What step `k` is, for messages: the file of a pattern, else the spec
    /// and the step.
    pub fn step_name(&self, k: u32) -> String {
        match &self.source {
            Source::Files(files) => files
                .get(k as usize)
                .map_or(self.spec.clone(), |f| f.display().to_string()),
            _ if self.steps() == 1 => self.spec.clone(),
            _ => format!("{} step {k}", self.spec),
        }
    }

    /// An error unless step `k` exists.
    pub fn check_step(&self, k: u32) -> Result<()> {
        let n = self.steps();
        if k >= n {
            let why = match n {
                1 => format!("{} is one volume, not a time series (step 0 only)", self.spec),
                _ => format!("{} has {n} steps, 0 to {}", self.spec, n - 1),
            };
            return Err(Error::invalid("time", k.to_string(), why));
        }
        Ok(())
    }

    /// The grid and voxel type of a source that comes in slabs (a
    /// generator, raw files, one-channel NRRD and NIfTI files), known
    /// before any voxel is read; None for the others.
    pub fn streamed_layout(&self) -> Option<([u32; 3], VoxelType)> {
        let raw = |path: &Path| self.raw_layout(path);
        match &self.source {
            Source::Generator { dims, .. } | Source::Still(VolumeSpec::Procedural { dims, .. }) => {
                Some((*dims, VoxelType::U8))
            }
            Source::Still(VolumeSpec::File(path)) => raw(path),
            Source::Files(files) if is_nrrd(&files[0]) => super::nrrd::streamed_layout(&files[0]),
            #[cfg(feature = "loaders")]
            Source::Files(files) if is_nifti(&files[0]) => super::nifti::streamed_layout(&files[0]),
            Source::Files(files) => raw(&files[0]),
            Source::Nrrd { path, .. } => super::nrrd::streamed_layout(path),
            #[cfg(feature = "loaders")]
            Source::Nifti { path, .. } => super::nifti::streamed_layout(path),
            _ => None,
        }
    }

    /// A raw file's grid and type: from the options, or its name.
    fn raw_layout(&self, path: &Path) -> Option<([u32; 3], VoxelType)> {
        let name = path.file_name()?.to_str()?.to_lowercase();
        let layout = match self.options.raw {
            Some(l) => l,
            None if name.ends_with(".raw") => super::raw::layout_from_name(path).ok()?,
            None => return None,
        };
        Some((layout.dims, layout.ty))
    }

    /// Step `k` for `storage` on the device `info` describes: dense, checked
    /// against the device before it is read or made; streamed into bricks
    /// (`load_bricks`) for bricks, and for auto where the source comes in
    /// slabs and its dense image would not fit; else whole. `progress`
    /// hears of a stream's brick rows.
    pub fn load_stored(
        &self,
        k: u32,
        storage: Storage,
        info: &DeviceInfo,
        progress: Option<StreamProgress>,
    ) -> Result<Volume> {
        let to = |edge| {
            let to = StreamTo::new(edge, PoolLimits::of(info));
            match &progress {
                Some(f) => to.progress(f.clone()),
                None => to,
            }
        };
        match storage {
            Storage::Dense => self.load(k, Some(info)),
            Storage::Bricks { edge } => self.load_bricks(k, &to(edge)),
            Storage::Auto => {
                let too_big = self
                    .streamed_layout()
                    .is_some_and(|(dims, ty)| crate::gpu::check_image3d(info, dims, super::stored_bytes(ty)).is_err());
                match too_big {
                    true => self.load_bricks(k, &to(POOL_BRICK)),
                    false => self.load(k, None),
                }
            }
        }
    }

    /// Step `k`, its size checked against `device` before it is read or
    /// made, normalised as step 0.
    pub fn load(&self, k: u32, device: Option<&DeviceInfo>) -> Result<Volume> {
        self.load_as(k, device, None)
    }

    /// As `load`, streamed into bricks (`PoolStream`) where the source
    /// comes in slabs (`streamed_layout`): `bricks` is the brick edge, the
    /// pool's limits, the bricks to keep and how ranks agree (`StreamTo`).
    /// Other sources load whole, unchecked against the device (their
    /// upload plans the pool).
    pub fn load_bricks(&self, k: u32, bricks: &StreamTo) -> Result<Volume> {
        self.load_as(k, None, Some(bricks))
    }

    fn load_as(&self, k: u32, device: Option<&DeviceInfo>, bricks: Option<&StreamTo>) -> Result<Volume> {
        self.check_step(k)?;
        if let Source::Channels(channels) = &self.source {
            let loaded = channels
                .iter()
                .map(|c| c.load(k.min(c.steps() - 1), device))
                .collect::<Result<Vec<_>>>()?;
            return Volume::join(loaded);
        }
        let mut volume = self.load_raw(k, device, bricks)?;
        // Step 0's range, or the one the options give.
        let norm_of = |step0: &Volume| match self.options.value_range {
            Some(range) => StepNorm::over(range, step0),
            None => Ok(StepNorm::of(step0)),
        };
        let first = match self.first.get() {
            Some(first) => *first,
            None if k == 0 => {
                let norm = norm_of(&volume)?;
                *self.first.get_or_init(|| norm)
            }
            None => {
                let norm = norm_of(&self.load_raw(0, device, bricks)?)?;
                *self.first.get_or_init(|| norm)
            }
        };
        first.apply(&mut volume, &self.step_name(k))?;
        Ok(volume)
    }

    fn load_raw(&self, k: u32, device: Option<&DeviceInfo>, bricks: Option<&StreamTo>) -> Result<Volume> {
        match (&self.source, bricks) {
            (Source::Still(spec), Some(b)) => spec.load_bricks(&self.options, b),
            (Source::Files(files), Some(b)) => {
                let file = one_step(&files[k as usize])?;
                VolumeSpec::File(file.to_path_buf()).load_bricks(&self.options, b)
            }
            (Source::Generator { generator, dims, param }, Some(b)) => generator.generate_bricks(*dims, *param, k, b),
            (Source::Nrrd { path, .. }, Some(b)) => super::nrrd::load_step_bricks(path, k, b),
            #[cfg(feature = "loaders")]
            (Source::Nifti { path, .. }, Some(b)) => super::nifti::load_step_bricks(path, k, b),
            _ => self.load_dense(k, device),
        }
    }

    fn load_dense(&self, k: u32, device: Option<&DeviceInfo>) -> Result<Volume> {
        match &self.source {
            Source::Still(spec) => spec.load_within(&self.options, device),
            Source::Generator { generator, dims, param } => {
                let [w, h, d] = dims;
                let what = format!("{}:{w}x{h}x{d}", generator.name());
                super::check_size(*dims, VoxelType::U8, &what, device)?;
                generator.generate_at(*dims, *param, k)
            }
            Source::Files(files) => {
                let file = one_step(&files[k as usize])?;
                VolumeSpec::File(file.to_path_buf()).load_within(&self.options, device)
            }
            #[cfg(feature = "loaders")]
            Source::Nifti { path, .. } => super::nifti::load_step(path, k, device),
            Source::Nrrd { path, .. } => super::nrrd::load_step(path, k, device),
            Source::Channels(_) => unreachable!("Series::load joins channels' steps"),
        }
    }
}

/// An error unless `[lo, hi]` can be a value range (`StepNorm::over`):
/// two finite values, the first below the second.
pub fn check_value_range([lo, hi]: [f64; 2]) -> Result<()> {
    match lo.is_finite() && hi.is_finite() && lo < hi {
        true => Ok(()),
        false => Err(Error::invalid(
            "value range",
            format!("{}:{}", number(lo), number(hi)),
            "must be two finite values, the first below the second",
        )),
    }
}

impl StepNorm {
    /// Step 0's grid, type and range; a step 0 with one value throughout
    /// (nothing to normalise by) gives the full texel range, or one unit
    /// above its value for floats, so later steps still map.
    pub fn of(v: &Volume) -> StepNorm {
        let norm = match v.norm[1] > 0.0 {
            true => v.norm,
            false => [v.norm[0].min(0.0), 1.0],
        };
        let [lo, hi] = v.value_range;
        StepNorm {
            dims: v.dims,
            spacing: v.spacing,
            ty: v.source_type,
            channels: v.channel_count(),
            norm,
            // One unit above, or as far above as |lo| where a unit is
            // lost to rounding (|lo| past 2^53).
            range: [lo, if hi > lo { hi } else { lo + lo.abs().max(1.0) }],
            affine: source_affine(v),
            constant: hi <= lo,
            given: false,
        }
    }

    /// Every step normalised over `[lo, hi]` in source units (a host's or
    /// `--value-range`'s choice), the grid, type and scaling taken from
    /// `v` (step 0): a value maps to `(value - lo) / (hi - lo)`, as a TF
    /// sees it, whatever range each step's own values span.
    pub fn over([lo, hi]: [f64; 2], v: &Volume) -> Result<StepNorm> {
        check_value_range([lo, hi])?;
        if v.channel_count() > 1 {
            return Err(Error::invalid(
                "value range",
                v.name.clone(),
                "applies to one channel: join one-channel volumes with + to give each the range",
            ));
        }
        let mut norm = StepNorm::of(v);
        norm.range = [lo, hi];
        norm.constant = false;
        norm.given = true;
        if v.data.texel_bytes() != 4 {
            norm.norm = norm.integer_norm(v);
            if !norm.norm.iter().all(|n| n.is_finite()) {
                return Err(Error::invalid(
                    "value range",
                    format!("{}:{}", number(lo), number(hi)),
                    format!("is too narrow or too wide for {}'s values in f32", v.name),
                ));
            }
        }
        Ok(norm)
    }

    /// An integer step's norm over the given `range`: its texels are read
    /// as stored / full (UNORM) and source = k x stored + c, so a value's
    /// place in [lo, hi] is (texel - (lo - c) / (k full)) x k full / (hi - lo).
    /// A step of one stored value has no k to tell: a unit per stored
    /// unit, through its value (any k maps one value exactly).
    fn integer_norm(&self, step: &Volume) -> [f32; 2] {
        let [lo, hi] = self.range;
        let full = step.data.unorm_scale();
        let [k, c] = source_affine(step).unwrap_or_else(|| {
            let (smin, _) = step.data.stored_range();
            [1.0, step.value_range[0] - smin]
        });
        [((lo - c) / (k * full)) as f32, (k * full / (hi - lo)) as f32]
    }

    /// What a step 0 of one value throughout means for the steps after it
    /// (`of` chose the range), None for one with a range.
    fn constant_note(&self) -> Option<String> {
        let [lo, hi] = self.range;
        let over = match self.ty {
            VoxelType::U8 | VoxelType::U16 | VoxelType::I8 | VoxelType::I16 => {
                format!("its type's full {} range", self.ty)
            }
            _ => format!("{} .. {}", number(lo), number(hi)),
        };
        self.constant.then(|| {
            format!(
                "step 0 holds one value ({}) throughout, so every step is normalised over {over} (a transfer function's 0 .. 1), and values past it clamp: --value-range LO:HI chooses the range",
                number(lo)
            )
        })
    }

    /// Normalises `step` as step 0 (its `norm`); an error naming
    /// `what` when its grid or voxel type is not step 0's.
    pub fn apply(&self, step: &mut Volume, what: &str) -> Result<()> {
        let channels = step.channel_count();
        if (step.dims, step.source_type, channels) != (self.dims, self.ty, self.channels) {
            let [w, h, d] = step.dims;
            let [w0, h0, d0] = self.dims;
            let (c, c0) = (channels, self.channels);
            return Err(Error::invalid(
                "time step",
                what.to_string(),
                format!(
                    "is {w}x{h}x{d} {} in {c} channel(s), where step 0 is {w0}x{h0}x{d0} {} in {c0} channel(s): every step must share one grid, type and channel count",
                    step.source_type, self.ty
                ),
            ));
        }
        // To f32's last bits: converters round a pixdim differently.
        let near = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs());
        if !(0..3).all(|i| near(step.spacing[i], self.spacing[i])) {
            let show = |[x, y, z]: [f32; 3]| format!("{x} x {y} x {z}");
            return Err(Error::invalid(
                "time step",
                what.to_string(),
                format!(
                    "has spacing {} where step 0 has {}: every step must share one grid",
                    show(step.spacing),
                    show(self.spacing)
                ),
            ));
        }
        if let (Some(a0), Some(a)) = (self.affine, source_affine(step)) {
            let near = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0);
            if !(near(a[0], a0[0]) && near(a[1], a0[1])) {
                // In the file's terms: a stored texel is the raw voxel
                // shifted, or complemented under a negative slope, so the
                // slope's magnitude is the file's and the offset between
                // two steps' values of one voxel is what differs.
                let how = match near(a[0], a0[0]) {
                    false => format!(
                        "its voxels scale by {} per raw unit (in magnitude) where step 0's scale by {} (a NIfTI's scl_slope)",
                        number(a[0]),
                        number(a0[0])
                    ),
                    true => format!(
                        "a raw voxel's value is {} off step 0's (a NIfTI's scl_inter), or its scl_slope's sign is not step 0's",
                        number(a[1] - a0[1])
                    ),
                };
                return Err(Error::invalid(
                    "time step",
                    what.to_string(),
                    format!("{how}: the steps of a series of integer voxels share one scaling (a NIfTI's scl_slope and scl_inter)"),
                ));
            }
        }
        step.norm = self.norm_for(step);
        // A subnormal step in a series spanning f64 maps onto step 0's
        // range only by an offset past f32: an error, not NaN texels.
        if !step.norm.iter().all(|n| n.is_finite()) {
            let [lo, hi] = step.value_range;
            let onto = match self.given {
                true => "the value range",
                false => "step 0's range",
            };
            return Err(Error::invalid(
                "time step",
                what.to_string(),
                format!(
                    "its values ({} .. {}) cannot be mapped onto {onto} ({} .. {}) in f32",
                    crate::error::number(lo),
                    crate::error::number(hi),
                    crate::error::number(self.range[0]),
                    crate::error::number(self.range[1])
                ),
            ));
        }
        Ok(())
    }

    /// The normalisation that maps `step`'s texels as step 0's: integer
    /// texels are absolute; float texels are `(v - lo) / (hi - lo)` of
    /// their own step's range, so `v` is recovered and mapped onto step 0's.
    fn norm_for(&self, step: &Volume) -> [f32; 2] {
        if step.data.texel_bytes() != 4 {
            return match self.given {
                true => self.integer_norm(step),
                false => self.norm,
            };
        }
        let [lo0, hi0] = self.range;
        let [lo, hi] = step.value_range;
        match hi > lo {
            true => [
                span_ratio([lo, lo0], [lo, hi]) as f32,
                span_ratio([lo, hi], [lo0, hi0]) as f32,
            ],
            // Texels all 0: the offset alone carries the value.
            false => [span_ratio([lo, lo0], [lo0, hi0]) as f32, 1.0],
        }
    }
}
