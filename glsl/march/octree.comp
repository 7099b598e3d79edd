#version 460
// Octree over active bricks: one of the four octree traversals (specialization
// constant 0: 0 = 84, 1 = 89, 2 = 93, 3 = rev) hands the leaves to the march
// in ray order; nonempty leaves' spans are marched on the global lattice.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"
layout(constant_id = 0) const uint OCTREE_KIND = 3u;

#include "octree_node.glsl"

layout(std430, set = 0, binding = OWN_BINDING) readonly buffer Nodes { OctNode oct_nodes[]; };

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

// The traversal's leaf callback reads the march from globals.
void march_ray(inout March m) {
    g_march = m;
    g_eps = region_margin(m);
    octree_walk(OctRay(m.ray.org, m.ray.dir, m.t_enter, m.t_exit));
    m = g_march;
}
