//! N-body analog: particles in Plummer-like clusters, deposited with
//! cloud-in-cell weights into a density field, stored as log density. Sizes
//! and counts scale with the volume, so occupancy does not depend on size.
//! Over time each cluster drifts at its own velocity (up to about 0.6 % of
//! the volume a step), so the visible set crosses brick faces.
//!
//! The density field is made one z-slab at a time, so its f32 values never
//! exist for the whole volume (nbody:2048 would need 32 GiB of them): a
//! first pass lists, per slab, the particles that deposit into it; a second
//! recomputes each listed particle (its random draws are found by jumping
//! the generator ahead: every particle takes the same draws) and deposits
//! it. Each voxel receives its particles in the same order as one pass over
//! the whole volume, so the values are the same bit for bit.

use super::Rng;
use rayon::prelude::*;
use std::ops::Range;

const CLUSTERS: usize = 48;
/// Particles per voxel of the volume (spread over all clusters).
const PARTICLES_PER_VOXEL: f64 = 0.03;
/// Random draws per particle: a uniform and three normals.
const DRAWS_PER_PARTICLE: u64 = 7;
/// The largest Plummer radius over `scale`: u capped at 0.99.
const MAX_RADIUS: f64 = 12.5;
/// Bytes of f32 density one slab holds at most (two are made at once).
const SLAB_BYTES: u64 = 256 << 20;

struct Cluster {
    centre: [f64; 3],
    scale: f64,
    count: usize,
    /// The generator before the cluster's first particle.
    rng: Rng,
}

/// Host bytes the generation takes at its peak for `voxels` voxels: the u8
/// volume, the slab lists (a u32 per particle, 0.03 a voxel, some twice)
/// and two slabs of f32 density at once.
pub fn peak_bytes(voxels: u64) -> u64 {
    let slabs = (2 * SLAB_BYTES).min(4 * voxels);
    voxels + voxels / 4 + slabs
}

fn clusters(dims: [u32; 3], seed: u64, time: u32) -> Vec<Cluster> {
    let n = dims.map(|d| d as f64);
    let size = n[0].max(n[1]).max(n[2]);
    let voxels = n[0] * n[1] * n[2];
    let mut rng = Rng::new(seed);
    let total = (voxels * PARTICLES_PER_VOXEL).ceil() as usize;
    // Cluster masses follow a steep power law: a few big, many small.
    let weights: Vec<f64> = (0..CLUSTERS).map(|_| rng.uniform().powf(3.0) + 0.02).collect();
    let sum: f64 = weights.iter().sum();
    // Velocities from their own stream, so step 0 is the still volume.
    let mut motion = Rng::new(seed ^ 0x005E_ED0F_71AE);
    let velocities: Vec<[f64; 3]> = (0..CLUSTERS)
        .map(|_| [motion.normal(), motion.normal(), motion.normal()].map(|v| v * size * 0.0035 * time as f64))
        .collect();
    let mut out = Vec::with_capacity(CLUSTERS);
    for (w, shift) in weights.iter().zip(&velocities) {
        let start = n.map(|d| d * (0.15 + 0.7 * rng.uniform()));
        let centre = [0, 1, 2].map(|a| start[a] + shift[a]);
        let scale = size * (0.004 + 0.012 * rng.uniform());
        let count = (total as f64 * w / sum).round() as usize;
        out.push(Cluster {
            centre,
            scale,
            count,
            rng: rng.clone(),
        });
        rng.skip(count as u64 * DRAWS_PER_PARTICLE);
    }
    out
}

/// Particle `j` of cluster `c`: its position (voxel units, minus 0.5), or
/// None where it falls outside the volume.
fn particle(c: &Cluster, j: usize, n: [f64; 3]) -> Option<[f64; 3]> {
    let mut rng = c.rng.clone();
    rng.skip(j as u64 * DRAWS_PER_PARTICLE);
    // Plummer radius from the inverse CDF, capped to keep halos bounded.
    let u = rng.uniform().clamp(1e-6, 0.99);
    let r = c.scale / (u.powf(-2.0 / 3.0) - 1.0).sqrt();
    let dir = [rng.normal(), rng.normal(), rng.normal()];
    let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt().max(1e-12);
    let p: [f64; 3] = [0, 1, 2].map(|a| c.centre[a] + r * dir[a] / len - 0.5);
    (!(0..3).any(|a| p[a] < 0.0 || p[a] > n[a] - 1.0)).then_some(p)
}

