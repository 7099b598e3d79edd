//! What a ray accumulates (`Mode`) and the iso values of iso frames.

use super::parse::numbers;
use super::shading::Shading;
use crate::error::{Error, Result};
use crate::tf::LUT_SIZE;

/// The specialization constant ids of the mode and of composite shading
/// (`MARCH_MODE`, `MARCH_SHADE` in `glsl/common/lattice.glsl`).
pub const MODE_CONSTANT_ID: u32 = 17;
/// `constant_id` of `MARCH_SHADE`.
pub const SHADE_CONSTANT_ID: u32 = 18;
/// `constant_id` of `MARCH_SHININESS` (`glsl/common/light.glsl`): the
/// whole Phong exponent of lit frames, 0 for pow.
pub const SHININESS_CONSTANT_ID: u32 = 29;

/// Iso values a frame can show at once.
pub const MAX_ISO: usize = 4;

/// What a ray accumulates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Mode {
    /// Emission and absorption, front to back (the default).
    #[default]
    Composite,
    /// The largest sample along the ray, then its colour and opacity from
    /// the transfer function (maximum intensity projection).
    Mip,
    /// The smallest sample (minimum intensity projection).
    MinIp,
    /// The mean of the samples along the ray.
    Average,
    /// The first crossing of an iso value, shaded, in the transfer
    /// function's colour at that value.
    Iso(Iso),
}

impl Mode {
    /// `composite`, `mip`, `minip`, `average`, `iso`.
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Composite => "composite",
            Mode::Mip => "mip",
            Mode::MinIp => "minip",
            Mode::Average => "average",
            Mode::Iso(_) => "iso",
        }
    }

    /// The shaders' `MARCH_MODE` (`glsl/common/lattice.glsl`).
    pub fn constant(&self) -> u32 {
        match self {
            Mode::Composite => 0,
            Mode::Mip => 1,
            Mode::MinIp => 2,
            Mode::Average => 3,
            Mode::Iso(_) => 4,
        }
    }

    /// The value beyond which samples cannot show in a mip (minip) frame
    /// whose TF's visible entries are `visible`
    /// (`TransferFunction::visible_entries`): every value at or below it
    /// (at or above it) maps to alpha exactly 0, interpolation included, so
    /// a region whose values all lie there cannot change a pixel. -1 (2)
    /// where no value is that; 2 (-1) where the TF shows nothing. 0 in the
    /// other modes.
    pub fn value_bound(&self, visible: Option<[u32; 2]>) -> f32 {
        let last = (LUT_SIZE - 1) as f32;
        match (self, visible) {
            (Mode::Mip, None) => 2.0,
            (Mode::Mip, Some([first, _])) if first >= 2 => (first - 2) as f32 / last,
            (Mode::Mip, Some(_)) => -1.0,
            (Mode::MinIp, None) => -1.0,
            (Mode::MinIp, Some([_, l])) if l as usize + 2 < LUT_SIZE => (l + 2) as f32 / last,
            (Mode::MinIp, Some(_)) => 2.0,
            _ => 0.0,
        }
    }

    /// Whether frames of this mode can use a structure built for `other`:
    /// the same kind, and for iso the same values (colours do not matter).
    pub fn same_classification(&self, other: &Mode) -> bool {
        match (self, other) {
            (Mode::Iso(x), Mode::Iso(y)) => x.values() == y.values(),
            _ => self.constant() == other.constant(),
        }
    }

    /// A mode by name; `iso` takes its values from `iso`.
    pub fn parse(name: &str, iso: Option<Iso>) -> Result<Mode> {
        let mode = match name {
            "composite" => Mode::Composite,
            "mip" => Mode::Mip,
            "minip" => Mode::MinIp,
            "average" => Mode::Average,
            "iso" => {
                return iso
                    .map(Mode::Iso)
                    .ok_or_else(|| Error::invalid("mode", "iso", "needs --iso V[,V2,...]"))
            }
            other => {
                return Err(Error::invalid(
                    "mode",
                    other,
                    "expected composite, mip, minip, average or iso",
                ))
            }
        };
        if let Some(iso) = iso {
            let values: Vec<String> = iso.values().iter().map(|v| v.to_string()).collect();
            return Err(Error::invalid(
                "iso",
                values.join(","),
                format!("iso values need --mode iso, not --mode {name}"),
            ));
        }
        Ok(mode)
    }
}

/// The iso values of `Mode::Iso` (normalised values in [0, 1], as transfer
/// function specs use) and the surface colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iso {
    values: [f32; MAX_ISO],
    count: usize,
    /// The surface colour; None: the transfer function's colour at the value.
    pub color: Option<[f32; 3]>,
}

impl Iso {
    /// 1 to 4 finite values.
    pub fn new(values: &[f32]) -> Result<Iso> {
        let listed = || values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(",");
        if values.is_empty() || values.len() > MAX_ISO {
            return Err(Error::invalid(
                "iso",
                listed(),
                format!("expected 1 to {MAX_ISO} values"),
            ));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(Error::invalid("iso", v.to_string(), "must be a finite number"));
        }
        let mut out = [0.0; MAX_ISO];
        out[..values.len()].copy_from_slice(values);
        Ok(Iso {
            values: out,
            count: values.len(),
            color: None,
        })
    }

    /// Parses `V[,V2,...]`.
    pub fn parse(s: &str) -> Result<Iso> {
        let values: Vec<f32> = s
            .split(',')
            .map(|v| {
                v.trim()
                    .parse::<f32>()
                    .map_err(|_| Error::invalid("iso", s, "expected V[,V2,...] (normalised values)"))
            })
            .collect::<Result<_>>()?;
        Iso::new(&values)
    }

    /// The surface colour instead of the transfer function's.
    pub fn with_color(mut self, rgb: [f32; 3]) -> Result<Iso> {
        if !rgb.iter().all(|c| c.is_finite() && (0.0..=1.0).contains(c)) {
            return Err(Error::invalid(
                "iso color",
                rgb.map(|c| c.to_string()).join(","),
                "components must be in [0, 1]",
            ));
        }
        self.color = Some(rgb);
        Ok(self)
    }

    pub fn values(&self) -> &[f32] {
        &self.values[..self.count]
    }

    /// Parses `--iso-color R,G,B` (each in [0, 1]) onto these values.
    pub fn parse_color(self, s: &str) -> Result<Iso> {
        let c = numbers("iso color", s, 3, &[','], "R,G,B in [0, 1]")?;
        self.with_color([c[0], c[1], c[2]])
    }
}

/// Validates what `FrameBuilder::build` checks of a frame's look.
pub(crate) fn validate(mode: &Mode, shading: &Option<Shading>, ert: Option<f32>) -> Result<()> {
    if let Some(s) = shading {
        s.validate()?;
        if !matches!(mode, Mode::Composite | Mode::Iso(_)) {
            return Err(Error::invalid(
                "shade",
                "on",
                format!("shades composite and iso frames, not {}", mode.name()),
            ));
        }
    }
    if ert.is_some() && !matches!(mode, Mode::Composite) {
        return Err(Error::invalid(
            "ert",
            ert.map(|e| e.to_string()).unwrap_or_default(),
            format!("ends composite rays only, not {}", mode.name()),
        ));
    }
    Ok(())
}
