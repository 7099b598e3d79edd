//! N-body analog: particles in Plummer-like clusters, deposited with
//! cloud-in-cell weights into a density field, stored as log density. Sizes
//! and counts scale with the volume, so occupancy does not depend on size.
//! Over time each cluster drifts at its own velocity (up to about 0.6 % of
//! the volume a step), so the visible set crosses brick faces.

use super::Rng;

const CLUSTERS: usize = 48;
/// Particles per voxel of the volume (spread over all clusters).
const PARTICLES_PER_VOXEL: f64 = 0.03;

pub fn generate(dims: [u32; 3], seed: u64, time: u32) -> Vec<u8> {
    let n = dims.map(|d| d as f64);
    let size = n[0].max(n[1]).max(n[2]);
    let voxels = n[0] * n[1] * n[2];
    let mut rng = Rng::new(seed);
    let mut density = vec![0f32; voxels as usize];
    let total = (voxels * PARTICLES_PER_VOXEL).ceil() as usize;
    // Cluster masses follow a steep power law: a few big, many small.
    let weights: Vec<f64> = (0..CLUSTERS).map(|_| rng.uniform().powf(3.0) + 0.02).collect();
    let sum: f64 = weights.iter().sum();
    // Velocities from their own stream, so step 0 is the still volume.
    let mut motion = Rng::new(seed ^ 0x005E_ED0F_71AE);
    let velocities: Vec<[f64; 3]> = (0..CLUSTERS)
        .map(|_| [motion.normal(), motion.normal(), motion.normal()].map(|v| v * size * 0.0035 * time as f64))
        .collect();
    let idx = |x: usize, y: usize, z: usize| x + dims[0] as usize * (y + dims[1] as usize * z);
    for (w, shift) in weights.iter().zip(&velocities) {
        let start = n.map(|d| d * (0.15 + 0.7 * rng.uniform()));
        let centre = [0, 1, 2].map(|a| start[a] + shift[a]);
        let scale = size * (0.004 + 0.012 * rng.uniform());
        let count = (total as f64 * w / sum).round() as usize;
        for _ in 0..count {
            // Plummer radius from the inverse CDF, capped to keep halos bounded.
            let u = rng.uniform().clamp(1e-6, 0.99);
            let r = scale / (u.powf(-2.0 / 3.0) - 1.0).sqrt();
            let dir = [rng.normal(), rng.normal(), rng.normal()];
            let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt().max(1e-12);
            let p: [f64; 3] = [0, 1, 2].map(|a| centre[a] + r * dir[a] / len - 0.5);
            if (0..3).any(|a| p[a] < 0.0 || p[a] > n[a] - 1.0) {
                continue;
            }
            let i = p.map(|c| c.floor() as usize);
            let f = [0, 1, 2].map(|a| p[a] - i[a] as f64);
            for dz in 0..2 {
                for dy in 0..2 {
                    for dx in 0..2 {
                        let (x, y, z) = (i[0] + dx, i[1] + dy, i[2] + dz);
                        if x < dims[0] as usize && y < dims[1] as usize && z < dims[2] as usize {
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
    density
        .iter()
        .map(|&d| ((1.0 + d).log2() * 48.0).round().min(255.0) as u8)
        .collect()
}
