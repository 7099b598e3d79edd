#version 460
// Range classification: a brick is active iff the TF's max alpha over its
// value range (apron included) is > 0, in any channel (each by its own TF).
// O(bricks) per TF change.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Ranges { vec2 ranges[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Flags { uint flags[]; };
layout(push_constant) uniform Push {
    uint bricks;
    uint groups_x;
    uint lut_size;
    uint tf_stride; // entries between channels' max tables (0: one for all)
} pc;

// The channel count is a constant: lavapipe runs a loop's body at least
// once and branches no lane takes, so a run-time count cost every brick.
layout(constant_id = 0) const uint CHANNELS = 1u;

#define TF_MAX_BINDING 1
#define TF_SIZE pc.lut_size
#include "tf_range.glsl"

void main() {
    uint b = linear_index(pc.groups_x);
    if (b >= pc.bricks) {
        return;
    }
    bool on = false;
    for (uint c = 0u; c < CHANNELS; ++c) {
        vec2 r = ranges[b * CHANNELS + c];
        on = on || tf_max_alpha_at(c * pc.tf_stride, r.x, r.y) > 0.0;
    }
    flags[b] = on ? 1u : 0u;
}
