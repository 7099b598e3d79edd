#version 460
// Morton codes of bricks' coordinates (a listed subset, or all of them);
// the payload is the brick index.
#extension GL_GOOGLE_include_directive : require
#include "morton.glsl"

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer ActiveBricks { uint active_bricks[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Codes { uint codes[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Payload { uint payload[]; };
layout(push_constant) uniform Push { uvec4 counts; uint n; uint groups_x; uint identity; uint pad; } pc;

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= pc.n) {
        return;
    }
    // identity = 1: code every brick (i is the brick index), not a list.
    uint b = pc.identity != 0u ? i : active_bricks[i];
    // A list entry past the active count (a capacity-sized LBVH build fills
    // the list with ~0 first): the largest 30-bit key, which the stable sort
    // keeps after every active brick.
    if (b == 0xFFFFFFFFu) {
        codes[i] = (1u << 30) - 1u;
        payload[i] = b;
        return;
    }
    uvec3 c = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    codes[i] = morton3(c);
    payload[i] = b;
}
