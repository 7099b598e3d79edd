#version 460
// Macro-cell grid: 3D-DDA over the cells from entry to exit, marching the
// active ones on the global lattice.
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

#include "frame_out.glsl"
layout(std430, set = 0, binding = 4) readonly buffer CellFlags { uint cell_flags[]; };
layout(push_constant) uniform Grid { uvec4 cells; } grid; // xyz: cells per axis; w: cell edge

#define GRID_CELL grid.cells.w
#define GRID_COUNTS grid.cells.xyz
#include "grid_dda.glsl"

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    March m;
    if (march_pixel(px, m)) {
        march_grid(m, m.t_enter, m.t_exit, region_margin(m));
    }
    frame_store(px, m.acc);
}
