//! Turbulence: four octaves of smooth value noise (fBm). The sum is symmetric
//! about 0.5, so its default ramp starting at 0.5 shows about half the voxels.
//! Over time each octave drifts through the noise, finer ones faster, so
//! the field evolves rather than slides.

use std::ops::Range;

fn hash(x: i64, y: i64, z: i64, seed: u64) -> f32 {
    let mut h = seed
        ^ (x as u64).wrapping_mul(0x8DA6_B343)
        ^ (y as u64).wrapping_mul(0xD816_3841)
        ^ (z as u64).wrapping_mul(0xCB1A_B31F);
    h = (h ^ (h >> 33)).wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h = (h ^ (h >> 33)).wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^= h >> 33;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

fn smooth(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

fn value_noise(p: [f32; 3], seed: u64) -> f32 {
    let i = p.map(|c| c.floor());
    let f = [0, 1, 2].map(|a| smooth(p[a] - i[a]));
    let [ix, iy, iz] = i.map(|c| c as i64);
    let mut acc = 0.0;
    for dz in 0..2 {
        for dy in 0..2 {
            for dx in 0..2 {
                let w = (if dx == 1 { f[0] } else { 1.0 - f[0] })
                    * (if dy == 1 { f[1] } else { 1.0 - f[1] })
                    * (if dz == 1 { f[2] } else { 1.0 - f[2] });
                acc += w * hash(ix + dx, iy + dy, iz + dz, seed);
            }
        }
    }
    acc
}

/// How far octave 0 drifts a step, in noise cells (4 across the volume).
const DRIFT: [f32; 3] = [0.05, 0.03, 0.02];

/// Layers `layers` (z) of the volume, x fastest.
pub fn generate(dims: [u32; 3], seed: u64, time: u32, layers: Range<u32>) -> Vec<u8> {
    let n = dims.into_iter().max().unwrap_or(1) as f32;
    super::fill(dims, layers, |x, y, z| {
        let p = [x, y, z].map(|c| (c as f32 + 0.5) / n * 4.0);
        let (mut sum, mut amp, mut norm, mut freq) = (0.0f32, 1.0f32, 0.0f32, 1.0f32);
        for octave in 0..4u64 {
            let drift = DRIFT.map(|d| d * time as f32 * (octave + 1) as f32);
            let q = [0, 1, 2].map(|a| p[a] * freq + drift[a]);
            sum += amp * value_noise(q, seed.wrapping_add(octave * 0x1000_0001));
            norm += amp;
            amp *= 0.5;
            freq *= 2.0;
        }
        let v = sum / norm;
        // Stretch the contrast of the sum (which clusters near 0.5) about 0.5.
        (((v - 0.5) * 2.5 + 0.5).clamp(0.0, 1.0) * 255.0).round() as u8
    })
}
