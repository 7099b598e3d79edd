// Bricked storage (src/volume/pool.rs): the volume cut into bricks of
// `edge`^3 voxels, each stored in a slot of (edge + 1)^3 texels of a pool
// image: its own voxels and, on its high sides, the next brick's first
// layer, so the eight voxels of every trilinear cell lie in one slot. A
// brick whose texels (that extra layer included) are all one value is not
// stored: its entry points at one texel holding that value, with step 0,
// so the same eight fetches read it eight times and no branch is needed.
// A pool past one allocation spans up to four images: volume_tex (image 0)
// and pool_1 to pool_3 (bound to volume_tex where unused).
//
// The table holds one entry per brick, x fastest, in a texel buffer of
// RG32UI: uvec2(x | y << 16, z | image << 16 | constant << 31), the pool
// image and texel its slot (or its value) starts at.
#ifndef LACUNA_BRICKS_GLSL
#define LACUNA_BRICKS_GLSL

layout(set = 0, binding = BRICK_TABLE_BINDING) uniform usamplerBuffer brick_table;
layout(set = 0, binding = POOL_BINDING) uniform sampler3D pool_1;
layout(set = 0, binding = POOL_BINDING + 1) uniform sampler3D pool_2;
layout(set = 0, binding = POOL_BINDING + 2) uniform sampler3D pool_3;
// Images the pool spans (march kernels specialise it; build kernels read
// any of four).
layout(constant_id = 28) const uint POOL_IMAGES = 4u;

// The pool texel of voxel v (0 <= v <= hi) in bricks of `edge`; in w the
// pool step to its +1 neighbours (1 in a stored brick, 0 in a constant
// one) plus twice its image.
ivec4 brick_texel(ivec3 v, ivec3 hi, int edge) {
    ivec3 b = v / edge;
    ivec3 n = hi / edge + 1;
    uvec2 e = texelFetch(brick_table, b.x + n.x * (b.y + n.y * b.z)).xy;
    int step = 1 - int(e.y >> 31u);
    ivec3 origin = ivec3(e.x & 0xffffu, e.x >> 16u, e.y & 0xffffu);
    return ivec4(origin + (v - b * edge) * step, step + 2 * int((e.y >> 16u) & 0x7fffu));
}

// Texel t of pool image `image`.
vec4 pool_fetch(int image, ivec3 t) {
    if (POOL_IMAGES == 1u || image == 0) {
        return texelFetch(volume_tex, t, 0);
    }
    if (image == 1) {
        return texelFetch(pool_1, t, 0);
    }
    if (image == 2) {
        return texelFetch(pool_2, t, 0);
    }
    return texelFetch(pool_3, t, 0);
}

// Voxel v (clamped to the volume), from the dense image when `edge` is 0,
// else from the pool.
vec4 stored_voxel(ivec3 v, ivec3 hi, int edge) {
    ivec3 c = clamp(v, ivec3(0), hi);
    if (edge == 0) {
        return texelFetch(volume_tex, c, 0);
    }
    ivec4 t = brick_texel(c, hi, edge);
    return pool_fetch(t.w >> 1, t.xyz);
}

#endif
