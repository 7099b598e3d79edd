#version 460
// Radix sort pass, step 1: per-block histogram of one 4-bit digit, written
// digit-major (hist[digit * blocks + block]) so one exclusive scan yields every
// block's scatter base for every digit.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x_id = 0) in;
#include "dispatch.glsl"

// Blocks of 1024 elements (src/prims/scan.rs BLOCK) = WIDTH invocations x
// ITEMS consecutive items, both specialization constants chosen per device
// (src/prims/layout.rs): wide on GPUs, narrow with long serial runs on CPU
// drivers, where every workgroup barrier is expensive.
layout(constant_id = 1) const uint ITEMS = 4u;
const uint WIDTH = gl_WorkGroupSize.x;
layout(std430, set = 0, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Hist { uint hist[]; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint shift; uint blocks; uint digit_mask; uint pad0; uint pad1; uint pad2; } pc;

shared uint counts[16];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint block = linear_group(pc.groups_x);
    if (lid < 16u) {
        counts[lid] = 0u;
    }
    barrier();
    uint base = block * 1024u + lid * ITEMS;
    for (uint i = 0u; i < ITEMS; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            atomicAdd(counts[(keys[idx] >> pc.shift) & pc.digit_mask], 1u);
        }
    }
    barrier();
    if (lid < 16u) {
        hist[lid * pc.blocks + block] = counts[lid];
    }
}
