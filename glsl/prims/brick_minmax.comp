#version 460
// Min/max of normalised voxel values per brick of `brick`^3 voxels, widened by
// an apron of `apron` voxels per side (clamped to the volume). One invocation
// per brick; output vec2(min, max) per brick and channel, at
// brick * channels + channel, bricks x fastest. NaN voxels are ignored; a
// brick of NaN only gets an empty range (min > max).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
#include "nan.glsl"
layout(set = 0, binding = 0) uniform sampler3D volume_tex;
layout(std430, set = 0, binding = 1) writeonly buffer Ranges { vec2 ranges[]; };
#define BRICK_TABLE_BINDING 2
#define POOL_BINDING 3
#include "bricks.glsl"
layout(push_constant) uniform Push {
    uvec4 dims;   // xyz: volume dims; w: brick edge
    uvec4 counts; // xyz: bricks per axis; w: total bricks (LISTED: listed bricks)
    vec4 lo;      // per channel: texel normalisation v = (texel - lo) * scale
    vec4 scale;
    uint apron;
    uint groups_x;
    uint pool_brick; // bricked storage: the pool's brick edge
} pc;

// Where the voxels come from, their kind and the channels are constants,
// not push values: lavapipe runs every side of an `if` (no lane need take
// it), so branching on them at run time paid for the other sources' and
// kinds' fetches too (cell-4 ranges of nbody:256 took 3 to 4.5 times as long).
layout(constant_id = 0) const uint SOURCE = 0u; // SOURCE_*
layout(constant_id = 1) const uint KIND = 0u;   // SOURCE_CELLS: VOLUME_KIND, 0 float, 1 unorm8, 2 unorm16
layout(constant_id = 2) const uint CHANNELS = 1u;
// 1: only the bricks `listed` names (a time step's changed bricks, the
// others kept from the step before); counts.w is then their number.
layout(constant_id = 3) const uint LISTED = 0u;
layout(std430, set = 0, binding = 7) readonly buffer Listed { uint listed[]; };
const uint SOURCE_IMAGE = 0u; // the dense volume image
const uint SOURCE_CELLS = 1u; // its cells copy (one channel)
const uint SOURCE_POOL = 2u;  // bricked storage: the brick table and pools

// The volume's cells copy (src/volume/cells.rs), where it has one: each
// cell's eight voxels in one texel (two for floats), stored values.
layout(set = 0, binding = 6) uniform usamplerBuffer cells;

// Widens the ranges by texel t's channels, NaN ignored.
void take(vec4 t, inout vec4 mn, inout vec4 mx) {
    if (CHANNELS == 1u) {
        if (!is_nan(t.x)) {
            mn.x = min(mn.x, t.x);
            mx.x = max(mx.x, t.x);
        }
        return;
    }
    for (int c = 0; c < 4; ++c) {
        if (!is_nan(t[c])) {
            mn[c] = min(mn[c], t[c]);
            mx[c] = max(mx[c], t[c]);
        }
    }
}

// Widens the ranges by the texels of `tex` in the box [t, t + n]; one
// channel in scalars (lavapipe ran the loop through take 1.4x slower, and a
// loop over four channels 7x).
void take_box(sampler3D tex, ivec3 t, ivec3 n, inout vec4 mn, inout vec4 mx) {
    if (CHANNELS == 1u) {
        float lo1 = mn.x;
        float hi1 = mx.x;
        for (int z = 0; z <= n.z; ++z) {
            for (int y = 0; y <= n.y; ++y) {
                for (int x = 0; x <= n.x; ++x) {
                    float v = texelFetch(tex, t + ivec3(x, y, z), 0).r;
                    if (!is_nan(v)) {
                        lo1 = min(lo1, v);
                        hi1 = max(hi1, v);
                    }
                }
            }
        }
        mn.x = lo1;
        mx.x = hi1;
        return;
    }
    for (int z = 0; z <= n.z; ++z) {
        for (int y = 0; y <= n.y; ++y) {
            for (int x = 0; x <= n.x; ++x) {
                take(texelFetch(tex, t + ivec3(x, y, z), 0), mn, mx);
            }
        }
    }
}

// The low corner of the next cell along one axis of the box [lo, hi]:
// every other voxel from lo, the last cell moved back to end at hi (a
// voxel read twice changes no extreme); at a one-voxel box the cell at hi,
// whose upper corner the copy clamps to hi where hi is the volume's last
// voxel (the host sends no other one-voxel box here).
int cell_at(int at, int lo, int hi) {
    return hi > lo ? min(at, hi - 1) : at;
}

