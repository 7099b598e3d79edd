//! Menger sponge: solid where no two base-3 digits of the cell coordinates
//! equal 1 at any level up to `level`. Solid voxels carry a gentle diagonal
//! gradient so the transfer function's colours show depth. Over time the
//! sponge slides along x, a voxel a step, wrapping around.

use std::ops::Range;

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
