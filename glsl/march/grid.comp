#version 460
// Macro-cell grid: 3D-DDA over the cells from entry to exit, marching the
// active ones on the global lattice. A cell is active by its flag (the
// frame's classification), or in MIP (MinIP) frames by its value range
// against the ray's running max (min) from before the run it joins
// (grid_dda.glsl): no higher (lower) than at the cell, so it keeps no fewer.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"

// Per cell, one texel: a flag (composite, iso; R32UI), or the bits of its
// normalised value range over the apron, (min, max) (mip, minip; RG32UI:
// src/accel/grid.rs). Texels, as llvmpipe loads a storage buffer lane by
// lane through the stack on an AVX2 CPU (docs/results/samples.md).
layout(set = 0, binding = OWN_BINDING) uniform usamplerBuffer cell_texels;
layout(push_constant) uniform Grid {
    uvec3 counts; // cells per axis
    uint cell;    // cell edge in voxels
} grid;

// A cell can change a MIP pixel only if some sample in it can exceed both
// the running max and every value the TF maps to transparent; samples lie
// within the cell's range widened by value_margin (src/accel/mode.rs).
// Several channels classify by flags in every mode (src/accel/grid.rs).
bool grid_cell_active(March m, uint i) {
    uvec4 cell = texelFetch(cell_texels, int(i));
    if (MARCH_MODE == MODE_MIP && VOLUME_CHANNELS == 1u) {
        float hi = uintBitsToFloat(cell.y);
        return hi + params.value_margin > max(m.best, params.value_bound);
    }
    if (MARCH_MODE == MODE_MINIP && VOLUME_CHANNELS == 1u) {
        float lo = uintBitsToFloat(cell.x);
        return lo - params.value_margin < min(m.best, params.value_bound);
    }
    return cell.x != 0u;
}

#define GRID_CELL grid.cell
#define GRID_COUNTS grid.counts
#define GRID_CELL_ACTIVE(m, i) grid_cell_active(m, i)
#include "grid_dda.glsl"

void march_ray(inout March m) {
    march_grid(m, m.t_enter, m.t_exit, region_margin(m));
}
