#version 460
// Macro-cell grid: 3D-DDA over the cells from entry to exit, marching the
// active ones on the global lattice.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"

layout(std430, set = 0, binding = OWN_BINDING) readonly buffer CellFlags { uint cell_flags[]; };
layout(push_constant) uniform Grid {
    uvec3 counts; // cells per axis
    uint cell;    // cell edge in voxels
} grid;

#define GRID_CELL grid.cell
#define GRID_COUNTS grid.counts
#include "grid_dda.glsl"

void march_ray(inout March m) {
    march_grid(m, m.t_enter, m.t_exit, region_margin(m));
}
