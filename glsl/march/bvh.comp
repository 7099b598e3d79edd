#version 460
// Tree traversal (LBVH and k-d trees share the node format): stack-based,
// front to back; each leaf's span is marched on the global lattice.
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
#include "bvh_node.glsl"

#include "frame_out.glsl"
layout(std430, set = 0, binding = 4) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = 5) readonly buffer Count { uint leaf_count; };

#define TREE_LEAF(m, span, eps) march_region(m, span)
#include "tree_traverse.glsl"

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    March m;
    if (march_pixel(px, m)) {
        traverse_tree(m);
    }
    frame_store(px, m.acc);
}
