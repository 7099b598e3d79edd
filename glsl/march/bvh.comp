#version 460
// Tree traversal (LBVH and k-d trees share the node format): stack-based,
// front to back; each leaf's span is marched on the global lattice.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"

#include "bvh_node.glsl"

layout(std430, set = 0, binding = OWN_BINDING) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = OWN_BINDING + 1) readonly buffer Count { uint leaf_count; };

#define TREE_LEAF(m, span, eps) march_region(m, span)
#include "tree_traverse.glsl"

void march_ray(inout March m) {
    traverse_tree(m);
}
