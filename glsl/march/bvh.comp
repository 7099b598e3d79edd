#version 460
// LBVH traversal: stack-based, front to back (children by entry t). Siblings
// of a Morton-split LBVH lie on opposite sides of a plane, so leaves arrive in
// ray order; each leaf's span is marched on the global lattice.
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
#define TF_SIZE params.dims.w
#include "tf.glsl"
#include "lattice.glsl"
#include "bvh_node.glsl"

layout(std430, set = 0, binding = FRAME_BINDING) writeonly buffer Frame { vec4 frame[]; };
layout(std430, set = 0, binding = 4) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = 5) readonly buffer Count { uint leaf_count; };

vec2 node_span(March m, int node, float eps) {
    return region_span(m, vec3(nodes[node].lo.xyz), vec3(nodes[node].hi.xyz), eps);
}

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    March m;
    if (march_begin(camera_ray(px), params.march.x, m) && leaf_count > 0u) {
        float eps = region_margin(m);
        int stack[64];
        int sp = 0;
        stack[sp++] = 0;
        while (sp > 0 && !m.done) {
            int node = stack[--sp];
            vec2 span = node_span(m, node, eps);
            // Missed, or wholly behind the samples already taken.
            if (!(span.x < span.y) || !(span.y > lattice_t(m, m.k))) {
                continue;
            }
            int left = nodes[node].lo.w;
            if (left < 0) {
                march_region(m, span);
                continue;
            }
            int right = nodes[node].hi.w;
            vec2 sl = node_span(m, left, eps);
            vec2 sr = node_span(m, right, eps);
            bool hl = sl.x < sl.y;
            bool hr = sr.x < sr.y;
            if (hl && hr) {
                bool left_first = sl.x <= sr.x;
                stack[sp++] = left_first ? right : left;
                stack[sp++] = left_first ? left : right;
            } else if (hl) {
                stack[sp++] = left;
            } else if (hr) {
                stack[sp++] = right;
            }
        }
    }
    frame[px.y * params.image.x + px.x] = m.acc;
}
