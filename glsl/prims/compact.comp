#version 460
// Stream compaction: out[offsets[i]] = i for every i with flags[i] != 0, where
// offsets is the exclusive scan of flags; the last invocation writes the count.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 256) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Flags { uint flags[]; };
layout(std430, set = 0, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Out { uint indices[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Count { uint count; };
layout(push_constant) uniform Push { uint n; uint groups_x; uint pad0; uint pad1; } pc;

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= pc.n) {
        return;
    }
    uint f = flags[i] != 0u ? 1u : 0u;
    if (f != 0u) {
        indices[offsets[i]] = i;
    }
    if (i == pc.n - 1u) {
        count = offsets[i] + f;
    }
}
