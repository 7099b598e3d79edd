#version 460
// Radix sort pass, step 2: stable scatter by one 4-bit digit. Each thread owns
// ITEMS consecutive items; a per-digit scan over the threads of the block gives
// each thread its rank among equal digits, so equal keys keep their order.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x_id = 0) in;
#include "dispatch.glsl"

// Blocks of 1024 elements (src/prims/scan.rs BLOCK) = WIDTH invocations x
// ITEMS consecutive items, both specialization constants chosen per device
// (src/prims/layout.rs): wide on GPUs, narrow with long serial runs on CPU
// drivers, where every workgroup barrier is expensive.
layout(constant_id = 1) const uint ITEMS = 4u;
const uint WIDTH = gl_WorkGroupSize.x;
layout(std430, set = 0, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = 1) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = 2) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = 3) writeonly buffer ValsOut { uint vals_out[]; };
layout(std430, set = 0, binding = 4) readonly buffer Offsets { uint offsets[]; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint shift; uint blocks; uint digit_mask; uint pad0; uint pad1; uint pad2; } pc;

shared uint ranks[16][WIDTH];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint block = linear_group(pc.groups_x);
    uint base = block * 1024u + lid * ITEMS;
    uint key[ITEMS];
    uint val[ITEMS];
    uint count[16];
    for (uint d = 0u; d < 16u; ++d) {
        count[d] = 0u;
    }
    for (uint i = 0u; i < ITEMS; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            key[i] = keys_in[idx];
            val[i] = vals_in[idx];
            count[(key[i] >> pc.shift) & pc.digit_mask] += 1u;
        }
    }
    for (uint d = 0u; d < 16u; ++d) {
        ranks[d][lid] = count[d];
    }
    barrier();
    for (uint offset = 1u; offset < WIDTH; offset <<= 1u) {
        uint add[16];
        for (uint d = 0u; d < 16u; ++d) {
            add[d] = lid >= offset ? ranks[d][lid - offset] : 0u;
        }
        barrier();
        for (uint d = 0u; d < 16u; ++d) {
            ranks[d][lid] += add[d];
        }
        barrier();
    }
    uint next[16];
    for (uint d = 0u; d < 16u; ++d) {
        next[d] = offsets[d * pc.blocks + block] + ranks[d][lid] - count[d];
    }
    for (uint i = 0u; i < ITEMS; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            uint d = (key[i] >> pc.shift) & pc.digit_mask;
            keys_out[next[d]] = key[i];
            vals_out[next[d]] = val[i];
            next[d] += 1u;
        }
    }
}
