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
    uvec4 counts; // xyz: bricks per axis; w: total bricks
    vec4 lo;      // per channel: texel normalisation v = (texel - lo) * scale
    vec4 scale;
    uint apron;
    uint groups_x;
    uint channels;
    uint pool_brick; // bricked storage: the pool's brick edge (0: dense)
} pc;

// Widens the ranges by texel t's channels, NaN ignored.
void take(vec4 t, inout vec4 mn, inout vec4 mx) {
    if (pc.channels == 1u) {
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
    if (pc.channels == 1u) {
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

void main() {
    uint b = linear_index(pc.groups_x);
    if (b >= pc.counts.w) {
        return;
    }
    uvec3 bc = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    ivec3 lo = max(ivec3(bc * pc.dims.w) - int(pc.apron), ivec3(0));
    ivec3 hi = min(ivec3(bc * pc.dims.w + pc.dims.w - 1u) + int(pc.apron), ivec3(pc.dims.xyz) - 1);
    ivec3 hi_voxel = ivec3(pc.dims.xyz) - 1;
    vec4 mn = vec4(3.4e38);
    vec4 mx = vec4(-3.4e38);
    int edge = int(pc.pool_brick);
    if (edge == 0) {
        take_box(volume_tex, lo, hi - lo, mn, mx);
    } else {
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
    for (uint c = 0u; c < pc.channels; ++c) {
        precise float a = (mn[c] - pc.lo[c]) * pc.scale[c];
        precise float d = (mx[c] - pc.lo[c]) * pc.scale[c];
        ranges[b * pc.channels + c] = vec2(clamp(a, 0.0, 1.0), clamp(d, 0.0, 1.0));
    }
}