pub fn generate(dims: [u32; 3], seed: u64, time: u32) -> Vec<u8> {
    generate_in_slabs(dims, seed, time, SLAB_BYTES)
}

/// As `generate`, with slabs of at most `slab_bytes` of density.
fn generate_in_slabs(dims: [u32; 3], seed: u64, time: u32, slab_bytes: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(dims.iter().map(|&d| d as usize).product());
    let collect: crate::Result<()> = for_each_slab(dims, seed, time, 0..dims[2], slab_bytes, |slab| {
        out.extend_from_slice(slab);
        Ok(())
    });
    debug_assert!(collect.is_ok());
    out
}

/// The volume's z-layers `layers` (the whole volume's values, bit for bit),
/// in order and in whole layers, to `sink` (which may stop it with an
/// error): the host holds two slabs of voxels and their density, not the
/// volume (`volume::PoolStream`), and a rank makes only its block's layers.
pub fn stream(
    dims: [u32; 3],
    seed: u64,
    time: u32,
    layers: Range<u32>,
    sink: impl FnMut(&[u8]) -> crate::Result<()>,
) -> crate::Result<()> {
    for_each_slab(dims, seed, time, layers, SLAB_BYTES, sink)
}

fn for_each_slab(
    dims: [u32; 3],
    seed: u64,
    time: u32,
    layers: Range<u32>,
    slab_bytes: u64,
    mut sink: impl FnMut(&[u8]) -> crate::Result<()>,
) -> crate::Result<()> {
    let n = dims.map(|d| d as f64);
    let clusters = clusters(dims, seed, time);
    let layer = dims[0] as usize * dims[1] as usize;
    let depth = (slab_bytes / (4 * layer as u64)).clamp(1, dims[2] as u64) as u32;
    let slabs = dims[2].div_ceil(depth) as usize;
    let layers = layers.start.min(dims[2])..layers.end.min(dims[2]);
    // The slabs that hold `layers`.
    let wanted = (layers.start / depth) as usize..layers.end.div_ceil(depth) as usize;
    // Pass 1, per cluster: the particles depositing into each wanted slab
    // (a particle at z deposits into layers floor(z) and floor(z) + 1).
    let lists: Vec<Vec<Vec<u32>>> = clusters
        .par_iter()
        .map(|c| {
            let mut per_slab = vec![Vec::new(); slabs];
            // A cluster far from every wanted layer lists nothing; skipping
            // it here only saves the draws.
            let reach = c.scale * MAX_RADIUS + 2.0;
            if c.centre[2] + reach < layers.start as f64 || c.centre[2] - reach > layers.end as f64 {
                return per_slab;
            }
            for j in 0..c.count {
                if let Some(p) = particle(c, j, n) {
                    let z = p[2].floor() as u32;
                    let (a, b) = ((z / depth) as usize, ((z + 1).min(dims[2] - 1) / depth) as usize);
                    if wanted.contains(&a) {
                        per_slab[a].push(j as u32);
                    }
                    if b != a && wanted.contains(&b) {
                        per_slab[b].push(j as u32);
                    }
                }
            }
            per_slab
        })
        .collect();
    // Pass 2, per slab: deposit its particles in cluster and particle
    // order, then store the log density. Two slabs at a time, whatever
    // the thread count, as `peak_bytes` counts.
    let slab = layer * depth as usize;
    let total = layer * dims[2] as usize;
    let mut pair_buf = vec![0u8; (2 * slab).min(total)];
    for pair in wanted.clone().step_by(2) {
        let z_pair = pair * depth as usize;
        let pair_layers = z_pair..(z_pair + 2 * depth as usize).min(dims[2] as usize);
        let pair_layers = pair_layers.start..pair_layers.end.min(wanted.end * depth as usize);
        let out = &mut pair_buf[..pair_layers.len() * layer];
        out.par_chunks_mut(slab).enumerate().for_each(|(half, out)| {
            let s = pair + half;
            let z0 = s * depth as usize;
            let mut density = vec![0f32; out.len()];
            let idx = |x: usize, y: usize, z: usize| x + dims[0] as usize * (y + dims[1] as usize * (z - z0));
            let in_slab = z0..z0 + out.len() / layer;
            for (c, per_slab) in clusters.iter().zip(&lists) {
                // Listed particles are inside: pass 1 found them so.
                for p in per_slab[s].iter().filter_map(|&j| particle(c, j as usize, n)) {
                    let i = p.map(|c| c.floor() as usize);
                    let f = [0, 1, 2].map(|a| p[a] - i[a] as f64);
                    for dz in 0..2 {
                        for dy in 0..2 {
                            for dx in 0..2 {
                                let (x, y, z) = (i[0] + dx, i[1] + dy, i[2] + dz);
                                if x < dims[0] as usize && y < dims[1] as usize && in_slab.contains(&z) {
                                    let wgt = (if dx == 1 { f[0] } else { 1.0 - f[0] })
                                        * (if dy == 1 { f[1] } else { 1.0 - f[1] })
                                        * (if dz == 1 { f[2] } else { 1.0 - f[2] });
                                    density[idx(x, y, z)] += wgt as f32;
                                }
                            }
                        }
                    }
                }
            }
            for (o, &d) in out.iter_mut().zip(&density) {
                *o = ((1.0 + d).log2() * 48.0).round().min(255.0) as u8;
            }
        });
        // The pair's layers within `layers`.
        let from = (layers.start as usize).max(pair_layers.start) - pair_layers.start;
        let to = (layers.end as usize).min(pair_layers.end) - pair_layers.start;
        sink(&out[from * layer..to * layer])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fnv1a(bytes: &[u8]) -> u64 {
        bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
        })
    }

    #[test]
    fn the_volumes_are_those_of_the_one_pass_generator() {
        // FNV-1a of nbody:64 steps 0 and 5 as the one-pass generator (before
        // slabs) made them: generators are stable forever.
        assert_eq!(fnv1a(&generate([64; 3], 1, 0)), 0xdd6d_86bf_865a_13e1);
        assert_eq!(fnv1a(&generate([64; 3], 1, 5)), 0x5ac8_e974_4c14_a480);
        assert_eq!(fnv1a(&generate([37, 50, 41], 7, 0)), 0xe260_4167_5b18_47e7);
    }

    #[test]
    fn slabs_of_any_depth_make_the_same_volume() {
        let dims = [37, 30, 41];
        let whole = generate_in_slabs(dims, 3, 4, u64::MAX);
        assert!(whole.iter().filter(|&&v| v > 0).count() > 500, "particles landed");
        // One layer, three (41 is not a multiple), and a slab past the end.
        for layers in [1, 3, 40] {
            let slabs = generate_in_slabs(dims, 3, 4, layers * 4 * 37 * 30);
            assert!(slabs == whole, "slabs of {layers} layers");
        }
        // Any run of layers is the whole volume's, in slabs of any depth
        // (runs that start and end inside a slab, or across several).
        let layer = 37 * 30;
        for (run, depth) in [(0..41, 3), (5..6, 3), (7..29, 4), (16..41, 16), (2..40, 40)] {
            let mut got = Vec::new();
            for_each_slab(dims, 3, 4, run.clone(), depth * 4 * layer as u64, |s| {
                assert!(s.len().is_multiple_of(layer) && !s.is_empty());
                got.extend_from_slice(s);
                Ok(())
            })
            .unwrap();
            let want = &whole[run.start as usize * layer..run.end as usize * layer];
            assert!(got == want, "layers {run:?} in slabs of {depth}");
        }
    }
}
