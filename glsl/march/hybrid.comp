#version 460
// Hybrid grid: a shallow k-d tree traversed front to back; inside each leaf,
// 3D-DDA over the global macro-cell grid, marching active cells only.
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
layout(std430, set = 0, binding = 6) readonly buffer CellFlags { uint cell_flags[]; };
layout(push_constant) uniform Grid { uvec4 cells; } grid;

#define GRID_CELL grid.cells.w
#define GRID_COUNTS grid.cells.xyz
#include "grid_dda.glsl"
#define TREE_LEAF(m, span, eps) march_grid(m, span.x, span.y, eps)
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
