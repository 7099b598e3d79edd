//! Benchmark configurations (TOML): the protocol, the data sets, the
//! structures with their parameters (the paper's columns) and the
//! speed-against-error sweep. `bench/quick.toml` and `bench/paper.toml` are
//! embedded in the binary, so `lacuna bench --quick` needs no files.

use crate::accel::table::params_for;
use crate::accel::{Accel, Params};
use crate::desc::{FrameDesc, LookSpec, Shading};
use crate::error::{Error, Result};
use crate::volume::{Filter, Storage};
use serde::Deserialize;
use std::path::Path;

/// The `--quick` config (`bench/quick.toml`).
pub const QUICK: &str = include_str!("../../bench/quick.toml");
/// The paper's config (`--paper`, `bench/paper.toml`).
pub const PAPER: &str = include_str!("../../bench/paper.toml");
/// auto's contract (`lacuna bench --suite auto`).
pub const AUTO: &str = include_str!("../../bench/auto.toml");

/// A bench config (TOML): the protocol, the structures and the data sets.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BenchConfig {
    /// The run's name (default: the config file's stem): the output folder
    /// `bench/out/NAME` and the records' `config`.
    #[serde(default)]
    pub name: String,
    /// Frame size [width, height] (default 512 x 512; the paper: 1024 x 1024).
    #[serde(default = "default_size", deserialize_with = "width_height")]
    pub size: [u32; 2],
    /// Views of the rotating orthographic camera (default 6; the paper: 36).
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Untimed frames (and builds) at least, per structure, before timing
    /// (default 2, never fewer): lavapipe compiles on first use. Warm-up
    /// goes on until two consecutive times agree within `stable`, up to
    /// `warmup_cap`.
    #[serde(default = "default_warmup")]
    pub warmup: u32,
    /// Most warm-up frames (and builds) per structure; hitting it is reported.
    #[serde(default = "default_warmup_cap")]
    pub warmup_cap: u32,
    /// Two consecutive warm-up times within this fraction count as stable.
    #[serde(default = "default_stable")]
    pub stable: f64,
    /// Timed builds per structure (the TF-change path), interleaved across
    /// structures; the median is reported (default 3).
    #[serde(default = "default_builds")]
    pub builds: u32,
    /// Timed rounds per view: each round renders every structure once, in
    /// order, so machine noise falls on all alike.
    #[serde(default = "default_rounds")]
    pub rounds: u32,
    /// Early ray termination threshold for the timed frames (default off, as
    /// in the paper).
    pub ert: Option<f32>,
    /// Sample step in voxels (default `render::DEFAULT_STEP`, 0.5).
    #[serde(default = "default_step")]
    pub step: f32,
    /// Sample filter of the timed frames, manual or hardware (default: the
    /// faster the device offers for each volume, `GpuVolume::default_filter`).
    pub filter: Option<String>,
    /// Camera elevation in degrees (default 20); the azimuth turns through
    /// 360 over the frames.
    #[serde(default = "default_elevation")]
    pub elevation: f64,
    /// The frames' look (mode, iso, shade, light, phong, gradient_opacity,
    /// clip, crop, jitter: `render`'s flags); a data set's own `look`
    /// replaces what it gives. Default: composite, unshaded, whole box.
    #[serde(default)]
    pub look: LookSpec,
    #[serde(rename = "dataset")]
    pub datasets: Vec<DatasetConfig>,
    #[serde(rename = "structure")]
    pub structures: Vec<StructureConfig>,
    pub error: Option<ErrorConfig>,
}

fn default_size() -> [u32; 2] {
    [512, 512]
}

/// Exactly two numbers, `form` naming them in the error (serde's arrays
/// from TOML drop extra items).
fn two<'de, D: serde::Deserializer<'de>>(d: D, form: &str) -> std::result::Result<[u32; 2], D::Error> {
    let v = Vec::<u32>::deserialize(d)?;
    <[u32; 2]>::try_from(v.as_slice()).map_err(|_| serde::de::Error::custom(format!("{form}, not {} numbers", v.len())))
}

fn width_height<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<[u32; 2], D::Error> {
    two(d, "size must be [width, height]")
}

