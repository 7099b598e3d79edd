//! CPU occupancy of voxel footprints in 32^3 bricks, each with a summed
//! volume table of u16 counts (32^3 = 32768 fits), built in parallel on every
//! transfer-function change. Counting a box costs 8 lookups per brick; the
//! tight box of a region shrinks each face by binary search per overlapped
//! brick (in parallel) and takes the union: O(bricks overlapped).

use super::IBox;
use crate::spatial::Sat3;
use crate::tf::TransferFunction;
use crate::volume::Volume;
use rayon::prelude::*;

/// Edge, in voxel footprints, of the bricks that each keep a summed-volume
/// table.
pub const SVT_BRICK: i32 = 32;

/// A brick index, its origin, and a box clipped to it in local coordinates.
type Clipped = (usize, [i32; 3], [i32; 3], [i32; 3]);

/// Active voxel footprints as per-brick summed-volume tables: the count in
/// any box in O(bricks it touches), which the CPU k-d builder splits on.
pub struct Occupancy {
    pub dims: [i32; 3],
    counts: [i32; 3],
    /// Per brick: the summed-area table of its active footprints.
    tables: Vec<Sat3<u16>>,
    /// Active footprints in the whole volume.
    pub active: u64,
}

/// Max (or min) of three neighbours along one axis of a staged block.
fn filter3(src: &[f32], dims: [usize; 3], axis: usize, pick: fn(f32, f32) -> f32) -> (Vec<f32>, [usize; 3]) {
    let mut out_dims = dims;
    out_dims[axis] -= 2;
    let stride = [1, dims[0], dims[0] * dims[1]];
    let mut out = Vec::with_capacity(out_dims.iter().product());
    for z in 0..out_dims[2] {
        for y in 0..out_dims[1] {
            for x in 0..out_dims[0] {
                let i = x * stride[0] + y * stride[1] + z * stride[2];
                let s = stride[axis];
                out.push(pick(pick(src[i], src[i + s]), src[i + 2 * s]));
            }
        }
    }
    (out, out_dims)
}

impl Occupancy {
    /// Classifies every footprint of `volume` under `tf` (active in any
    /// channel, each by its own TF) and builds the tables.
    pub fn new(volume: &Volume, tf: &TransferFunction) -> Self {
        let dims = volume.dims.map(|d| d as i32);
        let counts = dims.map(|d| (d + SVT_BRICK - 1) / SVT_BRICK);
        let n = counts.iter().product::<i32>() as usize;
        let tables: Vec<Sat3<u16>> = (0..n)
            .into_par_iter()
            .map(|b| {
                let bc = [
                    b as i32 % counts[0],
                    (b as i32 / counts[0]) % counts[1],
                    b as i32 / (counts[0] * counts[1]),
                ];
                let origin = bc.map(|c| c * SVT_BRICK);
                // Per channel, each footprint's range over the voxels its
                // samples read: the brick plus a one-voxel apron, clamped
                // like the sampler.
                let s = SVT_BRICK as usize + 2;
                let ranges: Vec<(Vec<f32>, Vec<f32>)> = volume
                    .channels()
                    .map(|channel| {
                        let mut staged = Vec::with_capacity(s * s * s);
                        for z in 0..s as i32 {
                            for y in 0..s as i32 {
                                for x in 0..s as i32 {
                                    let v = [x, y, z].map(|c| c - 1);
                                    let p = [0, 1, 2].map(|a| (origin[a] + v[a]).clamp(0, dims[a] - 1) as u32);
                                    staged.push(channel.value(p[0], p[1], p[2]));
                                }
                            }
                        }
                        let mut lo = (staged.clone(), [s; 3]);
                        let mut hi = (staged, [s; 3]);
                        for axis in 0..3 {
                            lo = filter3(&lo.0, lo.1, axis, f32::min);
                            hi = filter3(&hi.0, hi.1, axis, f32::max);
                        }
                        (lo.0, hi.0)
                    })
                    .collect();
                let b = SVT_BRICK as usize;
                Sat3::<u16>::new([b; 3], |x, y, z| {
                    let inside = [x, y, z]
                        .iter()
                        .zip(&origin)
                        .zip(&dims)
                        .all(|((c, o), d)| o + (*c as i32) < *d);
                    let i = x + b * (y + b * z);
                    inside
                        && ranges
                            .iter()
                            .enumerate()
                            .any(|(c, (lo, hi))| tf.channel(c).visible(lo[i], hi[i]))
                })
            })
            .collect();
        let active = tables.iter().map(|t| t.total() as u64).sum();
        Occupancy {
            dims,
            counts,
            tables,
            active,
        }
    }

