//! The frame's look on the command line: `--mode`, `--iso`, shading, clip
//! planes, the crop box and jitter, as a `LookSpec` (which checks every
//! flag against the mode).

use clap::{Args, ValueEnum};
use lacuna::render::{FrameBuilder, LookSpec};
use lacuna::Result;

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
    #[arg(long, value_name = "V[,V2,...]", allow_hyphen_values = true)]
    pub iso: Option<String>,
    /// Iso surface colour R,G,B in [0, 1] (default: the TF's colour at the value).
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true)]
    pub iso_color: Option<String>,
    /// Gradient (Blinn-Phong) shading of composite frames (iso surfaces are always lit).
    #[arg(long, value_enum, value_name = "on|off")]
    pub shade: Option<OnOff>,
    /// A fixed light at AZ,EL degrees (as --camera), or headlight (the default).
    #[arg(long, value_name = "AZ,EL", allow_hyphen_values = true)]
    pub light: Option<String>,
    /// Ambient, diffuse and specular weights and the shininess (default 0.1,0.7,0.2,10 as VTK).
    #[arg(long, value_name = "KA,KD,KS,N", allow_hyphen_values = true)]
    pub phong: Option<String>,
    /// Opacity times a ramp of the gradient magnitude from 0 at LO to 1 at HI (normalised value per unit length).
    #[arg(long, value_name = "LO:HI", allow_hyphen_values = true)]
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
    /// The mode, shading, clip and jitter set on `b` (`LookSpec::apply`).
    pub fn apply(&self, b: FrameBuilder) -> Result<FrameBuilder> {
        self.spec().apply(b)
    }

    pub fn spec(&self) -> LookSpec {
        LookSpec {
            mode: self.mode.clone(),
            iso: self.iso.clone(),
            iso_color: self.iso_color.clone(),
            shade: self.shade.map(|s| s == OnOff::On),
            light: self.light.clone(),
            phong: self.phong.clone(),
            gradient_opacity: self.gradient_opacity.clone(),
            clip: self.clip.clone(),
            crop: self.crop.clone(),
            jitter: self.jitter.map(|j| j == OnOff::On),
        }
    }
}
