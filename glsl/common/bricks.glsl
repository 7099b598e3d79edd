// Bricked storage (src/volume/pool.rs): the volume cut into bricks of
// `edge`^3 voxels, each stored in a slot of (edge + 1)^3 texels of the pool
// image: its own voxels and, on its high sides, the next brick's first
// layer, so the eight voxels of every trilinear cell lie in one slot. A
// brick whose texels (that extra layer included) are all one value is not
// stored: its entry points at one texel holding that value, with step 0,
// so the same eight fetches read it eight times and no branch is needed.
//
// The table holds one entry per brick, x fastest, in a texel buffer of
// RG32UI: uvec2(x | y << 16, z | constant << 31), the pool texel its slot
// (or its value) starts at.
#ifndef LACUNA_BRICKS_GLSL
#define LACUNA_BRICKS_GLSL

layout(set = 0, binding = BRICK_TABLE_BINDING) uniform usamplerBuffer brick_table;

// The pool texel of voxel v (0 <= v <= hi) in bricks of `edge`, and in w the
// pool step to its +1 neighbours: 1 in a stored brick, 0 in a constant one.
ivec4 brick_texel(ivec3 v, ivec3 hi, int edge) {
    ivec3 b = v / edge;
    ivec3 n = hi / edge + 1;
    uvec2 e = texelFetch(brick_table, b.x + n.x * (b.y + n.y * b.z)).xy;
    int step = 1 - int(e.y >> 31u);
    ivec3 origin = ivec3(e.x & 0xffffu, e.x >> 16u, e.y & 0xffffu);
    return ivec4(origin + (v - b * edge) * step, step);
}

// The pool texel of voxel v (clamped to the volume): v itself when `edge`
// is 0 (dense storage).
ivec3 stored_texel(ivec3 v, ivec3 hi, int edge) {
    ivec3 c = clamp(v, ivec3(0), hi);
    return edge == 0 ? c : brick_texel(c, hi, edge).xyz;
}

#endif
