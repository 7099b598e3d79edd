// The prologue of every march kernel (glsl/march/*.comp): the common
// bindings, the workgroup, the lattice march and main. A kernel is
//
//     #version 460
//     #extension GL_GOOGLE_include_directive : require
//     #include "march.glsl"
//     ... its own bindings (binding = OWN_BINDING + i; the host binds them by
//     name), specialization constants, push block and traversal ...
//     void march_ray(inout March m) { ... }
//
// march_ray marches pixel's ray m (entered by march_pixel, so m.t_enter <
// m.t_exit) through the structure on the global lattice (lattice.glsl).
#ifndef LACUNA_MARCH_GLSL
#define LACUNA_MARCH_GLSL

#define PARAMS_BINDING 0
#define VOLUME_BINDING 1
#define TF_BINDING 2
#define FRAME_BINDING 3
#define DEPTH_BINDING 4
#define GRADIENT_BINDING 5
#define OWN_BINDING 6

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "render_params.glsl"
#include "ray.glsl"
#include "camera.glsl"
#include "volume.glsl"
#include "tf.glsl"
#include "lattice.glsl"
#include "frame_out.glsl"

void march_ray(inout March m);

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    March m;
    if (march_pixel(px, m)) {
        march_ray(m);
        if (MARCH_MODE == MODE_ISO) {
            iso_refine(m);
        }
    }
    frame_store(px, march_result(m));
    // Only iso frames hit a surface; the others write the far depth.
    if (params.depth_out != 0u) {
        depth_store(px, march_depth(m));
    }
}

#endif
