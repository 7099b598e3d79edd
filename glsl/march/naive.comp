#version 460
// Naive ray marching: every lattice sample from entry to exit.
#extension GL_GOOGLE_include_directive : require

#define PARAMS_BINDING 0
#define VOLUME_BINDING 1
#define TF_BINDING 2
#define FRAME_BINDING 3

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "render_params.glsl"
#include "ray.glsl"
#include "camera.glsl"
#include "volume.glsl"
#include "tf.glsl"
#include "lattice.glsl"

#include "frame_out.glsl"

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    March m;
    if (march_pixel(px, m)) {
        march_rest(m);
    }
    frame_store(px, m.acc);
}
