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

// Widens the ranges by texel t's channels, NaN ignored (one channel: a
// scalar test, which lavapipe runs several times faster than the loop over
// four).
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
    if (edge == 0 && pc.channels == 1u) {
        // The common case, as plain as it gets: scalar extremes (lavapipe
        // ran the loop through take 1.4x slower, and a loop over four
        // channels 7x).
        float lo1 = mn.x;
        float hi1 = mx.x;
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                for (int x = lo.x; x <= hi.x; ++x) {
                    float t = texelFetch(volume_tex, ivec3(x, y, z), 0).r;
                    if (!is_nan(t)) {
                        lo1 = min(lo1, t);
                        hi1 = max(hi1, t);
                    }
                }
            }
        }
        mn.x = lo1;
        mx.x = hi1;
    } else if (edge == 0) {
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                for (int x = lo.x; x <= hi.x; ++x) {
                    take(texelFetch(volume_tex, ivec3(x, y, z), 0), mn, mx);
                }
            }
        }
    } else {
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                // One table read per run of a row inside one brick, and one
                // fetch for a run of a constant brick.
                int x = lo.x;
                while (x <= hi.x) {
                    ivec3 v = ivec3(x, y, z);
                    int run_end = min(hi.x, (x / edge) * edge + edge - 1);
                    ivec4 at = brick_texel(v, hi_voxel, edge);
                    // One value: its first voxel stands for the run.
                    int read_end = (at.w & 1) == 0 ? x : run_end;
                    for (int i = 0; i <= read_end - x; ++i) {
                        take(pool_fetch(at.w >> 1, at.xyz + ivec3(i, 0, 0)), mn, mx);
                    }
                    x = run_end + 1;
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
