#version 460
// Exclusive scan of u32, in place, per block of 1024 elements (256 threads x 4
// consecutive items); writes each block's total to `sums` for the next level.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 256) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) buffer Data { uint data[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint write_sums; uint pad; } pc;

shared uint partial[256];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint block = linear_group(pc.groups_x);
    uint base = block * 1024u + lid * 4u;
    uint v[4];
    uint total = 0u;
    for (uint i = 0u; i < 4u; ++i) {
        uint idx = base + i;
        v[i] = idx < pc.n ? data[idx] : 0u;
        total += v[i];
    }
    partial[lid] = total;
    barrier();
    // Hillis-Steele inclusive scan of the 256 thread totals.
    for (uint offset = 1u; offset < 256u; offset <<= 1u) {
        uint add = lid >= offset ? partial[lid - offset] : 0u;
        barrier();
        partial[lid] += add;
        barrier();
    }
    uint running = partial[lid] - total;
    for (uint i = 0u; i < 4u; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            data[idx] = running;
        }
        running += v[i];
    }
    if (lid == 255u && pc.write_sums != 0u) {
        sums[block] = partial[255];
    }
}
