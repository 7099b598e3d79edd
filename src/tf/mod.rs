//! Transfer functions: an RGBA lookup table over normalised values [0, 1],
//! linearly interpolated between entries exactly as `glsl/common/tf.glsl`
//! does, plus the max-alpha range query that classification relies on
//! (`max_alpha`, and `visible`: whether it is above 0).
//!
//! Alpha is opacity per voxel of path length; the marcher corrects it for
//! the step size. Specs: `ramp:LO:HI[:ALPHA]`, `band:LO:HI[:ALPHA]`,
//! `spike:CENTER:WIDTH[:ALPHA]`, or a ParaView-exported JSON colormap file.

use crate::error::{Error, Result};
use crate::gpu::Recording;
use crate::gpu::{vk, Buffer, Context, Staging};
use std::path::Path;

mod gpu;
pub use gpu::GpuTransferFunction;

/// Opacity of a sample of alpha `a` per voxel of path standing for `w`
/// voxels: `1 - (1 - a)^w`, with 0 and 1 exact. As `glsl/common/opacity.glsl`
/// (up to the rounding of the device's `pow`).
// The negated comparison mirrors the GLSL: a NaN alpha is transparent.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn opacity(a: f32, w: f32) -> f32 {
    if !(a > 0.0) {
        0.0
    } else if a >= 1.0 {
        1.0
    } else {
        1.0 - (1.0 - a).powf(w)
    }
}

/// RGBA at normalised value `v` of a `LUT_SIZE`-entry table, bit-for-bit the
/// GLSL `tf_lookup`.
pub fn lookup_in(table: &[[f32; 4]], v: f32) -> [f32; 4] {
    let x = v * (LUT_SIZE - 1) as f32;
    let fl = x.floor();
    let i = (fl as usize).min(LUT_SIZE - 1);
    let j = (i + 1).min(LUT_SIZE - 1);
    let f = x - fl;
    let (a, b) = (table[i], table[j]);
    [0, 1, 2, 3].map(|c| a[c] * (1.0 - f) + b[c] * f)
}

/// How an error about the count of transfer functions ends.
const ONE_TF_EACH: &str = "give one for all channels, or one per channel";

/// LUT entries: fine enough that a spike one LUT step wide is narrower than
/// the gap between adjacent 8-bit values (1/255).
pub const LUT_SIZE: usize = 1024;

/// A transfer function: RGBA over normalised values [0, 1], sampled into a
/// LUT of `LUT_SIZE` entries, with the tables classification asks of it.
#[derive(Clone, Debug)]
pub struct TransferFunction {
    /// The spec it was made from.
    pub spec: String,
    lut: Vec<[f32; 4]>,
    /// Sparse table: `max_table[k][i]` = max alpha of entries i .. i + 2^k.
    max_table: Vec<Vec<f32>>,
    /// `shown[i]`: how many of the entries before i have alpha above 0.
    shown: Box<[u32; LUT_SIZE + 1]>,
    /// The transfer functions of channels 2 and up (`per_channel`); this
    /// one is channel 1's. Empty: one transfer function for every channel.
    other_channels: Vec<TransferFunction>,
}

/// The default colour ramp (dark violet through orange to pale yellow).
fn colormap(t: f32) -> [f32; 3] {
    const STOPS: [(f32, [f32; 3]); 5] = [
        (0.0, [0.05, 0.03, 0.25]),
        (0.25, [0.30, 0.10, 0.55]),
        (0.5, [0.80, 0.25, 0.35]),
        (0.75, [0.98, 0.60, 0.15]),
        (1.0, [1.0, 0.95, 0.70]),
    ];
    let t = t.clamp(0.0, 1.0);
    for w in STOPS.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            let f = (t - t0) / (t1 - t0);
            return [0, 1, 2].map(|i| c0[i] + (c1[i] - c0[i]) * f);
        }
    }
    STOPS[4].1
}

