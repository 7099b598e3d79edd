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

pub fn morton3(c: [u32; 3]) -> u32 {
    (spread(c[0]) << 2) | (spread(c[1]) << 1) | spread(c[2])
}
