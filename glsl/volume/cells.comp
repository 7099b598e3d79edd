#version 460
// The volume's cells copy (src/volume/cells.rs) made on the device from the
// volume image it was uploaded to: per cell (i, j, k), i in -1..W-1 and so
// on, its eight voxels clamped to the volume, x fastest, as the host packs
// them: unorm8 as the bytes of two words, unorm16 as the 16-bit halves of
// four, float32 as the bits of eight. Reading the texels back out of the
// image (exactly: a unorm texel times 255 or 65535 rounds to its integer)
// spares a host packing and a staging copy of 8 to 32 bytes a voxel.
// The binding starts at the first row of cells this dispatch writes (a copy
// may pass maxStorageBufferRange).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(set = 0, binding = 0) uniform sampler3D volume_tex;
layout(std430, set = 0, binding = 1) writeonly buffer Cells { uint words[]; };
layout(push_constant) uniform Push {
    uvec4 dims;  // xyz: volume dims; w: VOLUME_KIND (0 float32, 1 unorm8, 2 unorm16)
    uvec4 cells; // xyz: cells per axis (dims + 1); w: rows of cells this dispatch writes
    uint first;  // the first row of cells (y fastest) this dispatch writes
    uint groups_x;
} pc;

// Word w of the cell whose corners are lo (x low) and hi (x high), four
// each: (y, z) = (0, 0), (1, 0), (0, 1), (1, 1). Corner b is x = b & 1 of
// pair b >> 1.
void store_cell(uint at, vec4 lo, vec4 hi) {
    float v[8] = float[8](lo.x, hi.x, lo.y, hi.y, lo.z, hi.z, lo.w, hi.w);
    if (pc.dims.w == 1u) {
        for (int h = 0; h < 2; ++h) {
            uint w = 0u;
            for (int b = 0; b < 4; ++b) {
                w |= uint(round(v[4 * h + b] * 255.0)) << (8 * b);
            }
            words[2u * at + uint(h)] = w;
        }
    } else if (pc.dims.w == 2u) {
        for (int p = 0; p < 4; ++p) {
            words[4u * at + uint(p)] = uint(round(v[2 * p] * 65535.0)) | (uint(round(v[2 * p + 1] * 65535.0)) << 16);
        }
    } else {
        for (int b = 0; b < 8; ++b) {
            words[8u * at + uint(b)] = floatBitsToUint(v[b]);
        }
    }
}

// The voxels at x of the four rows (y0, z0), (y1, z0), (y0, z1), (y1, z1).
vec4 column(int x, ivec2 y, ivec2 z) {
    return vec4(texelFetch(volume_tex, ivec3(x, y.x, z.x), 0).r, texelFetch(volume_tex, ivec3(x, y.y, z.x), 0).r,
                texelFetch(volume_tex, ivec3(x, y.x, z.y), 0).r, texelFetch(volume_tex, ivec3(x, y.y, z.y), 0).r);
}

// One invocation per row of cells (j, k): each voxel column is read once
// and serves the cell on either side of it.
void main() {
    uint n = linear_index(pc.groups_x);
    if (n >= pc.cells.w) {
        return;
    }
    uint row = pc.first + n;
    int j = int(row % pc.cells.y) - 1;
    int k = int(row / pc.cells.y) - 1;
    ivec3 hi = ivec3(pc.dims.xyz) - 1;
    ivec2 y = clamp(ivec2(j, j + 1), ivec2(0), ivec2(hi.y));
    ivec2 z = clamp(ivec2(k, k + 1), ivec2(0), ivec2(hi.z));
    vec4 lo = column(0, y, z);
    uint at = n * pc.cells.x;
    for (int i = -1; i < hi.x + 1; ++i) {
        vec4 next = column(min(i + 1, hi.x), y, z);
        store_cell(at + uint(i + 1), lo, next);
        lo = next;
    }
}
