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
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            // Bricked storage: one table read per run of a row inside one
            // brick, and one fetch for a run of a constant brick.
            int x = lo.x;
            while (x <= hi.x) {
                ivec3 v = ivec3(x, y, z);
                // The run: the rest of the row (dense), or of this brick.
                int run_end = edge == 0 ? hi.x : min(hi.x, (x / edge) * edge + edge - 1);
                int read_end = run_end;
                ivec4 at = ivec4(0);
                if (edge != 0) {
                    at = brick_texel(v, hi_voxel, edge);
                    if ((at.w & 1) == 0) {
                        read_end = x; // one value: its first voxel stands for the run
                    }
                }
                for (int i = 0; i <= read_end - x; ++i) {
                    vec4 t = edge == 0 ? texelFetch(volume_tex, v + ivec3(i, 0, 0), 0)
                                       : pool_fetch(at.w >> 1, at.xyz + ivec3(i, 0, 0));
                    for (int c = 0; c < 4; ++c) {
                        if (!is_nan(t[c])) {
                            mn[c] = min(mn[c], t[c]);
                            mx[c] = max(mx[c], t[c]);
                        }
                    }
                }
                x = run_end + 1;
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
