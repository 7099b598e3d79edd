#version 460
// Voxel classification (the paper's brick voting), every voxel through the TF
// on every TF change. apron = 0: a brick is hit iff one of its own voxels
// has alpha > 0 at its value (the paper; not conservative). apron = 1: every
// trilinear cell a sample in the brick can read is classified by the TF's max
// alpha over the cell's 8 values; the union of those ranges is the brick's
// apron range, so this agrees with range classification exactly. Several
// channels: a brick is hit iff it is in any channel, each by its own TF.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
#include "nan.glsl"
layout(set = 0, binding = 0) uniform sampler3D volume_tex;
layout(std430, set = 0, binding = 1) readonly buffer TransferLut { vec4 tf_lut[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Flags { uint flags[]; };
#define BRICK_TABLE_BINDING 4
#define POOL_BINDING 5
#include "bricks.glsl"
layout(push_constant) uniform Push {
    uvec4 dims;   // xyz: volume dims; w: brick edge
    uvec4 counts; // xyz: bricks per axis; w: total bricks
    vec4 lo;      // per channel: v = (texel - lo) * scale
    vec4 scale;
    uint apron;
    uint groups_x;
    uint lut_size;
    uint channels;
    uint tf_step;    // 1: a table per channel; 0: one for all
    uint max_stride; // entries of one channel's max table
    uint pool_brick; // bricked storage: the pool's brick edge (0: dense)
    uint pad;
} pc;

#define TF_MAX_BINDING 2
#define TF_SIZE pc.lut_size
#include "tf_range.glsl"

float value_at(ivec3 i, uint ch) {
    vec4 t = stored_voxel(i, ivec3(pc.dims.xyz) - 1, int(pc.pool_brick));
    precise float v = (t[ch] - pc.lo[ch]) * pc.scale[ch];
    return is_nan(v) ? v : clamp(v, 0.0, 1.0);
}

float lut_alpha(uint base, float v) {
    precise float x = v * float(TF_SIZE - 1u);
    float fl = floor(x);
    uint i = min(uint(fl), TF_SIZE - 1u);
    uint j = min(i + 1u, TF_SIZE - 1u);
    precise float a = mix(tf_lut[base + i].a, tf_lut[base + j].a, x - fl);
    return a;
}

bool brick_hit(ivec3 first, ivec3 last, uint ch) {
    uint lut = ch * pc.tf_step * TF_SIZE;
    uint table = ch * pc.tf_step * pc.max_stride;
    bool hit = false;
    if (pc.apron == 0u) {
        for (int z = first.z; z <= last.z && !hit; ++z) {
            for (int y = first.y; y <= last.y && !hit; ++y) {
                for (int x = first.x; x <= last.x && !hit; ++x) {
                    float v = value_at(ivec3(x, y, z), ch);
                    hit = !is_nan(v) && lut_alpha(lut, v) > 0.0;
                }
            }
        }
    } else {
        // Cells with lower corner first-1 .. last cover every sample in the brick.
        for (int z = first.z - 1; z <= last.z && !hit; ++z) {
            for (int y = first.y - 1; y <= last.y && !hit; ++y) {
                for (int x = first.x - 1; x <= last.x && !hit; ++x) {
                    float mn = 3.4e38;
                    float mx = -3.4e38;
                    bool no_data = false;
                    for (int c = 0; c < 8; ++c) {
                        float v = value_at(ivec3(x, y, z) + ivec3(c & 1, (c >> 1) & 1, c >> 2), ch);
                        no_data = no_data || is_nan(v);
                        mn = min(mn, v);
                        mx = max(mx, v);
                    }
                    // A cell with a NaN voxel has only NaN samples.
                    hit = !no_data && tf_max_alpha_at(table, mn, mx) > 0.0;
                }
            }
        }
    }
    return hit;
}

void main() {
    uint b = linear_index(pc.groups_x);
    if (b >= pc.counts.w) {
        return;
    }
    uvec3 bc = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    ivec3 first = ivec3(bc * pc.dims.w);
    ivec3 last = min(first + int(pc.dims.w) - 1, ivec3(pc.dims.xyz) - 1);
    bool hit = false;
    for (uint ch = 0u; ch < pc.channels && !hit; ++ch) {
        hit = brick_hit(first, last, ch);
    }
    flags[b] = hit ? 1u : 0u;
}
