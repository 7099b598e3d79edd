//! Menger sponge: solid where no two base-3 digits of the cell coordinates
//! equal 1 at any level up to `level`. Solid voxels carry a gentle diagonal
//! gradient so the transfer function's colours show depth. Over time the
//! sponge slides along x, a voxel a step, wrapping around.

use std::ops::Range;

/// The level a size gets when its spec names none.
pub const DEFAULT_LEVEL: u32 = 3;

/// The finest level whose holes span at least a voxel on every axis
/// (3^level <= the shortest side). A finer level samples sub-voxel holes
/// at voxel centres: on a side of 3^k voxels every centre then falls in a
/// hole and the volume is empty.
pub fn finest_level(dims: [u32; 3]) -> u32 {
    let side = dims.into_iter().min().unwrap_or(0) as u64;
    (0..).take_while(|&l| 3u64.pow(l + 1) <= side).count() as u32
}

/// Layers `layers` (z) of the volume, x fastest.
pub fn generate(dims: [u32; 3], level: u32, time: u32, layers: Range<u32>) -> Vec<u8> {
    let scale = 3u64.pow(level);
    super::fill(dims, layers, |x, y, z| {
        let x = ((x as u64 + time as u64) % dims[0] as u64) as u32;
        // The cell of the level-`level` grid that holds this voxel's centre.
        let cell = |i: u32, n: u32| (2 * i as u64 + 1) * scale / (2 * n as u64);
        let (mut cx, mut cy, mut cz) = (cell(x, dims[0]), cell(y, dims[1]), cell(z, dims[2]));
        for _ in 0..level {
            let ones = (cx % 3 == 1) as u32 + (cy % 3 == 1) as u32 + (cz % 3 == 1) as u32;
            if ones >= 2 {
                return 0;
            }
            cx /= 3;
            cy /= 3;
            cz /= 3;
        }
        let t = (x as f32 / dims[0] as f32 + y as f32 / dims[1] as f32 + z as f32 / dims[2] as f32) / 3.0;
        (128.0 + 127.0 * t).round() as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_finest_level_is_the_largest_power_of_three_within_the_shortest_side() {
        for (dims, level) in [
            ([1, 1, 1], 0),
            ([2, 9, 9], 0),
            ([3, 3, 3], 1),
            ([8, 8, 8], 1),
            ([9, 9, 9], 2),
            ([26, 26, 26], 2),
            ([27, 81, 243], 3),
            ([243, 243, 243], 5),
            ([4096, 4096, 4096], 7),
        ] {
            assert_eq!(finest_level(dims), level, "{dims:?}");
        }
    }

    #[test]
    fn every_resolvable_level_leaves_solid_voxels() {
        for n in 1..=30u32 {
            for level in 0..=finest_level([n; 3]) {
                let v = generate([n; 3], level, 0, 0..n);
                assert!(v.iter().any(|&x| x > 0), "menger:{n}:{level} is empty");
            }
        }
    }
}
