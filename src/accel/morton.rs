//! 30-bit Morton codes of brick coordinates (10 bits per axis, x highest),
//! the CPU twin of `glsl/common/morton.glsl`.

/// Bricks per axis a 30-bit code can address.
pub const MAX_BRICKS_PER_AXIS: u32 = 1024;

fn spread(v: u32) -> u32 {
    let mut v = v & 0x3FF;
    v = (v | (v << 16)) & 0x0300_00FF;
    v = (v | (v << 8)) & 0x0300_F00F;
    v = (v | (v << 4)) & 0x030C_30C3;
    v = (v | (v << 2)) & 0x0924_9249;
    v
}

/// The 30-bit Morton code of `c` (10 bits an axis, x highest).
pub fn morton3(c: [u32; 3]) -> u32 {
    (spread(c[0]) << 2) | (spread(c[1]) << 1) | spread(c[2])
}

/// Push block of `glsl/build/morton.comp` (the LBVH and the GPU k-d tree):
/// `counts.xyz` bricks per axis; `identity` 1 codes every brick (thread i
/// is brick i) instead of a list of bricks.
pub(crate) use crate::gpu::shaders::build_morton::Push as MortonPush;

impl MortonPush {
    /// Codes the `n` bricks listed in the input buffer.
    pub(crate) fn list(counts: [u32; 3], n: u32, groups_x: u32) -> Self {
        MortonPush {
            counts: [counts[0], counts[1], counts[2], 0],
            n,
            groups_x,
            ..Default::default()
        }
    }

    /// Codes every brick 0..n (no input list).
    pub(crate) fn every(counts: [u32; 3], n: u32, groups_x: u32) -> Self {
        MortonPush {
            identity: 1,
            ..Self::list(counts, n, groups_x)
        }
    }
}
