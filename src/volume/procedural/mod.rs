//! Deterministic procedural volumes, analogs of the paper's data sets, at any
//! size. Each generator has a default transfer function under which its
//! occupancy resembles the data set it imitates, and animates over
//! `STEPS` time steps (`generate_at`): particles move, tubes grow,
//! turbulence evolves, the sponge slides, shells expand. Step 0 is the
//! still volume.

mod menger;
mod nbody;
mod shells;
mod turbulence;
mod vessels;

use super::{StreamTo, Volume, VoxelData, VoxelType};
use crate::error::{Error, Result};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Generator {
    /// Menger sponge (PARAM: level, default 3): empty space inside the volume.
    Menger,
    /// Clustered particles splatted into a density field (PARAM: seed): ~0.15 % visible.
    Nbody,
    /// Sparse branching tubes (PARAM: seed): ~1 % visible.
    Vessels,
    /// Noise field (PARAM: seed): ~50 % visible.
    Turbulence,
    /// Thin concentric spherical shells (PARAM: count, default 4).
    Shells,
}

/// Time steps of every generator's animation (`generate_at`).
pub const STEPS: u32 = 64;

impl Generator {
    pub const ALL: [Generator; 5] = [
        Generator::Menger,
        Generator::Nbody,
        Generator::Vessels,
        Generator::Turbulence,
        Generator::Shells,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Generator::Menger => "menger",
            Generator::Nbody => "nbody",
            Generator::Vessels => "vessels",
            Generator::Turbulence => "turbulence",
            Generator::Shells => "shells",
        }
    }

    pub fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|g| g.name()).collect()
    }

    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == s)
    }

    /// The transfer function spec this generator's occupancy is tuned for.
    pub fn default_tf(self) -> &'static str {
        match self {
            Generator::Menger => "ramp:0.3:1:0.2",
            Generator::Nbody => "ramp:0.35:1",
            Generator::Vessels => "ramp:0.3:1",
            Generator::Turbulence => "ramp:0.49:1:0.2",
            Generator::Shells => "ramp:0.2:1:0.8",
        }
    }

    /// The still volume (step 0 of its animation).
    pub fn generate(self, dims: [u32; 3], param: Option<f64>) -> Result<Volume> {
        self.generate_at(dims, param, 0)
    }

    /// Step `time` (below `STEPS`) of its animation.
    pub fn generate_at(self, dims: [u32; 3], param: Option<f64>, time: u32) -> Result<Volume> {
        self.generate_as(dims, param, time, None)
    }

    /// As `generate_at`, streamed into bricks as `to` says
    /// (`volume::PoolStream`) where the generator makes its volume
    /// in slabs (nbody): the host then holds the stored bricks, not the
    /// dense volume. The others are made whole (their upload plans the pool).
    pub fn generate_bricks(self, dims: [u32; 3], param: Option<f64>, time: u32, to: &StreamTo) -> Result<Volume> {
        self.generate_as(dims, param, time, Some(to))
    }

    fn generate_as(self, dims: [u32; 3], param: Option<f64>, time: u32, bricks: Option<&StreamTo>) -> Result<Volume> {
        let streamed = bricks.filter(|_| self == Generator::Nbody);
        if time >= STEPS {
            return Err(Error::invalid(
                "time",
                time.to_string(),
                format!("a generator has {STEPS} steps, 0 to {}", STEPS - 1),
            ));
        }
        let n = super::check_dims(dims, self.name())?;
        // The u8 voxels, and the n-body's slabs of f32 density beside them.
        let peak = match (self, streamed) {
            (Generator::Nbody, Some(_)) => nbody::peak_bytes(n) - n,
            (Generator::Nbody, None) => nbody::peak_bytes(n),
            _ => n,
        };
        let [w, h, d] = dims;
        crate::limits::check_host(format_args!("volume {}:{w}x{h}x{d}", self.name()), peak, 1)?;
        let bad = |why: &str| {
            Error::invalid(
                "generator parameter",
                format!("{}:{}", self.name(), param.unwrap_or(0.0)),
                why.to_string(),
            )
        };
        let seed = |p: Option<f64>| -> Result<u64> {
            match p {
                None => Ok(1),
                Some(v) if v >= 0.0 && v.fract() == 0.0 => Ok(v as u64),
                Some(_) => Err(bad("the seed must be a non-negative integer")),
            }
        };
        let data = match self {
            Generator::Menger => {
                let level = param.unwrap_or(3.0);
                if !((0.0..=12.0).contains(&level) && level.fract() == 0.0) {
                    return Err(bad("the Menger level must be an integer in 0..=12"));
                }
                menger::generate(dims, level as u32, time)
            }
            Generator::Nbody => match streamed {
                Some(to) => {
                    let seed = seed(param)?;
                    let pool = to.run(dims, 1, |stream, layers| {
                        nbody::stream(dims, seed, time, layers, |slab| stream.push(slab))
                    })?;
                    return self.named(dims, param, VoxelData::Bricks(std::sync::Arc::new(pool)));
                }
                None => nbody::generate(dims, seed(param)?, time),
            },
            Generator::Vessels => vessels::generate(dims, seed(param)?, time),
            Generator::Turbulence => turbulence::generate(dims, seed(param)?, time),
            Generator::Shells => {
                let count = param.unwrap_or(4.0);
                if !((1.0..=64.0).contains(&count) && count.fract() == 0.0) {
                    return Err(bad("the shell count must be an integer in 1..=64"));
                }
                shells::generate(dims, count as u32, time)
            }
        };
        self.named(dims, param, VoxelData::U8(data))
    }

    /// The volume of `data`, named by its spec, with the default TF.
    fn named(self, dims: [u32; 3], param: Option<f64>, data: VoxelData) -> Result<Volume> {
        let name = match param {
            Some(p) => format!("{}:{}x{}x{}:{}", self.name(), dims[0], dims[1], dims[2], p),
            None => format!("{}:{}x{}x{}", self.name(), dims[0], dims[1], dims[2]),
        };
        let mut volume = Volume::new(name, dims, [1.0; 3], VoxelType::U8, data)?;
        volume.default_tf = Some(self.default_tf().to_string());
        Ok(volume)
    }
}

/// Fills a u8 volume in parallel over z-slices from `f(x, y, z)`.
pub(crate) fn fill(dims: [u32; 3], f: impl Fn(u32, u32, u32) -> u8 + Sync) -> Vec<u8> {
    let [w, h, d] = dims;
    let slice = w as usize * h as usize;
    let mut data = vec![0u8; slice * d as usize];
    data.par_chunks_mut(slice).enumerate().for_each(|(z, out)| {
        for y in 0..h {
            for x in 0..w {
                out[x as usize + y as usize * w as usize] = f(x, y, z as u32);
            }
        }
    });
    data
}

/// SplitMix64: small, fast, and stable across versions (unlike crate RNGs
/// whose streams may change), so volumes are reproducible forever.
#[derive(Clone)]
pub(crate) struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    /// Jumps `draws` draws ahead (a SplitMix64 state only adds a constant
    /// a draw).
    pub fn skip(&mut self, draws: u64) {
        self.0 = self.0.wrapping_add(draws.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}
