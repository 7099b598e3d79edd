#version 460
// Adds each block's scanned offset to its 1024 elements (second half of a
// multi-level scan).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 256) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) buffer Data { uint data[]; };
layout(std430, set = 0, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint pad0; uint pad1; } pc;

void main() {
    uint block = linear_group(pc.groups_x);
    uint add = offsets[block];
    uint base = block * 1024u + gl_LocalInvocationID.x * 4u;
    for (uint i = 0u; i < 4u; ++i) {
        uint idx = base + i;
        if (idx < pc.n) {
            data[idx] += add;
        }
    }
}