/// The LUT entries `max_alpha` covers for the values [lo, hi] (lo <= hi),
/// a NaN bound taken as the end it bounds.
fn entries_of(lo: f32, hi: f32) -> (usize, usize) {
    let lo = if lo.is_nan() { 0.0 } else { lo.clamp(0.0, 1.0) };
    let hi = if hi.is_nan() { 1.0 } else { hi.clamp(0.0, 1.0) };
    let scale = (LUT_SIZE - 1) as f32;
    // Floor and ceiling of values in [0, scale] by truncation: `floor` and
    // `ceil` are library calls on x86-64's baseline (no SSE4.1).
    let (l, h) = (lo * scale, hi * scale);
    let ceil = h as usize + ((h as usize as f32) < h) as usize;
    ((l as usize).saturating_sub(1), (ceil + 1).min(LUT_SIZE - 1))
}

fn entry_value(i: usize) -> f32 {
    i as f32 / (LUT_SIZE - 1) as f32
}

impl TransferFunction {
    /// Builds a TF from a LUT of exactly `LUT_SIZE` entries with alpha in [0, 1].
    pub fn from_lut(spec: impl Into<String>, lut: Vec<[f32; 4]>) -> Result<Self> {
        let spec = spec.into();
        if lut.len() != LUT_SIZE {
            return Err(Error::invalid(
                "transfer function",
                spec,
                format!("LUT has {} entries, expected {LUT_SIZE}", lut.len()),
            ));
        }
        if lut.iter().flatten().any(|c| !c.is_finite() || *c < 0.0) || lut.iter().any(|e| e[3] > 1.0) {
            return Err(Error::invalid(
                "transfer function",
                spec,
                "LUT values must be finite, >= 0, alpha <= 1",
            ));
        }
        let mut max_table = vec![lut.iter().map(|e| e[3]).collect::<Vec<f32>>()];
        let mut k = 1;
        while (1 << k) <= LUT_SIZE {
            let prev = &max_table[k - 1];
            let half = 1 << (k - 1);
            let next: Vec<f32> = (0..=LUT_SIZE - (1 << k)).map(|i| prev[i].max(prev[i + half])).collect();
            max_table.push(next);
            k += 1;
        }
        let mut shown = Box::new([0u32; LUT_SIZE + 1]);
        for (i, e) in lut.iter().enumerate() {
            shown[i + 1] = shown[i] + (e[3] > 0.0) as u32;
        }
        Ok(TransferFunction {
            spec,
            lut,
            max_table,
            shown,
            other_channels: Vec::new(),
        })
    }

