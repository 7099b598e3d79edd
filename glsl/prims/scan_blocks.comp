#version 460
// Exclusive scan of u32, in place, per block of 1024 elements (WIDTH threads x
// ITEMS consecutive items); writes each block's total to `sums` for the next level.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x_id = 0) in;
#include "dispatch.glsl"

// Blocks of 1024 elements (src/prims/scan.rs BLOCK) = WIDTH invocations x
// ITEMS consecutive items, both specialization constants chosen per device
// (src/prims/layout.rs): wide on GPUs, narrow with long serial runs on CPU
// drivers, where every workgroup barrier is expensive.
layout(constant_id = 1) const uint ITEMS = 4u;
const uint WIDTH = gl_WorkGroupSize.x;
layout(std430, set = 0, binding = 0) buffer Data { uint data[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint write_sums; uint pad; } pc;

shared uint partial[WIDTH];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint block = linear_group(pc.groups_x);
    uint base = block * 1024u + lid * ITEMS;
    uint v[ITEMS];
    uint total = 0u;
    for (uint i = 0u; i < ITEMS; ++i) {
        uint idx = base + i;
        v[i] = idx < pc.n ? data[idx] : 0u;
        total += v[i];
    }
    partial[lid] = total;
    barrier();
    // Hillis-Steele inclusive scan of the thread totals.
    for (uint offset = 1u; offset < WIDTH; offset <<= 1u) {
        uint add = lid >= offset ? partial[lid - offset] : 0u;
        barrier();
        partial[lid] += add;
        barrier();
    }
    uint running = partial[lid] - total;
    for (uint i = 0u; i < ITEMS; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            data[idx] = running;
        }
        running += v[i];
    }
    if (lid == WIDTH - 1u && pc.write_sums != 0u) {
        sums[block] = partial[WIDTH - 1u];
    }
}
