#version 460
// Voxel classification (the paper's brick voting), every voxel through the TF
// on every TF change. apron = 0: a brick is hit iff one of its own voxels
// has alpha > 0 at its value (the paper; not conservative). apron = 1: every
// trilinear cell a sample in the brick can read is classified by the TF's max
// alpha over the cell's 8 values; the union of those ranges is the brick's
// apron range, so this agrees with range classification exactly.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
#include "nan.glsl"
layout(set = 0, binding = 0) uniform sampler3D volume_tex;
layout(std430, set = 0, binding = 1) readonly buffer TransferLut { vec4 tf_lut[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Flags { uint flags[]; };
layout(push_constant) uniform Push {
    uvec4 dims;   // xyz: volume dims; w: brick edge
    uvec4 counts; // xyz: bricks per axis; w: total bricks
    vec2 norm;
    uint apron;
    uint groups_x;
    uint lut_size;
    uint pad0;
    uint pad1;
    uint pad2;
} pc;

#define TF_MAX_BINDING 2
#define TF_SIZE pc.lut_size
#include "tf_range.glsl"

float value_at(ivec3 i) {
    ivec3 c = clamp(i, ivec3(0), ivec3(pc.dims.xyz) - 1);
    precise float v = (texelFetch(volume_tex, c, 0).r - pc.norm.x) * pc.norm.y;
    return is_nan(v) ? v : clamp(v, 0.0, 1.0);
}

float lut_alpha(float v) {
    precise float x = v * float(TF_SIZE - 1u);
    float fl = floor(x);
    uint i = min(uint(fl), TF_SIZE - 1u);
    uint j = min(i + 1u, TF_SIZE - 1u);
    precise float a = mix(tf_lut[i].a, tf_lut[j].a, x - fl);
    return a;
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
    if (pc.apron == 0u) {
        for (int z = first.z; z <= last.z && !hit; ++z) {
            for (int y = first.y; y <= last.y && !hit; ++y) {
                for (int x = first.x; x <= last.x && !hit; ++x) {
                    float v = value_at(ivec3(x, y, z));
                    hit = !is_nan(v) && lut_alpha(v) > 0.0;
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
                        float v = value_at(ivec3(x, y, z) + ivec3(c & 1, (c >> 1) & 1, c >> 2));
                        no_data = no_data || is_nan(v);
                        mn = min(mn, v);
                        mx = max(mx, v);
                    }
                    // A cell with a NaN voxel has only NaN samples.
                    hit = !no_data && tf_max_alpha(mn, mx) > 0.0;
                }
            }
        }
    }
    flags[b] = hit ? 1u : 0u;
}
