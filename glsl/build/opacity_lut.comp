#version 460
// The march kernels' LUT for one frame (glsl/common/tf.glsl): entries
// 0..n-1 the transfer function with alpha corrected for the frame's step dt,
// entries n..2n-1 the raw one, for the ray's shortened last sample; with a
// transfer function per channel, channel c's two tables at 2 n c.
#extension GL_GOOGLE_include_directive : require
#include "opacity.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Raw { vec4 raw[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Lut { vec4 lut[]; };
layout(push_constant) uniform Push { float dt; uint n; uint channels; } pc;

void main() {
    uint e = gl_GlobalInvocationID.x;
    if (e >= pc.n * pc.channels) {
        return;
    }
    uint i = e % pc.n;
    uint base = 2u * (e - i);
    vec4 c = raw[e];
    lut[base + i] = vec4(c.rgb, opacity(c.a, pc.dt));
    lut[base + pc.n + i] = c;
}