fn first_last<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<[u32; 2]>, D::Error> {
    two(d, "time must be [FIRST, LAST]").map(Some)
}

fn default_frames() -> u32 {
    6
}

fn default_warmup() -> u32 {
    2
}

fn default_builds() -> u32 {
    3
}

fn default_step() -> f32 {
    crate::desc::DEFAULT_STEP
}

fn default_elevation() -> f64 {
    20.0
}

fn default_warmup_cap() -> u32 {
    30
}

fn default_stable() -> f64 {
    0.05
}

fn default_rounds() -> u32 {
    3
}

/// Frame times whose max/min over the rounds of one view exceed this are
/// marked unstable.
pub const UNSTABLE_SPREAD: f64 = 1.5;

/// One data set of a bench config: its volume, transfer function and look.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetConfig {
    /// A volume spec (file or NAME:SIZE[:PARAM]).
    pub volume: String,
    /// Transfer function spec, one per channel separated by `|` (default: each channel's generator's).
    pub tf: Option<String>,
    /// Skip (with a note) instead of failing when the file is missing.
    #[serde(default)]
    pub optional: bool,
    /// This data set's look, over the run's (`BenchConfig::look`).
    #[serde(default)]
    pub look: LookSpec,
    /// Early ray termination threshold for this data set's timed frames
    /// (default: the run's), so one run can time a volume with and without.
    pub ert: Option<f32>,
    /// A time series' steps `[FIRST, LAST]`: the data set is step FIRST,
    /// and each later step is timed to its first exact frame (upload,
    /// ranges, build, frame) per structure; FIRST warms up.
    #[serde(default, deserialize_with = "first_last")]
    pub time: Option<[u32; 2]>,
    /// Voxel storage on the device: dense, bricks, bricks:EDGE or auto
    /// (default auto, as `render --storage`).
    pub storage: Option<String>,
    /// `[LO, HI]`: the source values the TF's 0 and 1 stand for, in every
    /// step and channel (as `render --value-range`; default: step 0's own
    /// range).
    pub value_range: Option<[f64; 2]>,
}

impl DatasetConfig {
    /// How its volume loads: with its `value_range`, checked.
    pub fn options(&self) -> Result<crate::volume::LoadOptions> {
        if let Some(range) = self.value_range {
            crate::volume::check_value_range(range)?;
        }
        Ok(crate::volume::LoadOptions {
            value_range: self.value_range,
            ..Default::default()
        })
    }

    /// Its voxel storage (`storage`, default auto).
    pub fn storage(&self) -> Result<Storage> {
        self.storage.as_deref().map_or(Ok(Storage::Auto), Storage::parse)
    }

    /// Frames its `time` range renders per structure (0 without one).
    pub fn new_steps(&self) -> u64 {
        self.time
            .map_or(0, |[first, last]| last.saturating_sub(first) as u64 + 1)
    }

    /// The look of its frames: its own over the run's.
    pub fn look(&self, config: &BenchConfig) -> LookSpec {
        self.look.over(&config.look)
    }

    /// Its name in reports: the volume, and its look where that is not the
    /// default (`nbody:96 [mode iso; iso 0.3; shade]`), and its time range
    /// (`nbody:96 [time 1..4]`), so one volume can be
    /// measured in several looks.
    pub fn label(&self, config: &BenchConfig) -> Result<String> {
        let desc = self.look(config).apply(FrameDesc::builder(1, 1))?.build()?;
        let default_light = Shading::default().describe();
        let look: Vec<String> = desc
            .describe_look()
            .into_iter()
            .map(|(k, v)| match k {
                "shade" if v == default_light => k.to_string(),
                _ => format!("{k} {v}"),
            })
            .collect();
        let mut look = look;
        if let Some(e) = self.ert {
            look.push(format!("ert {e}"));
        }
        // The frames are step FIRST's, and the steps' records these steps'.
        if let Some([first, last]) = self.time {
            look.push(format!("time {first}..{last}"));
        }
        if let Some([lo, hi]) = self.value_range {
            look.push(format!("range {lo}..{hi}"));
        }
        let storage = self.storage()?;
        if storage != Storage::Auto {
            look.push(format!("storage {storage}"));
        }
        Ok(match look.is_empty() {
            true => self.volume.clone(),
            false => format!("{} [{}]", self.volume, look.join("; ")),
        })
    }
}

