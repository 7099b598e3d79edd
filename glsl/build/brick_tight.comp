#version 460
// Per-8^3-brick tight box of the active voxel footprints (k-d tree on the
// GPU). A footprint [i, i+1]^3 is active iff the TF's max alpha over the 27
// voxels its samples can read is > 0 (DESIGN invariant 2), NaN voxels ignored,
// in any channel (each by its own TF; one channel staged at a time). The brick and its
// one-voxel apron are staged in shared memory; the box is reduced there with
// atomics. An empty brick writes an inverted box (lo = INT_MAX, hi = INT_MIN).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
#include "nan.glsl"

layout(set = 0, binding = 0) uniform sampler3D volume_tex;
layout(std430, set = 0, binding = 2) writeonly buffer Boxes { ivec4 boxes[]; }; // lo, hi (exclusive) per brick
#define BRICK_TABLE_BINDING 3
#define POOL_BINDING 4
#include "bricks.glsl"
layout(push_constant) uniform Push {
    uvec4 dims;   // xyz: volume dims; w: brick edge (8)
    uvec4 counts; // xyz: bricks per axis; w: total bricks
    vec4 lo;      // per channel: v = (texel - lo) * scale
    vec4 scale;
    uint groups_x;
    uint lut_size;
    uint channels;
    uint tf_stride; // entries between channels' max tables (0: one for all)
    uint pool_brick; // bricked storage: the pool's brick edge (0: dense)
    uint pad0;
    uint pad1;
    uint pad2;
} pc;

#define TF_MAX_BINDING 1
#define TF_SIZE pc.lut_size
#include "tf_range.glsl"

const int B = 8;
const int S = B + 2; // staged edge: brick plus apron
shared float staged[S * S * S];
shared int box[6];

// Widens the brick's box by every voxel whose footprint is active in the
// staged channel (its max table at `table`).
void mark_active(ivec3 origin, ivec3 hi, uint lid, uint table) {
    for (uint i = lid; i < uint(B * B * B); i += 64u) {
        ivec3 l = ivec3(int(i) % B, (int(i) / B) % B, int(i) / (B * B));
        ivec3 v = origin + l;
        if (any(greaterThan(v, hi))) {
            continue;
        }
        float mn = 3.4e38;
        float mx = -3.4e38;
        for (int dz = 0; dz < 3; ++dz) {
            for (int dy = 0; dy < 3; ++dy) {
                for (int dx = 0; dx < 3; ++dx) {
                    // Staged index of voxel v + (d - 1), clamped like the volume.
                    ivec3 s = clamp(v + ivec3(dx, dy, dz) - 1, ivec3(0), hi) - origin + 1;
                    float x = staged[s.x + S * (s.y + S * s.z)];
                    if (!is_nan(x)) {
                        mn = min(mn, x);
                        mx = max(mx, x);
                    }
                }
            }
        }
        if (tf_max_alpha_at(table, mn, mx) > 0.0) {
            atomicMin(box[0], v.x);
            atomicMin(box[1], v.y);
            atomicMin(box[2], v.z);
            atomicMax(box[3], v.x + 1);
            atomicMax(box[4], v.y + 1);
            atomicMax(box[5], v.z + 1);
        }
    }
}

void main() {
    uint b = linear_group(pc.groups_x);
    if (b >= pc.counts.w) {
        return;
    }
    uint lid = gl_LocalInvocationID.x;
    uvec3 bc = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    ivec3 origin = ivec3(bc) * B;
    ivec3 hi = ivec3(pc.dims.xyz) - 1;
    if (lid < 3u) {
        box[lid] = 0x7FFFFFFF;
        box[lid + 3u] = int(0x80000000);
    }
    for (uint ch = 0u; ch < pc.channels; ++ch) {
        // The previous channel's reads of the staged voxels come first.
        barrier();
        for (uint i = lid; i < uint(S * S * S); i += 64u) {
            ivec3 l = ivec3(int(i) % S, (int(i) / S) % S, int(i) / (S * S));
            vec4 t = stored_voxel(origin + l - 1, hi, int(pc.pool_brick));
            precise float n = (t[ch] - pc.lo[ch]) * pc.scale[ch];
            staged[i] = is_nan(n) ? n : clamp(n, 0.0, 1.0);
        }
        barrier();
        mark_active(origin, hi, lid, ch * pc.tf_stride);
    }
    barrier();
    if (lid == 0u) {
        boxes[2u * b] = ivec4(box[0], box[1], box[2], 0);
        boxes[2u * b + 1u] = ivec4(box[3], box[4], box[5], 0);
    }
}