// As take_box over the box [lo, hi] of a dense one-channel volume, from
// its cells copy: a 2x2x2 block of voxels a fetch, an eighth of
// take_box's. Unorm extremes are found on the stored integers, then
// scaled as the manual filter scales a sample (integer times 1 / unit;
// on lavapipe also what texelFetch returns, tests/prims.rs).
void take_cells(ivec3 lo, ivec3 hi, inout vec4 mn, inout vec4 mx) {
    ivec3 n = ivec3(pc.dims.xyz) + 1;
    uint a = 0xffffffffu;
    uint b = 0u;
    float lo1 = mn.x;
    float hi1 = mx.x;
    for (int z = lo.z; z <= hi.z; z += 2) {
        for (int y = lo.y; y <= hi.y; y += 2) {
            for (int x = lo.x; x <= hi.x; x += 2) {
                ivec3 j = ivec3(cell_at(x, lo.x, hi.x), cell_at(y, lo.y, hi.y), cell_at(z, lo.z, hi.z)) + 1;
                int at = j.x + n.x * (j.y + n.y * j.z);
                if (KIND == 1u) {
                    uvec2 w = texelFetch(cells, at).xy;
                    for (uint s = 0u; s < 32u; s += 8u) {
                        uint v0 = (w.x >> s) & 255u;
                        uint v1 = (w.y >> s) & 255u;
                        a = min(a, min(v0, v1));
                        b = max(b, max(v0, v1));
                    }
                } else if (KIND == 2u) {
                    uvec4 w = texelFetch(cells, at);
                    uvec4 l = w & 65535u;
                    uvec4 u = w >> 16u;
                    uvec4 m0 = min(l, u);
                    uvec4 m1 = max(l, u);
                    a = min(a, min(min(m0.x, m0.y), min(m0.z, m0.w)));
                    b = max(b, max(max(m1.x, m1.y), max(m1.z, m1.w)));
                } else {
                    for (int h = 0; h < 2; ++h) {
                        uvec4 w = texelFetch(cells, 2 * at + h);
                        for (int c = 0; c < 4; ++c) {
                            float v = uintBitsToFloat(w[c]);
                            if (!is_nan(v)) {
                                lo1 = min(lo1, v);
                                hi1 = max(hi1, v);
                            }
                        }
                    }
                }
            }
        }
    }
    if (KIND != 0u) {
        // Constant reciprocals, as volume.glsl's (no division at run time).
        float inv = KIND == 1u ? (1.0 / 255.0) : (1.0 / 65535.0);
        precise float lo_v = float(a) * inv;
        precise float hi_v = float(b) * inv;
        lo1 = min(lo1, lo_v);
        hi1 = max(hi1, hi_v);
    }
    mn.x = lo1;
    mx.x = hi1;
}

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= pc.counts.w) {
        return;
    }
    uint b = LISTED != 0u ? listed[i] : i;
    // A listed index past the bricks writes nothing (the list is the caller's).
    if (b >= pc.counts.x * pc.counts.y * pc.counts.z) {
        return;
    }
    uvec3 bc = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    ivec3 lo = max(ivec3(bc * pc.dims.w) - int(pc.apron), ivec3(0));
    ivec3 hi = min(ivec3(bc * pc.dims.w + pc.dims.w - 1u) + int(pc.apron), ivec3(pc.dims.xyz) - 1);
    ivec3 hi_voxel = ivec3(pc.dims.xyz) - 1;
    vec4 mn = vec4(3.4e38);
    vec4 mx = vec4(-3.4e38);
    if (SOURCE == SOURCE_CELLS) {
        take_cells(lo, hi, mn, mx);
    } else if (SOURCE == SOURCE_IMAGE) {
        take_box(volume_tex, lo, hi - lo, mn, mx);
    } else {
        int edge = int(pc.pool_brick);
        // Bricked: pool brick by pool brick, each overlap with the box one
        // table read; a constant brick is one value, read once.
        ivec3 b_hi = hi / edge;
        for (int bz = lo.z / edge; bz <= b_hi.z; ++bz) {
            for (int by = lo.y / edge; by <= b_hi.y; ++by) {
                for (int bx = lo.x / edge; bx <= b_hi.x; ++bx) {
                    ivec3 pb = ivec3(bx, by, bz) * edge;
                    ivec3 s_lo = max(lo, pb);
                    ivec3 n = min(hi, pb + edge - 1) - s_lo;
                    ivec4 at = brick_texel(s_lo, hi_voxel, edge);
                    int image = at.w >> 1;
                    if ((at.w & 1) == 0) {
                        take(pool_fetch(image, at.xyz), mn, mx);
                    } else if (image == 0) {
                        take_box(volume_tex, at.xyz, n, mn, mx);
                    } else if (image == 1) {
                        take_box(pool_1, at.xyz, n, mn, mx);
                    } else if (image == 2) {
                        take_box(pool_2, at.xyz, n, mn, mx);
                    } else {
                        take_box(pool_3, at.xyz, n, mn, mx);
                    }
                }
            }
        }
    }
    // Normalise the extremes exactly as sample_volume (sample_channels)
    // normalises a sample.
    for (uint c = 0u; c < CHANNELS; ++c) {
        precise float a = (mn[c] - pc.lo[c]) * pc.scale[c];
        precise float d = (mx[c] - pc.lo[c]) * pc.scale[c];
        ranges[b * CHANNELS + c] = vec2(clamp(a, 0.0, 1.0), clamp(d, 0.0, 1.0));
    }
}
