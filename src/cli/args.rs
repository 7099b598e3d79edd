//! Arguments `render`, `view` and `bench` share: the frame (camera, step,
//! early termination, sample filter) and the structure (`--accel` and every
//! structure's parameters, as flags made from their schemas).

use super::look::LookArgs;
use clap::builder::{PossibleValue, TypedValueParser};
use clap::{Arg, ArgMatches, Args, Command, FromArgMatches};
use lacuna::accel::table::{params_for, shared_params, SharedParam};
use lacuna::accel::{Accel, Builder, Params, TABLE};
use lacuna::gpu::Context;
use lacuna::render::{Filter, FrameBuilder, FrameDesc, Orbit, Projection, DEFAULT_STEP};
use lacuna::Result;

/// The frame's options besides its size (whose default differs per command).
#[derive(Args, Clone)]
pub struct FrameArgs {
    /// Orbit camera AZIMUTH,ELEVATION in degrees.
    #[arg(long, default_value_t = Angles::default(), allow_hyphen_values = true)]
    pub camera: Angles,
    /// Perspective projection with this vertical field of view (degrees); default orthographic.
    #[arg(long, allow_hyphen_values = true)]
    pub perspective: Option<f64>,
    /// Perspective eye distance from the centre, in bounding-sphere radii (default: fit).
    #[arg(long, requires = "perspective", allow_hyphen_values = true)]
    pub distance: Option<f64>,
    /// Sample step in voxels.
    #[arg(long, default_value_t = DEFAULT_STEP, allow_hyphen_values = true)]
    pub step: f32,
    /// Early ray termination at this accumulated alpha (default off).
    #[arg(long, allow_hyphen_values = true)]
    pub ert: Option<f32>,
    /// Sample filter: manual (eight texel fetches, f32 weights) or hardware (the sampler's linear filtering; default where the volume's format supports it).
    #[arg(long)]
    pub filter: Option<Filter>,
    #[command(flatten)]
    pub look: LookArgs,
}

impl FrameArgs {
    /// The frame's builder at `size` with these options (not yet validated
    /// together: `build` does).
    pub fn builder(&self, size: (u32, u32)) -> Result<FrameBuilder> {
        let projection = match self.perspective {
            Some(fov_deg) => Projection::Perspective {
                fov_deg,
                distance: self.distance,
            },
            None => Projection::Orthographic,
        };
        let b = FrameDesc::builder(size.0, size.1)
            .orbit(self.camera.0, self.camera.1, projection)
            .step(self.step)
            .ert(self.ert);
        let b = match self.filter {
            Some(f) => b.filter(f),
            None => b,
        };
        self.look.apply(b)
    }

    /// The validated frame at `size`.
    pub fn desc(&self, size: (u32, u32)) -> Result<FrameDesc> {
        self.builder(size)?.build()
    }
}

/// `--camera AZIMUTH,ELEVATION` in degrees; its default is the frame's
/// (`Orbit::default`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angles(pub f64, pub f64);

impl Default for Angles {
    fn default() -> Self {
        let o = Orbit::default();
        Angles(o.azimuth_deg, o.elevation_deg)
    }
}

impl std::fmt::Display for Angles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{}", self.0, self.1)
    }
}

impl std::str::FromStr for Angles {
    type Err = lacuna::Error;
    fn from_str(s: &str) -> Result<Self> {
        Orbit::parse_orbit(s).map(|(a, e)| Angles(a, e))
    }
}

/// `--accel NAME`: a structure of the table; `--help` lists them.
#[derive(Clone)]
pub struct AccelParser;

impl TypedValueParser for AccelParser {
    type Value = Accel;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &std::ffi::OsStr) -> Result<Accel, clap::Error> {
        let text = value.to_string_lossy();
        text.parse::<Accel>().map_err(|e| {
            let arg = arg.map_or("--accel".to_string(), |a| a.to_string());
            clap::Error::raw(
                clap::error::ErrorKind::InvalidValue,
                format!("invalid value '{text}' for '{arg}': {e}\n"),
            )
            .with_cmd(cmd)
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            TABLE
                .iter()
                .map(|a| PossibleValue::new(a.name()).help(a.method().description())),
        ))
    }
}

/// Every structure's parameters as `--NAME VALUE` flags, made from their
/// schemas; the values given, by name.
#[derive(Clone, Debug, Default)]
pub struct StructureArgs {
    given: Vec<(&'static str, String)>,
}

impl StructureArgs {
    /// `accel`'s parameters: its defaults with the values given, checked
    /// (every flag's value is checked; flags of other structures' parameters
    /// are then left out).
    pub fn params(&self, accel: Accel) -> Result<Params> {
        let given: Vec<(&str, &str)> = self.given.iter().map(|(n, v)| (*n, v.as_str())).collect();
        params_for(accel, &given)
    }

    fn schema() -> Vec<SharedParam> {
        // The table's parameters agree by construction (a test checks it);
        // a disagreement leaves the flags out rather than fail `--help`.
        shared_params(TABLE).unwrap_or_default()
    }
}

impl FromArgMatches for StructureArgs {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Vec::new();
        for p in Self::schema() {
            if let Some(v) = matches.get_one::<String>(p.param.name) {
                given.push((p.param.name, v.clone()));
            }
        }
        Ok(StructureArgs { given })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl Args for StructureArgs {
    fn augment_args(mut cmd: Command) -> Command {
        for p in Self::schema() {
            cmd = cmd.arg(
                Arg::new(p.param.name)
                    .long(p.param.name)
                    .value_name("VALUE")
                    .allow_hyphen_values(true)
                    .help(p.help())
                    .help_heading("Structure parameters"),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// How `auto` gets the device's kernel constants.
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct ModelArgs {
    /// auto: measure the device's kernel constants again and rewrite their cache
    /// ($XDG_CACHE_HOME/lacuna, else ~/.cache/lacuna).
    #[arg(long)]
    pub recalibrate: bool,
}

impl ModelArgs {
    /// A builder whose auto keeps its kernel constants in the cache folder
    /// (measured there again with `--recalibrate`).
    pub fn builder(&self, ctx: &Context) -> Result<Builder> {
        let builder = Builder::new(ctx)?;
        builder.use_cost_cache(lacuna::accel::auto::cache::default_folder())?;
        if self.recalibrate {
            builder.recalibrate()?;
        }
        Ok(builder)
    }
}
