#version 460
// Per-pixel ray limits from a host's depth image: where the camera ray of
// each pixel meets the host's opaque surface, as t along the ray in voxels.
// The march kernels end their rays there (lattice.glsl, march_pixel).
#extension GL_GOOGLE_include_directive : require

#define PARAMS_BINDING 0
// This pass writes the t_max array of the parameter block.
#define PARAMS_ACCESS

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "render_params.glsl"
#include "ray.glsl"
#include "camera.glsl"

// The host's depth (its first component), read with texelFetch: one texel per pixel.
layout(set = 0, binding = 1) uniform sampler2D depth_image;

const float NO_LIMIT = 3.4e38;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    float d = texelFetch(depth_image, ivec2(px), 0).r;
    float limit = NO_LIMIT;
    // The far plane's depth is where nothing was drawn.
    if (d != params.far_depth) {
        precise vec2 ndc = (vec2(px) + 0.5) * 2.0 / vec2(params.image.xy) - 1.0;
        precise vec4 q = params.ndc_to_voxel * vec4(ndc, d, 1.0);
        if (q.w != 0.0) {
            Ray r = camera_ray(px);
            precise vec3 p = q.xyz / q.w;
            precise float t = dot(p - r.org, r.dir);
            // A surface behind the ray's start ends it before it begins.
            limit = abs(t) < NO_LIMIT ? t : (t < 0.0 ? 0.0 : NO_LIMIT);
        }
    }
    params.t_max[px.y * params.image.x + px.x] = limit;
}