/// A `[[structure]]`: a label, a structure, and values of its parameters
/// (`cell = 4`, `kd = "deep"`, `max_leaf = 32`, `collapse = true`, ...: any
/// structure's parameter, `-` written `_`; those the structure does not have
/// are ignored, unknown names are an error).
#[derive(Clone, Debug, Deserialize)]
pub struct StructureConfig {
    pub label: String,
    pub accel: String,
    #[serde(flatten)]
    pub params: std::collections::BTreeMap<String, toml::Value>,
}

/// A speed-against-error sweep: steps and ERT thresholds against a fine
/// reference.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorConfig {
    /// Data sets (by label: the volume spec, with its look in brackets
    /// when it has one) to sweep; default: all.
    pub datasets: Option<Vec<String>>,
    pub steps: Vec<f32>,
    /// Early-termination thresholds; 0 means off.
    pub ert: Vec<f32>,
    /// Sample filters (manual, hardware); default: the timed frames'. A
    /// filter the volume's format cannot use is skipped with a note.
    #[serde(default)]
    pub filters: Vec<String>,
    pub reference_step: f32,
    /// Views per point (orbit as above).
    pub frames: u32,
    /// Structure the sweep is timed with (images are identical for all).
    pub accel: String,
    /// Jitter settings swept (default: the data set's): `[false, true]`
    /// shows what jitter does to the error against the fine reference.
    #[serde(default)]
    pub jitter: Vec<bool>,
}

/// A structure resolved from its config.
#[derive(Clone, Debug)]
pub struct StructureSpec {
    pub label: String,
    pub accel: Accel,
    pub params: Params,
}

impl StructureConfig {
    pub fn resolve(&self) -> Result<StructureSpec> {
        let accel: Accel = self.accel.parse()?;
        let mut given = Vec::new();
        for (key, value) in &self.params {
            let name = key.replace('_', "-");
            let text = match value {
                toml::Value::String(s) => s.clone(),
                toml::Value::Integer(n) => n.to_string(),
                toml::Value::Boolean(b) => b.to_string(),
                other => {
                    return Err(Error::invalid(
                        "structure parameter",
                        format!("{key} = {other}"),
                        "expected a string, an integer or a boolean",
                    ))
                }
            };
            given.push((name, text));
        }
        let given: Vec<(&str, &str)> = given.iter().map(|(n, t)| (n.as_str(), t.as_str())).collect();
        Ok(StructureSpec {
            label: self.label.clone(),
            params: params_for(accel, &given)?,
            accel,
        })
    }
}

impl ErrorConfig {
    /// The filters swept: `filters`, or the timed frames' `timed`.
    pub fn filters(&self, timed: Filter) -> Result<Vec<Filter>> {
        if self.filters.is_empty() {
            return Ok(vec![timed]);
        }
        self.filters.iter().map(|f| Filter::parse(f)).collect()
    }
}

impl BenchConfig {
    /// The timed frames' filter, when the config names one.
    pub fn timed_filter(&self) -> Result<Option<Filter>> {
        self.filter.as_deref().map(Filter::parse).transpose()
    }