    /// Parses a spec, or reads a ParaView JSON file when `spec` names one.
    pub fn parse(spec: &str) -> Result<Self> {
        let path = Path::new(spec);
        if spec.to_lowercase().ends_with(".json") || path.is_file() {
            return Self::from_paraview_json(path);
        }
        let parts: Vec<&str> = spec.split(':').collect();
        let bad = |why: &str| Error::invalid("transfer function", spec, why.to_string());
        let nums: Vec<f32> = parts[1..]
            .iter()
            .map(|p| {
                p.parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| bad(&format!("'{p}' is not a finite number")))
            })
            .collect::<Result<_>>()?;
        let alpha = |i: usize| -> Result<f32> {
            let a = nums.get(i).copied().unwrap_or(1.0);
            if (0.0..=1.0).contains(&a) {
                Ok(a)
            } else {
                Err(bad("ALPHA must be in [0, 1]"))
            }
        };
        let arity = |min: usize, form: &str| -> Result<()> {
            if nums.len() < min || nums.len() > min + 1 {
                Err(bad(&format!("expected {form}")))
            } else {
                Ok(())
            }
        };
        let lut: Vec<[f32; 4]> = match parts[0] {
            "ramp" => {
                arity(2, "ramp:LO:HI[:ALPHA]")?;
                let (lo, hi, a) = (nums[0], nums[1], alpha(2)?);
                if lo >= hi {
                    return Err(bad("LO must be below HI"));
                }
                (0..LUT_SIZE)
                    .map(|i| {
                        let v = entry_value(i);
                        let t = ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
                        let c = colormap(v);
                        [c[0], c[1], c[2], a * t]
                    })
                    .collect()
            }
            "band" => {
                arity(2, "band:LO:HI[:ALPHA]")?;
                let (lo, hi, a) = (nums[0], nums[1], alpha(2)?);
                if lo > hi {
                    return Err(bad("LO must not exceed HI"));
                }
                // A band inside [0, 1] but narrower than one LUT step keeps its nearest entry.
                let nearest = (((lo + hi) / 2.0).clamp(0.0, 1.0) * (LUT_SIZE - 1) as f32).round() as usize;
                let holds_entry = hi < 0.0 || lo > 1.0 || (0..LUT_SIZE).any(|i| (lo..=hi).contains(&entry_value(i)));
                (0..LUT_SIZE)
                    .map(|i| {
                        let v = entry_value(i);
                        let c = colormap(v);
                        let inside = (lo..=hi).contains(&v) || (!holds_entry && i == nearest);
                        [c[0], c[1], c[2], if inside { a } else { 0.0 }]
                    })
                    .collect()
            }
            "spike" => {
                arity(2, "spike:CENTER:WIDTH[:ALPHA]")?;
                let (centre, width, a) = (nums[0], nums[1], alpha(2)?);
                if width <= 0.0 {
                    return Err(bad("WIDTH must be > 0"));
                }
                if !(0.0..=1.0).contains(&centre) {
                    return Err(bad("CENTER must be in [0, 1]"));
                }
                // The entry nearest the centre always carries the peak, so a
                // spike narrower than one LUT step is not lost.
                let nearest = (centre * (LUT_SIZE - 1) as f32).round() as usize;
                (0..LUT_SIZE)
                    .map(|i| {
                        let v = entry_value(i);
                        let tri = (1.0 - (v - centre).abs() / (width / 2.0)).max(0.0);
                        let c = colormap(centre);
                        [c[0], c[1], c[2], if i == nearest { a } else { a * tri }]
                    })
                    .collect()
            }
            _ => {
                return Err(bad(
                    "expected ramp:LO:HI[:ALPHA], band:LO:HI[:ALPHA], spike:CENTER:WIDTH[:ALPHA] or a .json file",
                ))
            }
        };
        Self::from_lut(spec, lut)
    }

    /// A ParaView colormap export: `RGBPoints` (x, r, g, b)* and optional
    /// opacity `Points` (x, alpha, midpoint, sharpness)*; midpoint and
    /// sharpness are ignored (linear segments). The x range of `RGBPoints` is
    /// mapped onto the volume's normalised [0, 1] ("rescale to data range").
    /// Without `Points` opacity ramps linearly from 0 to 1 over that range.
    /// (Feature `loaders`; without it, an error saying so.)
    #[cfg(not(feature = "loaders"))]
    pub fn from_paraview_json(path: &Path) -> Result<Self> {
        Err(Error::format(
            path,
            "ParaView JSON transfer functions need lacuna's `loaders` cargo feature",
        ))
    }

    /// A ParaView colormap export (feature `loaders`).
    #[cfg(feature = "loaders")]
    pub fn from_paraview_json(path: &Path) -> Result<Self> {
        // serde_json's values take up to some 40 times the text (a value
        // for every number): check before reading.
        let (_, len) = crate::limits::open_input(path)?;
        let len = len.min(crate::limits::MAX_TEXT_INPUT + 1); // past the cap, read_input names it
        crate::limits::check_host(format_args!("ParaView JSON {}", path.display()), len, 40)?;
        let text =
            crate::limits::read_input_text(path, "ParaView JSON transfer function", crate::limits::MAX_TEXT_INPUT)?;
        Self::from_paraview_json_str(&text, path)
    }

    /// A ParaView colormap export held in memory; `origin` names it in errors.
    #[cfg(feature = "loaders")]
    pub fn from_paraview_json_str(text: &str, origin: &Path) -> Result<Self> {
        let path = origin;
        let json: serde_json::Value =
            serde_json::from_str(text).map_err(|e| Error::format(path, format!("invalid JSON: {e}")))?;
        let map = match &json {
            serde_json::Value::Array(a) => a.first().unwrap_or(&serde_json::Value::Null),
            other => other,
        };
        let numbers = |key: &str, stride: usize| -> Result<Option<Vec<f64>>> {
            let Some(v) = map.get(key) else {
                return Ok(None);
            };
            let arr = v
                .as_array()
                .ok_or_else(|| Error::format(path, format!("'{key}' is not an array")))?;
            let nums: Option<Vec<f64>> = arr.iter().map(|x| x.as_f64().filter(|f| f.is_finite())).collect();
            let nums =
                nums.ok_or_else(|| Error::format(path, format!("'{key}' holds a value that is not a finite number")))?;
            if nums.is_empty() || nums.len() % stride != 0 {
                return Err(Error::format(
                    path,
                    format!("'{key}' must hold groups of {stride} numbers"),
                ));
            }
            Ok(Some(nums))
        };
        let rgb = numbers("RGBPoints", 4)?
            .ok_or_else(|| Error::format(path, "no 'RGBPoints' array (not a ParaView colormap export)"))?;
        let opacity = numbers("Points", 4)?;
        let xs: Vec<f64> = rgb.chunks(4).map(|c| c[0]).collect();
        let (x0, x1) = (xs[0], xs[xs.len() - 1]);
        if xs.windows(2).any(|w| w[1] < w[0]) {
            return Err(Error::format(path, "'RGBPoints' x values must be ascending"));
        }
        if x1 <= x0 {
            return Err(Error::format(path, "'RGBPoints' spans an empty range"));
        }
        if rgb.chunks(4).any(|c| c[1..].iter().any(|v| !(0.0..=1.0).contains(v))) {
            return Err(Error::format(path, "'RGBPoints' colours must be in [0, 1]"));
        }
        if let Some(op) = &opacity {
            if op.chunks(4).any(|c| !(0.0..=1.0).contains(&c[1])) {
                return Err(Error::format(path, "opacity 'Points' values must be in [0, 1]"));
            }
            if op.chunks(4).zip(op.chunks(4).skip(1)).any(|(a, b)| b[0] < a[0]) {
                return Err(Error::format(path, "opacity 'Points' x values must be ascending"));
            }
        }
        // Piecewise-linear interpolation over (x, values...) groups,
        // ascending in x: between the first group at or past x and the one
        // before it (a binary search, so a colormap of millions of points
        // builds its table at once).
        let (rgb, opacity) = (
            rgb.chunks(4).collect::<Vec<_>>(),
            opacity.as_ref().map(|op| op.chunks(4).collect::<Vec<_>>()),
        );
        let interp = |groups: &[&[f64]], x: f64, channel: usize| -> f64 {
            match groups.partition_point(|g| g[0] < x) {
                0 => groups[0][channel],
                j if j == groups.len() => groups[j - 1][channel],
                j => {
                    let (a, b) = (groups[j - 1], groups[j]);
                    let span = b[0] - a[0];
                    let f = if span > 0.0 { (x - a[0]) / span } else { 1.0 };
                    a[channel] + (b[channel] - a[channel]) * f
                }
            }
        };
        let lut = (0..LUT_SIZE)
            .map(|i| {
                let x = x0 + (x1 - x0) * entry_value(i) as f64;
                let a = match &opacity {
                    Some(op) => interp(op, x, 1),
                    None => entry_value(i) as f64,
                };
                [
                    interp(&rgb, x, 1) as f32,
                    interp(&rgb, x, 2) as f32,
                    interp(&rgb, x, 3) as f32,
                    a as f32,
                ]
            })
            .collect();
        Self::from_lut(path.display().to_string(), lut)
    }

    /// One transfer function per channel of a multi-channel volume, in
    /// channel order (1 to `volume::MAX_CHANNELS`, each itself one).
    pub fn per_channel(tfs: Vec<TransferFunction>) -> Result<Self> {
        let spec = tfs.iter().map(|t| t.spec.as_str()).collect::<Vec<_>>().join(" | ");
        if tfs.is_empty() || tfs.len() > crate::limits::MAX_CHANNELS || tfs.iter().any(|t| t.channel_count() > 1) {
            return Err(Error::invalid(
                "transfer function",
                spec,
                format!(
                    "{} per-channel transfer functions: 1 to {}, each one",
                    tfs.len(),
                    crate::limits::MAX_CHANNELS
                ),
            ));
        }
        let mut tfs = tfs.into_iter();
        let Some(mut first) = tfs.next() else {
            return Err(Error::invalid("transfer function", spec, "no transfer function"));
        };
        first.other_channels = tfs.collect();
        first.spec = spec;
        Ok(first)
    }

    /// One spec per channel separated by `|` (`ramp:0.3:1 | spike:0.6:0.2`,
    /// as `spec` prints them), or one spec (`parse`).
    pub fn parse_channels(spec: &str) -> Result<Self> {
        match spec.contains('|') {
            true => Self::per_channel(
                spec.split('|')
                    .map(|s| Self::parse(s.trim()))
                    .collect::<Result<Vec<_>>>()?,
            ),
            false => Self::parse(spec),
        }
    }

    /// How many channels it gives transfer functions for; 1 applies to
    /// every channel.
    pub fn channel_count(&self) -> usize {
        1 + self.other_channels.len()
    }

    /// Channel `c`'s transfer function (0-based): its own, or the only one
    /// (one transfer function serves every channel).
    ///
    /// # Panics
    /// If it has one per channel and `c >= channel_count()`, as indexing a
    /// slice does (`check_channels` says whether it suits a volume).
    pub fn channel(&self, c: usize) -> &TransferFunction {
        match c {
            0 => self,
            _ if self.other_channels.is_empty() => self,
            _ => &self.other_channels[c - 1],
        }
    }

    /// An error unless it suits a volume of `channels` channels: one
    /// transfer function for all of them, or one each.
    pub fn check_channels(&self, channels: usize) -> Result<()> {
        let n = self.channel_count();
        if n != 1 && n != channels {
            return Err(Error::invalid(
                "transfer function",
                self.spec.clone(),
                format!(
                    "{n} transfer functions for a volume of {channels} channel{}: {ONE_TF_EACH}",
                    if channels == 1 { "" } else { "s" }
                ),
            ));
        }
        Ok(())
    }

    /// Each channel's transfer function (`channel_count` of them).
    pub fn channels(&self) -> impl Iterator<Item = &TransferFunction> {
        std::iter::once(self).chain(self.other_channels.iter())
    }

    pub fn lut(&self) -> &[[f32; 4]] {
        &self.lut
    }

    /// RGBA at normalised value `v`, bit-for-bit the GLSL `tf_lookup` of the raw table.
    pub fn lookup(&self, v: f32) -> [f32; 4] {
        lookup_in(&self.lut, v)
    }

    /// The LUT with alpha corrected for a step of `dt` voxels (`opacity`),
    /// rgb unchanged: what `glsl/build/opacity_lut.comp` writes per frame.
    pub fn corrected_lut(&self, dt: f32) -> Vec<[f32; 4]> {
        self.lut.iter().map(|&[r, g, b, a]| [r, g, b, opacity(a, dt)]).collect()
    }

    /// The march kernels' LUT for a frame of step `dt`, as
    /// `glsl/build/opacity_lut.comp` writes it: per channel's transfer
    /// function, `corrected_lut(dt)` then the raw LUT.
    pub fn frame_tables(&self, dt: f32) -> Vec<[f32; 4]> {
        self.channels()
            .flat_map(|t| [t.corrected_lut(dt), t.lut.clone()].concat())
            .collect()
    }

    /// Max of alpha over entries `i..=j`.
    fn max_entries(&self, i: usize, j: usize) -> f32 {
        let len = j - i + 1;
        let k = usize::BITS as usize - 1 - len.leading_zeros() as usize;
        self.max_table[k][i].max(self.max_table[k][j + 1 - (1 << k)])
    }

    /// Conservative max alpha over every value in [lo, hi]: covers the LUT
    /// entries any interpolated lookup there can touch, widened by one entry
    /// each side for rounding (DESIGN invariant 2). O(1).
    pub fn max_alpha(&self, lo: f32, hi: f32) -> f32 {
        if lo > hi {
            return 0.0;
        }
        let (i, j) = entries_of(lo, hi);
        self.max_entries(i, j)
    }

    /// Whether `max_alpha(lo, hi) > 0`, from a count of the entries shown
    /// (alpha is never negative): a host classification's per-brick test.
    pub fn visible(&self, lo: f32, hi: f32) -> bool {
        // Without branches: an empty range's entries are looked up too.
        let (empty, (i, j)) = (lo > hi, entries_of(lo, hi));
        !empty & (self.shown[j + 1] > self.shown[i])
    }

    /// The max-alpha sparse table flattened for the GPU: level k at
    /// `k * LUT_SIZE`, zero padded (`glsl/common/tf_range.glsl`).
    pub fn max_table_flat(&self) -> Vec<f32> {
        let mut flat = vec![0f32; self.max_table.len() * LUT_SIZE];
        for (k, level) in self.max_table.iter().enumerate() {
            flat[k * LUT_SIZE..k * LUT_SIZE + level.len()].copy_from_slice(level);
        }
        flat
    }

    /// As `upload`, recorded into `cmd`: copies from staging, then a barrier
    /// to compute-shader reads. Keep the returned `Staging` until the
    /// submission completed.
    pub fn record_upload(&self, cmd: Recording<'_>) -> Result<(GpuTransferFunction, Staging)> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let (luts, tables) = self.channel_tables();
        let (lut, a) = Buffer::record_with_data(cmd, "transfer function", bytemuck::cast_slice(&luts), usage)?;
        let name = "transfer function max table";
        let (max_table, b) = Buffer::record_with_data(cmd, name, bytemuck::cast_slice(&tables), usage)?;
        Ok((self.on_gpu(lut, max_table), a.join(b)))
    }

    /// Uploads the LUT (`vec4` per entry) and the max-alpha table and waits.
    pub fn upload(&self, ctx: &Context) -> Result<GpuTransferFunction> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let (luts, tables) = self.channel_tables();
        let lut = Buffer::with_data(ctx, "transfer function", bytemuck::cast_slice(&luts), usage)?;
        let max_table = Buffer::with_data(ctx, "transfer function max table", bytemuck::cast_slice(&tables), usage)?;
        Ok(self.on_gpu(lut, max_table))
    }

    /// Every channel's LUT and flattened max table, channel after channel.
    fn channel_tables(&self) -> (Vec<[f32; 4]>, Vec<f32>) {
        let luts = self.channels().flat_map(|t| t.lut.iter().copied()).collect();
        let tables = self.channels().flat_map(|t| t.max_table_flat()).collect();
        (luts, tables)
    }

    /// Its opacities, as a number: equal for transfer functions whose
    /// every channel's alpha entries are equal bit for bit. Classification
    /// reads only those, so a structure built for one skips exactly for
    /// the other (a recoloured one; `GpuTransferFunction::alpha_key`).
    pub fn alpha_key(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for t in self.channels() {
            t.lut.len().hash(&mut h);
            t.lut.iter().for_each(|e| e[3].to_bits().hash(&mut h));
        }
        h.finish()
    }

    fn on_gpu(&self, lut: Buffer, max_table: Buffer) -> GpuTransferFunction {
        GpuTransferFunction {
            alpha_key: self.alpha_key(),
            lut,
            max_table,
            visible: self.visible_entries(),
            channels: self.channel_count() as u32,
            // Every channel's table has the same levels (`max_table_flat`).
            max_stride: (self.max_table.len() * LUT_SIZE) as u32,
        }
    }

    /// The first and last LUT entries with alpha > 0; None if every entry
    /// is transparent.
    pub fn visible_entries(&self) -> Option<[u32; 2]> {
        let first = self.lut.iter().position(|c| c[3] > 0.0)?;
        let last = self.lut.iter().rposition(|c| c[3] > 0.0)?;
        Some([first as u32, last as u32])
    }
}

impl std::str::FromStr for TransferFunction {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Self::parse(s)
    }
}
