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
use std::ops::Range;

/// The built-in volume generators (`NAME:SIZE[:PARAM]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Generator {
    /// Menger sponge (PARAM: level, default 3 or the finest the size resolves):
    /// empty space inside the volume.
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

/// Bytes of u8 voxels a stream makes at once (whole layers, at least one).
const SLAB_BYTES: u64 = 64 << 20;

/// Time steps of every generator's animation (`generate_at`).
pub const STEPS: u32 = 64;

/// The largest seed a spec can name exactly (2^53).
const MAX_SEED: f64 = 9_007_199_254_740_992.0;

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
    /// (`volume::PoolStream`): every generator makes its volume a slab of
    /// layers at a time (the nbody generator its density too), so the host
    /// holds the stored bricks, not the dense volume, and a rank makes only
    /// its own layers (`StreamTo::across`). The voxels are those of
    /// `generate_at`, bit for bit.
    pub fn generate_bricks(self, dims: [u32; 3], param: Option<f64>, time: u32, to: &StreamTo) -> Result<Volume> {
        self.generate_as(dims, param, time, Some(to))
    }

    fn generate_as(self, dims: [u32; 3], param: Option<f64>, time: u32, bricks: Option<&StreamTo>) -> Result<Volume> {
        if time >= STEPS {
            return Err(Error::invalid(
                "time",
                time.to_string(),
                format!("a generator has {STEPS} steps, 0 to {}", STEPS - 1),
            ));
        }
        let n = super::check_dims(dims, self.name())?;
        let [w, h, d] = dims;
        let layer = w as u64 * h as u64;
        let per_slab = (SLAB_BYTES / layer).clamp(1, d as u64) as u32;
        // The u8 voxels (a stream's slab of them), and the n-body's slabs of
        // f32 density beside them.
        let voxels = if bricks.is_some() { per_slab as u64 * layer } else { n };
        let peak = match self {
            Generator::Nbody => nbody::peak_bytes(n) - n + voxels,
            _ => voxels,
        };
        crate::limits::check_host(format_args!("volume {}:{w}x{h}x{d}", self.name()), peak, 1)?;
        let bad = |why: &str| {
            Error::invalid(
                "generator parameter",
                // Past 1e15 in exponent form: the f64 read, not a rounded
                // integer that looks like the one given.
                format!("{}:{}", self.name(), crate::error::number(param.unwrap_or(0.0))),
                why.to_string(),
            )
        };
        let seed = |p: Option<f64>| -> Result<u64> {
            match p {
                None => Ok(1),
                // Up to 2^53, where every integer is its own f64: a larger
                // one would alias its neighbours' seeds.
                Some(v) if (0.0..=MAX_SEED).contains(&v) && v.fract() == 0.0 => Ok(v as u64),
                Some(_) => Err(bad("the seed must be an integer from 0 to 2^53")),
            }
        };
        // Layers of the volume, its parameter checked.
        let layers: Box<dyn Fn(Range<u32>) -> Vec<u8>> = match self {
            Generator::Menger => {
                let finest = menger::finest_level(dims);
                let level = param.unwrap_or(menger::DEFAULT_LEVEL.min(finest) as f64);
                if !((0.0..=12.0).contains(&level) && level.fract() == 0.0) {
                    return Err(bad("the Menger level must be an integer in 0..=12"));
                }
                if level as u32 > finest {
                    return Err(bad(&format!(
                        "level {level} needs at least 3^{level} = {} voxels a side; {w}x{h}x{d} resolves levels up to {finest}",
                        3u64.pow(level as u32)
                    )));
                }
                Box::new(move |z| menger::generate(dims, level as u32, time, z))
            }
            Generator::Nbody => {
                let seed = seed(param)?;
                let data = match bricks {
                    Some(to) => VoxelData::Bricks(std::sync::Arc::new(to.run(dims, 1, |stream, z| {
                        nbody::stream(dims, seed, time, z, |slab| stream.push(slab))
                    })?)),
                    None => VoxelData::U8(nbody::generate(dims, seed, time)),
                };
                return self.named(dims, param, data);
            }
            Generator::Vessels => {
                let seed = seed(param)?;
                Box::new(move |z| vessels::generate(dims, seed, time, z))
            }
            Generator::Turbulence => {
                let seed = seed(param)?;
                Box::new(move |z| turbulence::generate(dims, seed, time, z))
            }
            Generator::Shells => {
                let count = param.unwrap_or(4.0);
                if !((1.0..=64.0).contains(&count) && count.fract() == 0.0) {
                    return Err(bad("the shell count must be an integer in 1..=64"));
                }
                Box::new(move |z| shells::generate(dims, count as u32, time, z))
            }
        };
        let data = match bricks {
            None => VoxelData::U8(layers(0..d)),
            Some(to) => VoxelData::Bricks(std::sync::Arc::new(to.run(dims, 1, |stream, z| {
                let mut at = z.start;
                while at < z.end {
                    let end = (at + per_slab).min(z.end);
                    stream.push(&layers(at..end))?;
                    at = end;
                }
                Ok(())
            })?)),
        };
        self.named(dims, param, data)
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

/// Layers `layers` (z) of a u8 volume from `f(x, y, z)`, in parallel over
/// z-slices.
pub(crate) fn fill(dims: [u32; 3], layers: Range<u32>, f: impl Fn(u32, u32, u32) -> u8 + Sync) -> Vec<u8> {
    let [w, h, _] = dims;
    let slice = w as usize * h as usize;
    let mut data = vec![0u8; slice * layers.len()];
    data.par_chunks_mut(slice).enumerate().for_each(|(i, out)| {
        let z = layers.start + i as u32;
        for y in 0..h {
            for x in 0..w {
                out[x as usize + y as usize * w as usize] = f(x, y, z);
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
