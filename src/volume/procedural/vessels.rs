//! Vessel tree analog: a branching random walk of tapered tubes grown from
//! the bottom of the volume, rasterised with a soft radial profile. Over
//! time the tubes grow thicker, 5 % of their radius a step.

use std::ops::Range;

use super::Rng;

struct Segment {
    a: [f32; 3],
    b: [f32; 3],
    radius: f32,
}

fn grow(rng: &mut Rng, out: &mut Vec<Segment>, start: [f32; 3], dir: [f32; 3], radius: f32, depth: u32) {
    let mut p = start;
    let mut d = dir;
    let steps = 6 + (rng.uniform() * 6.0) as u32;
    for step in 0..steps {
        let len = 0.035 + 0.02 * rng.uniform() as f32;
        let jitter = [rng.normal(), rng.normal(), rng.normal()].map(|v| v as f32 * 0.25);
        let mut nd = [0, 1, 2].map(|a| d[a] + jitter[a]);
        let l = (nd[0] * nd[0] + nd[1] * nd[1] + nd[2] * nd[2]).sqrt().max(1e-6);
        nd = nd.map(|c| c / l);
        let q = [0, 1, 2].map(|a| p[a] + nd[a] * len);
        if q.iter().any(|&c| !(0.03..=0.97).contains(&c)) {
            return;
        }
        out.push(Segment { a: p, b: q, radius });
        p = q;
        d = nd;
        if depth < 6 && step >= 2 && rng.uniform() < 0.3 {
            let side = [rng.normal(), rng.normal(), rng.normal()].map(|v| v as f32);
            let bd = [0, 1, 2].map(|a| d[a] + side[a] * 0.9);
            grow(rng, out, p, bd, radius * 0.75, depth + 1);
        }
    }
}

/// Layers `layers` (z) of the volume, x fastest: each tube segment is
/// drawn where it meets them (a voxel keeps its largest value, in any order).
pub fn generate(dims: [u32; 3], seed: u64, time: u32, layers: Range<u32>) -> Vec<u8> {
    let growth = 1.0 + 0.05 * time as f32;
    let mut rng = Rng::new(seed);
    let mut segments = Vec::new();
    for _ in 0..3 {
        let start = [
            0.35 + 0.3 * rng.uniform() as f32,
            0.35 + 0.3 * rng.uniform() as f32,
            0.05,
        ];
        grow(&mut rng, &mut segments, start, [0.0, 0.0, 1.0], 0.018, 0);
    }
    let scale = dims.map(|d| d as f32);
    let segs: Vec<([f32; 3], [f32; 3], f32)> = segments
        .iter()
        .map(|s| {
            let a = [0, 1, 2].map(|i| s.a[i] * scale[i]);
            let b = [0, 1, 2].map(|i| s.b[i] * scale[i]);
            // At least a voxel thick at any size.
            (
                a,
                b,
                (s.radius * scale.iter().cloned().fold(0.0, f32::max)).max(1.0) * growth,
            )
        })
        .collect();
    let [w, h, _] = dims;
    let mut data = vec![0u8; w as usize * h as usize * layers.len()];
    for (a, b, r) in &segs {
        let reach = r + 1.5;
        let lo = [0, 1, 2].map(|i| ((a[i].min(b[i]) - reach).floor().max(0.0)) as u32);
        let hi = [0, 1, 2].map(|i| ((a[i].max(b[i]) + reach).ceil() as u32).min(dims[i]));
        let ab = [0, 1, 2].map(|i| b[i] - a[i]);
        let ab2 = ab.iter().map(|c| c * c).sum::<f32>().max(1e-12);
        for z in lo[2].max(layers.start)..hi[2].min(layers.end) {
            for y in lo[1]..hi[1] {
                for x in lo[0]..hi[0] {
                    let p = [x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5];
                    let ap = [0, 1, 2].map(|i| p[i] - a[i]);
                    let t = ((ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / ab2).clamp(0.0, 1.0);
                    let d2 = (0..3).map(|i| (ap[i] - t * ab[i]).powi(2)).sum::<f32>();
                    let v = (1.0 - (d2.sqrt() - r + 1.0) / 2.0).clamp(0.0, 1.0);
                    let i = x as usize + w as usize * (y as usize + h as usize * (z - layers.start) as usize);
                    data[i] = data[i].max((v * 255.0).round() as u8);
                }
            }
        }
    }
    data
}
