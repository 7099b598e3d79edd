//! The frame's look on the command line: `--mode`, `--iso`, shading, clip
//! planes, the crop box and jitter. Every flag is checked against the mode:
//! a flag the frame would not use is an error, not silently ignored.

use clap::{Args, ValueEnum};
use lacuna::render::{Clip, FrameBuilder, Iso, Light, Mode, Shading};
use lacuna::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

#[derive(Args, Clone, Default)]
pub struct LookArgs {
    /// What each ray shows: composite (emission-absorption), mip / minip (the largest / smallest sample through the TF), average (the mean sample), iso (the first crossing of an --iso value, lit).
    #[arg(long, value_name = "MODE")]
    pub mode: Option<String>,
    /// Iso values for --mode iso, normalised to [0, 1] as TF specs: V[,V2,...] (up to 4).
    #[arg(long, value_name = "V[,V2,...]")]
    pub iso: Option<String>,
    /// Iso surface colour R,G,B in [0, 1] (default: the TF's colour at the value).
    #[arg(long, value_name = "R,G,B")]
    pub iso_color: Option<String>,
    /// Gradient (Blinn-Phong) shading of composite frames (iso surfaces are always lit).
    #[arg(long, value_enum, value_name = "on|off")]
    pub shade: Option<OnOff>,
    /// A fixed light at AZ,EL degrees (as --camera), or headlight (the default).
    #[arg(long, value_name = "AZ,EL", allow_hyphen_values = true)]
    pub light: Option<String>,
    /// Ambient, diffuse and specular weights and the shininess (default 0.1,0.7,0.2,10 as VTK).
    #[arg(long, value_name = "KA,KD,KS,N")]
    pub phong: Option<String>,
    /// Opacity times a ramp of the gradient magnitude from 0 at LO to 1 at HI (normalised value per unit length).
    #[arg(long, value_name = "LO:HI")]
    pub gradient_opacity: Option<String>,
    /// Keep A x + B y + C z + D >= 0 in voxel coordinates; repeatable (up to 6).
    #[arg(long, value_name = "A,B,C,D", allow_hyphen_values = true)]
    pub clip: Vec<String>,
    /// Keep the box X0:X1,Y0:Y1,Z0:Z1 in voxel coordinates.
    #[arg(long, value_name = "X0:X1,Y0:Y1,Z0:Z1", allow_hyphen_values = true)]
    pub crop: Option<String>,
    /// Shift each pixel's samples by a fixed hashed fraction of the step (removes wood-grain).
    #[arg(long, value_enum, value_name = "on|off")]
    pub jitter: Option<OnOff>,
}

impl LookArgs {
    /// The mode, shading, clip and jitter set on `b`; the builder's `build`
    /// checks them together.
    pub fn apply(&self, b: FrameBuilder) -> Result<FrameBuilder> {
        let mode = self.mode()?;
        let b = b
            .mode(mode)
            .shading(self.shading(&mode)?)
            .clip(self.clip()?)
            .jitter(self.jitter == Some(OnOff::On));
        Ok(b)
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

    /// The shading of a frame of `mode`: `--shade on` (composite), always
    /// for iso; the lighting flags need one of them.
    fn shading(&self, mode: &Mode) -> Result<Option<Shading>> {
        let lit = match (self.shade, mode) {
            (Some(OnOff::On), _) => true,
            (Some(OnOff::Off), Mode::Iso(_)) => {
                return Err(Error::invalid("shade", "off", "iso surfaces are always lit"));
            }
            (_, Mode::Iso(_)) => true,
            _ => false,
        };
        let flags = [
            ("--light", &self.light),
            ("--phong", &self.phong),
            ("--gradient-opacity", &self.gradient_opacity),
        ];
        if !lit {
            if let Some((flag, Some(v))) = flags.iter().find(|(_, v)| v.is_some()) {
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
            if matches!(mode, Mode::Iso(_)) {
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
