#version 460
// Octree over active bricks: one of the four octree traversals (specialization
// constant 0: 0 = 84, 1 = 89, 2 = 93, 3 = rev) hands the leaves to the march
// in ray order; nonempty leaves' spans are marched on the global lattice.
#extension GL_GOOGLE_include_directive : require

#define PARAMS_BINDING 0
#define VOLUME_BINDING 1
#define TF_BINDING 2
#define FRAME_BINDING 3

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(constant_id = 0) const uint OCTREE_KIND = 3u;

#include "render_params.glsl"
#include "ray.glsl"
#include "camera.glsl"
#include "volume.glsl"
#include "tf.glsl"
#include "lattice.glsl"
#include "octree_node.glsl"

#include "frame_out.glsl"
layout(std430, set = 0, binding = 4) readonly buffer Nodes { OctNode oct_nodes[]; };

March g_march;
float g_eps;

bool octree_leaf(uint node, float t0, float t1) {
    if (oct_nodes[node].info.y != 0u) {
        // The leaf's box with the margin, not the traversal's t-span: the
        // margin covers samples that round into it from a neighbour.
        march_region(g_march, region_span(g_march, oct_nodes[node].lo.xyz, oct_nodes[node].hi.xyz, g_eps));
    }
    return g_march.done;
}

#include "octree_traverse.glsl"

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    if (march_pixel(px, g_march)) {
        g_eps = region_margin(g_march);
        octree_walk(OctRay(g_march.ray.org, g_march.ray.dir, g_march.t_enter, g_march.t_exit));
    }
    frame_store(px, g_march.acc);
}
