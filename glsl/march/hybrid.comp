#version 460
// Hybrid grid: a shallow k-d tree traversed front to back; inside each leaf,
// 3D-DDA over the global macro-cell grid, marching active cells only.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"

#include "bvh_node.glsl"

layout(std430, set = 0, binding = OWN_BINDING) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = OWN_BINDING + 1) readonly buffer Count { uint leaf_count; };
// The grid's flags, a texel a cell (R32UI; grid.comp says why texels).
layout(set = 0, binding = OWN_BINDING + 2) uniform usamplerBuffer cell_flags;
layout(push_constant) uniform Grid {
    uvec3 counts; // cells per axis
    uint cell;    // cell edge in voxels
} grid;

#define GRID_CELL grid.cell
#define GRID_COUNTS grid.counts
#define GRID_CELL_ACTIVE(m, i) (texelFetch(cell_flags, int(i)).x != 0u)
#include "grid_dda.glsl"
#define TREE_LEAF(m, span, eps) march_grid(m, span.x, span.y, eps)
#include "tree_traverse.glsl"

void march_ray(inout March m) {
    traverse_tree(m);
}
