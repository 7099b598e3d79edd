#version 460
// Morton codes of the active bricks' coordinates; the payload is the brick index.
#extension GL_GOOGLE_include_directive : require
#include "morton.glsl"

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer ActiveBricks { uint active_bricks[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Codes { uint codes[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Payload { uint payload[]; };
layout(push_constant) uniform Push { uvec4 counts; uint n; uint groups_x; } pc;

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= pc.n) {
        return;
    }
    uint b = active_bricks[i];
    uvec3 c = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    codes[i] = morton3(c);
    payload[i] = b;
}
