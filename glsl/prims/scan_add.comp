#version 460
// Adds each block's scanned offset to its 1024 elements (second half of a
// multi-level scan).
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
layout(std430, set = 0, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint pad0; uint pad1; } pc;

void main() {
    uint block = linear_group(pc.groups_x);
    uint add = offsets[block];
    uint base = block * 1024u + gl_LocalInvocationID.x * ITEMS;
    for (uint i = 0u; i < ITEMS; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            data[idx] += add;
        }
    }
}