    /// A config from TOML `text` read from `origin` (a path, or a built-in
    /// config's name), whose stem names the run when the config does not.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let c = Self::parse_unchecked(text, origin)?;
        c.validate(origin)?;
        Ok(c)
    }

    /// As `parse`, without the protocol's checks (`validate`): the command
    /// line overrides fields first, then validates.
    pub fn parse_unchecked(text: &str, origin: &str) -> Result<Self> {
        let mut c: BenchConfig = toml::from_str(text).map_err(|e| {
            // The place as a line and column, not the parser's drawing of it.
            let at = e.span().map_or(String::new(), |span| {
                let before = text.get(..span.start).unwrap_or(text);
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
                format!(" at line {line}, column {column}")
            });
            // The parser's message may run over lines ("invalid array\nexpected `]`").
            let message = e.message().trim().replace('\n', ": ");
            Error::format(origin, format!("invalid bench config{at}: {message}"))
        })?;
        if c.name.is_empty() {
            let stem = Path::new(origin.split(' ').next().unwrap_or(origin)).file_stem();
            c.name = stem.map_or("bench".into(), |s| s.to_string_lossy().into_owned());
        }
        // The name is a folder under the output root, never a path out of it.
        if matches!(c.name.as_str(), "." | "..") || c.name.contains(['/', '\\']) || c.name.contains(char::is_control) {
            return Err(Error::format(
                origin,
                format!(
                    "name '{}' must be a plain folder name (no '/', '\\' or '..')",
                    c.name.escape_debug()
                ),
            ));
        }
        Ok(c)
    }

    pub fn load(path: &Path) -> Result<Self> {
        let c = Self::load_unchecked(path)?;
        c.validate(&path.display().to_string())?;
        Ok(c)
    }

    /// As `load`, without `validate` (see `parse_unchecked`).
    pub fn load_unchecked(path: &Path) -> Result<Self> {
        let text = crate::limits::read_input_text(path, "bench config", crate::limits::MAX_TEXT_INPUT)?;
        Self::parse_unchecked(&text, &path.display().to_string())
    }

    /// With `--frames-out`: an error, before anything runs, where two
    /// runs' frames would get one file (labels that differ only in
    /// characters a file name drops: `my grid` and `my_grid`).
    pub fn check_frame_files(&self, origin: &str) -> Result<()> {
        let mut structures: Vec<&str> = self.structures.iter().map(|s| s.label.as_str()).collect();
        if !self
            .structures
            .iter()
            .any(|s| s.resolve().is_ok_and(|r| r.accel == Accel::naive()))
        {
            structures.push("naive");
        }
        let mut files = std::collections::HashMap::new();
        for d in &self.datasets {
            let dataset = d.label(self)?;
            for s in &structures {
                let file = super::files::frame_file(&dataset, s);
                let run = format!("{dataset} / {s}");
                if let Some(other) = files.insert(file.clone(), run.clone()) {
                    return Err(Error::format(
                        origin,
                        format!("--frames-out would write '{other}' and '{run}' to one file, {file}: give one structure or data set another label"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks the protocol; run again after command-line overrides.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let bad = |m: &str| Err(Error::format(origin, m.to_string()));
        let side = crate::limits::MAX_FRAME_SIDE;
        if self.size.iter().any(|&s| s == 0 || s > side) {
            return bad(&format!(
                "width and height must be in 1..={side} pixels, not {}x{}",
                self.size[0], self.size[1]
            ));
        }
        for (what, n) in [("frames", self.frames), ("builds", self.builds)] {
            if n == 0 {
                return bad(&format!("frames and builds must be at least 1: {what} is 0"));
            }
        }
        let most = crate::limits::MAX_RUNS;
        for (what, n) in [
            ("frames", self.frames),
            ("builds", self.builds),
            ("rounds", self.rounds),
            ("warmup", self.warmup),
            ("warmup_cap", self.warmup_cap),
        ] {
            if n > most {
                return bad(&format!("{what} {n} must be at most {most}"));
            }
        }
        // What a run keeps per structure: the phase timings of each build
        // and a time per frame and round (a few hundred bytes each at most).
        let per_structure = self.builds as u64 + self.frames as u64 * self.rounds as u64;
        crate::limits::check_host(
            format_args!(
                "{origin}: {} builds and {} frames x {} rounds for {} structures",
                self.builds,
                self.frames,
                self.rounds,
                self.structures.len()
            ),
            per_structure.saturating_mul(self.structures.len() as u64),
            256,
        )?;
        if self.rounds < 2 {
            return bad("rounds must be at least 2 (the noise spread needs two rounds of each view)");
        }
        if self.warmup_cap < self.warmup.max(2) {
            return bad("warmup_cap must be at least warmup and at least 2");
        }
        if !(self.stable.is_finite() && self.stable > 0.0 && self.stable < 1.0) {
            return bad("stable must be a fraction in (0, 1), like 0.05");
        }
        if self.ert.is_some_and(|t| !(t > 0.0 && t <= 1.0)) {
            return bad(&format!("ert must be in (0, 1], not {}", self.ert.unwrap_or_default()));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return bad("step must be > 0");
        }
        if !(-90.0..=90.0).contains(&self.elevation) {
            return bad(&format!(
                "elevation must be in [-90, 90] degrees, not {}",
                self.elevation
            ));
        }
        self.timed_filter().map_err(|e| Error::format(origin, e.to_string()))?;
        if self.datasets.is_empty() || self.structures.is_empty() {
            return bad("needs at least one [[dataset]] and one [[structure]]");
        }
        // Results are keyed by data set label and structure: a label twice
        // would write a results.json that --compare refuses.
        let mut datasets = std::collections::HashSet::new();
        for d in &self.datasets {
            let label = d
                .label(self)
                .map_err(|e| Error::format(origin, format!("data set '{}': {e}", d.volume)))?;
            // An optional data set's transfer function file may be missing
            // with its volume: checked where the volume loads.
            if let Some(spec) = d.tf.as_ref().filter(|_| !d.optional) {
                crate::tf::TransferFunction::parse_channels(spec)
                    .map_err(|e| Error::format(origin, format!("data set '{}': {e}", d.volume)))?;
            }
            if !datasets.insert(label.clone()) {
                return bad(&format!(
                    "data set '{label}' appears twice (data sets are told apart by volume, look, ert and storage, not by transfer function alone)"
                ));
            }
        }
        let mut labels = std::collections::HashSet::new();
        for s in &self.structures {
            let resolved = s
                .resolve()
                .map_err(|e| Error::format(origin, format!("structure '{}': {e}", s.label)))?;
            // The run adds naive under that label where a config has none.
            if s.label == "naive" && resolved.accel != Accel::naive() {
                return bad(&format!(
                    "structure label 'naive' is the naive march's (every run times it), not {}'s: give it another label",
                    s.accel
                ));
            }
            if !labels.insert(&s.label) {
                return bad(&format!("structure label '{}' appears twice", s.label));
            }
        }
        if let Some(e) = &self.error {
            if let Some(s) = e.steps.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
                return bad(&format!("error sweep step {s} must be > 0"));
            }
            if !(e.reference_step.is_finite() && e.reference_step > 0.0) {
                return bad(&format!("error sweep reference_step {} must be > 0", e.reference_step));
            }
            if e.frames == 0 || e.frames > most {
                return bad(&format!("error sweep frames must be in 1..={most}, not {}", e.frames));
            }
            if let Some(wanted) = &e.datasets {
                let labels = self
                    .datasets
                    .iter()
                    .map(|d| d.label(self))
                    .collect::<Result<Vec<_>>>()?;
                if let Some(w) = wanted.iter().find(|w| !labels.contains(w)) {
                    return bad(&format!(
                        "error sweep data set '{w}' is none of the [[dataset]] labels: {}",
                        labels.join(", ")
                    ));
                }
            }
            if e.ert.iter().any(|t| !(0.0..=1.0).contains(t)) {
                return bad("error sweep ert thresholds must be in [0, 1] (0 = off)");
            }
            e.filters(Filter::Manual)
                .map_err(|err| Error::format(origin, err.to_string()))?;
            e.accel
                .parse::<Accel>()
                .map_err(|err| Error::format(origin, err.to_string()))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_bench_config_loads_and_names_volumes_that_parse() {
        use crate::volume::{LoadOptions, VolumeSpec};
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("bench");
        let mut seen = 0;
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            if path.extension().is_some_and(|e| e == "toml") {
                // Loading validates the protocol and resolves every structure.
                let config = BenchConfig::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                for d in &config.datasets {
                    VolumeSpec::parse(&d.volume, &LoadOptions::default())
                        .unwrap_or_else(|e| panic!("{}: {}: {e}", path.display(), d.volume));
                }
                seen += 1;
            }
        }
        // quick, paper, auto, looks, channels, series, gpu-sparse at least.
        assert!(seen >= 7, "only {seen} configs in {}", dir.display());
    }
}
