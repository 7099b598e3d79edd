//! A frame's look in text, as `render`'s flags and bench configs give it
//! (`--mode iso --iso 0.3`, `look = { mode = "iso", iso = "0.3" }`), checked
//! against the mode: an option the frame would not use is an error, not
//! silently ignored.

use super::{Clip, FrameBuilder, Iso, Light, Mode, Shading};
use crate::error::{Error, Result};

/// The look options, unparsed; None: not given.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize), serde(deny_unknown_fields))]
pub struct LookSpec {
    /// composite, mip, minip, average or iso.
    pub mode: Option<String>,
    /// Iso values V[,V2,...] (mode iso); in TOML also a number, `iso = 0.3`.
    #[cfg_attr(feature = "serde", serde(default, deserialize_with = "number_or_text"))]
    pub iso: Option<String>,
    /// Iso surface colour R,G,B.
    pub iso_color: Option<String>,
    /// Gradient shading of composite frames (iso surfaces are always lit).
    pub shade: Option<bool>,
    /// AZ,EL of a fixed light, or headlight.
    pub light: Option<String>,
    /// KA,KD,KS,SHININESS.
    pub phong: Option<String>,
    /// LO:HI gradient-magnitude opacity ramp.
    pub gradient_opacity: Option<String>,
    /// Clip planes A,B,C,D.
    #[cfg_attr(feature = "serde", serde(default))]
    pub clip: Vec<String>,
    /// Crop box X0:X1,Y0:Y1,Z0:Z1.
    pub crop: Option<String>,
    pub jitter: Option<bool>,
}

/// A value given as text or as a number (`"0.3,0.5"` or `0.3`), as text.
#[cfg(feature = "serde")]
fn number_or_text<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<String>, D::Error> {
    struct Given;
    impl serde::de::Visitor<'_> for Given {
        type Value = String;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number or a string of numbers separated by commas")
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<String, E> {
            Ok(v.to_string())
        }
    }
    d.deserialize_any(Given).map(Some)
}

impl LookSpec {
    /// These options, each given one replacing `base`'s.
    pub fn over(&self, base: &LookSpec) -> LookSpec {
        let pick = |a: &Option<String>, b: &Option<String>| a.clone().or_else(|| b.clone());
        LookSpec {
            mode: pick(&self.mode, &base.mode),
            iso: pick(&self.iso, &base.iso),
            iso_color: pick(&self.iso_color, &base.iso_color),
            shade: self.shade.or(base.shade),
            light: pick(&self.light, &base.light),
            phong: pick(&self.phong, &base.phong),
            gradient_opacity: pick(&self.gradient_opacity, &base.gradient_opacity),
            clip: if self.clip.is_empty() {
                base.clip.clone()
            } else {
                self.clip.clone()
            },
            crop: pick(&self.crop, &base.crop),
            jitter: self.jitter.or(base.jitter),
        }
    }

    /// The mode, shading, clip and jitter set on `b`; `build` checks them
    /// together.
    pub fn apply(&self, b: FrameBuilder) -> Result<FrameBuilder> {
        let mode = self.mode()?;
        Ok(b.mode(mode)
            .shading(self.shading(&mode)?)
            .clip(self.clip()?)
            .jitter(self.jitter == Some(true)))
    }

    fn mode(&self) -> Result<Mode> {
        let iso = self.iso.as_deref().map(Iso::parse).transpose()?;
        let iso = match (iso, &self.iso_color) {
            (Some(iso), Some(c)) => Some(iso.parse_color(c)?),
            (None, Some(c)) => return Err(Error::invalid("iso color", c, "needs --mode iso --iso V")),
            (iso, None) => iso,
        };
        match &self.mode {
            Some(name) => Mode::parse(name, iso),
            None if iso.is_some() => Err(Error::invalid(
                "iso",
                self.iso.clone().unwrap_or_default(),
                "iso values need --mode iso",
            )),
            None => Ok(Mode::Composite),
        }
    }

    /// The shading of a frame of `mode`: `shade` on (composite), always for
    /// iso; the lighting options need one of them.
    fn shading(&self, mode: &Mode) -> Result<Option<Shading>> {
        let iso = matches!(mode, Mode::Iso(_));
        let lit = match self.shade {
            Some(false) if iso => return Err(Error::invalid("shade", "off", "iso surfaces are always lit")),
            Some(on) => on || iso,
            None => iso,
        };
        let options = [
            ("--light", &self.light),
            ("--phong", &self.phong),
            ("--gradient-opacity", &self.gradient_opacity),
        ];
        if !lit {
            if let Some((flag, Some(v))) = options.iter().find(|(_, v)| v.is_some()) {
                return Err(Error::invalid(
                    "shade",
                    format!("{flag} {v}"),
                    "lighting needs --shade on (or --mode iso)",
                ));
            }
            return Ok(None);
        }
        let mut s = Shading::default();
        if let Some(l) = &self.light {
            s.light = Light::parse(l)?;
        }
        if let Some(p) = &self.phong {
            s = s.parse_phong(p)?;
        }
        if let Some(g) = &self.gradient_opacity {
            if iso {
                return Err(Error::invalid("gradient opacity", g, "iso surfaces are opaque"));
            }
            s = s.parse_gradient_opacity(g)?;
        }
        Ok(Some(s))
    }

    fn clip(&self) -> Result<Clip> {
        let mut clip = Clip::default();
        for plane in &self.clip {
            clip = clip.parse_plane(plane)?;
        }
        if let Some(c) = &self.crop {
            clip = clip.parse_crop(c)?;
        }
        Ok(clip)
    }
}
