//! Gradient shading: Blinn-Phong lighting of each visible sample by the
//! gradient of the trilinear field (`glsl/common/light.glsl`).

use super::parse::numbers;
use crate::error::{Error, Result};

/// Where the light comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Light {
    /// At the eye, shining along each ray (the default, as VTK's).
    #[default]
    Headlight,
    /// From this direction about the volume's centre, in degrees, as an
    /// orbit camera's (`Orbit`): azimuth about y from +z, elevation above
    /// the xz plane, in the volume's physical space.
    Fixed { azimuth_deg: f64, elevation_deg: f64 },
}

impl Light {
    /// `headlight`, or `AZ,EL` in degrees for a fixed light.
    pub fn parse(s: &str) -> Result<Light> {
        if s.trim() == "headlight" {
            return Ok(Light::Headlight);
        }
        let v = numbers("light", s, 2, &[','], "AZ,EL in degrees, or headlight")?;
        Ok(Light::Fixed {
            azimuth_deg: v[0] as f64,
            elevation_deg: v[1] as f64,
        })
    }
}

/// Blinn-Phong lighting of each visible sample by its gradient (central
/// differences of the trilinear field), white light. The defaults are VTK's
/// (`vtkVolumeProperty`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    pub ambient: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
    pub light: Light,
    /// Opacity times a ramp of the gradient's magnitude (normalised value
    /// per unit of physical length) from 0 at `[0]` to 1 at `[1]`, as VTK's
    /// gradient opacity. Only lowers opacity.
    pub gradient_opacity: Option<[f32; 2]>,
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            ambient: 0.1,
            diffuse: 0.7,
            specular: 0.2,
            shininess: 10.0,
            light: Light::Headlight,
            gradient_opacity: None,
        }
    }
}

impl Shading {
    /// The shininess where it is a whole number (then a lit sample raises
    /// to it by repeated squaring, `glsl/common/light.glsl`), else 0 (pow).
    pub fn whole_shininess(&self) -> u32 {
        whole_exponent(self.shininess)
    }

    pub(crate) fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("ambient", self.ambient),
            ("diffuse", self.diffuse),
            ("specular", self.specular),
        ] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return Err(Error::invalid(name, v.to_string(), "must be in [0, 1]"));
            }
        }
        if !(self.shininess.is_finite() && self.shininess >= 1.0 && self.shininess <= 128.0) {
            return Err(Error::invalid(
                "shininess",
                self.shininess.to_string(),
                "must be in [1, 128]",
            ));
        }
        if let Light::Fixed {
            azimuth_deg,
            elevation_deg,
        } = self.light
        {
            super::orbit::check_angles("light", azimuth_deg, elevation_deg)?;
        }
        if let Some([lo, hi]) = self.gradient_opacity {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
                return Err(Error::invalid(
                    "gradient opacity",
                    format!("{lo}:{hi}"),
                    "expected LO:HI with 0 <= LO < HI",
                ));
            }
        }
        Ok(())
    }

    /// `light headlight, phong 0.1,0.7,0.2,10[, gradient opacity LO:HI]`,
    /// in the flags' syntax.
    pub fn describe(&self) -> String {
        let light = match self.light {
            Light::Headlight => "headlight".to_string(),
            Light::Fixed {
                azimuth_deg,
                elevation_deg,
                // Read as f32 (`parse`): printed as one, 30 is not 30.000001907348633.
            } => format!("{},{}", azimuth_deg as f32, elevation_deg as f32),
        };
        let mut s = format!(
            "light {light}, phong {},{},{},{}",
            self.ambient, self.diffuse, self.specular, self.shininess
        );
        if let Some([lo, hi]) = self.gradient_opacity {
            s += &format!(", gradient opacity {lo}:{hi}");
        }
        s
    }

    /// Parses `--phong KA,KD,KS,SHININESS` onto these settings.
    pub fn parse_phong(mut self, s: &str) -> Result<Shading> {
        let v = numbers("phong", s, 4, &[','], "KA,KD,KS,SHININESS")?;
        (self.ambient, self.diffuse, self.specular, self.shininess) = (v[0], v[1], v[2], v[3]);
        self.validate()?;
        Ok(self)
    }

    /// Parses `--gradient-opacity LO:HI` onto these settings.
    pub fn parse_gradient_opacity(mut self, s: &str) -> Result<Shading> {
        let v = numbers("gradient opacity", s, 2, &[':'], "LO:HI (gradient magnitudes)")?;
        self.gradient_opacity = Some([v[0], v[1]]);
        self.validate()?;
        Ok(self)
    }

    /// The direction toward a fixed light in the volume's physical space
    /// (unit), or None for the headlight.
    pub fn light_dir(&self) -> Option<[f32; 3]> {
        match self.light {
            Light::Headlight => None,
            Light::Fixed {
                azimuth_deg,
                elevation_deg,
            } => {
                let (sa, ca) = azimuth_deg.to_radians().sin_cos();
                let (se, ce) = elevation_deg.to_radians().sin_cos();
                Some([(ce * sa) as f32, se as f32, (ce * ca) as f32])
            }
        }
    }
}

/// `shininess` where it is a whole number from 1 to 128, else 0: the
/// exponents a lit sample raises to by repeated squaring.
pub fn whole_exponent(shininess: f32) -> u32 {
    match shininess.fract() == 0.0 && (1.0..=128.0).contains(&shininess) {
        true => shininess as u32,
        false => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::{Light, Shading};

    #[test]
    fn a_fixed_light_is_described_as_given() {
        let shading = Shading {
            light: Light::parse("45,30.1").unwrap(),
            ..Shading::default()
        };
        assert!(
            shading.describe().starts_with("light 45,30.1, phong "),
            "{}",
            shading.describe()
        );
    }
}