    /// Active footprints of brick `b` in local `[lo, hi)` (clipped to the brick).
    fn count_local(&self, b: usize, lo: [i32; 3], hi: [i32; 3]) -> i64 {
        if (0..3).any(|a| lo[a] >= hi[a]) {
            return 0;
        }
        self.tables[b].count(lo.map(|c| c as usize), hi.map(|c| c as usize))
    }

    /// The bricks `bx` overlaps, with the box clipped to each in local coordinates.
    fn overlapped(&self, bx: &IBox) -> Vec<Clipped> {
        let lo = [0, 1, 2].map(|a| bx[0][a].max(0));
        let hi = [0, 1, 2].map(|a| bx[1][a].min(self.dims[a]));
        if (0..3).any(|a| lo[a] >= hi[a]) {
            return Vec::new();
        }
        let blo = lo.map(|c| c / SVT_BRICK);
        let bhi = hi.map(|c| (c - 1) / SVT_BRICK);
        let mut out = Vec::new();
        for z in blo[2]..=bhi[2] {
            for y in blo[1]..=bhi[1] {
                for x in blo[0]..=bhi[0] {
                    let origin = [x, y, z].map(|c| c * SVT_BRICK);
                    let l = [0, 1, 2].map(|a| (lo[a] - origin[a]).max(0));
                    let h = [0, 1, 2].map(|a| (hi[a] - origin[a]).min(SVT_BRICK));
                    let b = (x + self.counts[0] * (y + self.counts[1] * z)) as usize;
                    out.push((b, origin, l, h));
                }
            }
        }
        out
    }

    /// Active footprints in `bx`.
    pub fn count(&self, bx: &IBox) -> i64 {
        self.overlapped(bx)
            .iter()
            .map(|&(b, _, l, h)| self.count_local(b, l, h))
            .sum()
    }

    pub fn is_active(&self, x: i32, y: i32, z: i32) -> bool {
        self.count(&[[x, y, z], [x + 1, y + 1, z + 1]]) > 0
    }

    /// Tight box of the active footprints in `bx`, or None if there are none.
    pub fn tight(&self, bx: &IBox) -> Option<IBox> {
        self.overlapped(bx)
            .par_iter()
            .filter_map(|&(b, origin, mut l, mut h)| {
                let total = self.count_local(b, l, h);
                if total == 0 {
                    return None;
                }
                for a in 0..3 {
                    // Largest lo face keeping every footprint.
                    let (mut lo, mut hi) = (l[a], h[a] - 1);
                    while lo < hi {
                        let mid = (lo + hi + 1) / 2;
                        let mut t = l;
                        t[a] = mid;
                        if self.count_local(b, t, h) == total {
                            lo = mid;
                        } else {
                            hi = mid - 1;
                        }
                    }
                    l[a] = lo;
                    // Smallest hi face keeping every footprint.
                    let (mut lo, mut hi) = (l[a] + 1, h[a]);
                    while lo < hi {
                        let mid = (lo + hi) / 2;
                        let mut t = h;
                        t[a] = mid;
                        if self.count_local(b, l, t) == total {
                            hi = mid;
                        } else {
                            lo = mid + 1;
                        }
                    }
                    h[a] = lo;
                }
                Some([[0, 1, 2].map(|a| origin[a] + l[a]), [0, 1, 2].map(|a| origin[a] + h[a])])
            })
            .reduce_with(|a, b| {
                [
                    [0, 1, 2].map(|i| a[0][i].min(b[0][i])),
                    [0, 1, 2].map(|i| a[1][i].max(b[1][i])),
                ]
            })
    }
}
