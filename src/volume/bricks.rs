//! Per-brick value ranges over a one-voxel apron (DESIGN invariant 2),
//! computed on the CPU. A sample inside brick b's footprint interpolates
//! voxels b*B-1 ..= b*B+B, so those are the voxels its range covers.

use super::Volume;
use crate::tf::TransferFunction;
use rayon::prelude::*;

/// Brick edge in voxels.
pub const BRICK: u32 = 8;

/// Voxels each side a brick's ranges reach past it: the one-voxel apron of
/// DESIGN invariant 2 (a sample in a brick reads its neighbours' voxels).
pub const APRON: u32 = 1;

/// A volume's value range per brick (apron included), per channel.
#[derive(Clone, Debug)]
pub struct BrickGrid {
    pub brick: u32,
    /// Bricks per axis (ceil(dims / brick)).
    pub counts: [u32; 3],
    /// Normalised [min, max] per brick, x fastest (channel 1's).
    pub ranges: Vec<[f32; 2]>,
    /// The same for channels 2 and up.
    pub other_channels: Vec<Vec<[f32; 2]>>,
}

impl BrickGrid {
    /// Ranges of `brick`^3 bricks; `apron` = 1 widens each by one voxel per side
    /// (0 reproduces the paper's per-voxel classification).
    pub fn new(volume: &Volume, brick: u32, apron: u32) -> Self {
        BrickGrid {
            brick,
            counts: volume.dims.map(|d| d.div_ceil(brick)),
            ranges: Self::channel(volume, brick, apron),
            other_channels: volume
                .other_channels
                .iter()
                .map(|c| Self::channel(c, brick, apron))
                .collect(),
        }
    }

    fn channel(volume: &Volume, brick: u32, apron: u32) -> Vec<[f32; 2]> {
        let counts = volume.dims.map(|d| d.div_ceil(brick));
        let n = counts.iter().map(|&c| c as usize).product();
        (0..n)
            .into_par_iter()
            .map(|i| {
                let b = [
                    i as u32 % counts[0],
                    (i as u32 / counts[0]) % counts[1],
                    i as u32 / (counts[0] * counts[1]),
                ];
                let lo = [0, 1, 2].map(|a| (b[a] * brick).saturating_sub(apron));
                let hi = [0, 1, 2].map(|a| (b[a] * brick + brick - 1 + apron).min(volume.dims[a] - 1));
                let mut r = [f32::INFINITY, f32::NEG_INFINITY];
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            let v = volume.value(x, y, z);
                            r[0] = r[0].min(v);
                            r[1] = r[1].max(v);
                        }
                    }
                }
                r
            })
            .collect()
    }

    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Active flags under `tf`: max alpha over the brick's range > 0 in
    /// any channel (each by its own transfer function).
    pub fn active(&self, tf: &TransferFunction) -> Vec<bool> {
        let channels: Vec<&Vec<[f32; 2]>> = std::iter::once(&self.ranges).chain(&self.other_channels).collect();
        (0..self.ranges.len())
            .map(|b| {
                channels
                    .iter()
                    .enumerate()
                    .any(|(c, r)| tf.channel(c).visible(r[b][0], r[b][1]))
            })
            .collect()
    }
}
