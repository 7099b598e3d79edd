// 30-bit Morton codes of brick coordinates (10 bits per axis, x highest),
// matching src/accel/morton.rs.
#ifndef LACUNA_MORTON_GLSL
#define LACUNA_MORTON_GLSL

uint morton_spread(uint v) {
    v &= 0x3FFu;
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

uint morton3(uvec3 c) {
    return (morton_spread(c.x) << 2) | (morton_spread(c.y) << 1) | morton_spread(c.z);
}

#endif
