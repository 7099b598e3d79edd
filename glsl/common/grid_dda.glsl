// 3D-DDA (Amanatides & Woo) over the macro-cell grid, marching the active
// cells' spans in ray order. The crossing to the next cell is recomputed from
// the cell's planes at every step (no accumulated error); a direction
// component of exactly 0 never crosses its axis. Cell spans come from the
// cell boxes with the usual margin, so a cell the DDA grazes past within
// rounding is still covered by its neighbours' margins. The includer
// provides GRID_CELL (edge in voxels), GRID_COUNTS and GRID_CELL_ACTIVE(m, i)
// (whether ray m marches cell i).
#ifndef LACUNA_GRID_DDA_GLSL
#define LACUNA_GRID_DDA_GLSL

// Marches active cells between t0 and t1 (already inside the volume span).
void march_grid(inout March m, float t0, float t1, float eps) {
    if (!(t0 < t1) || m.done) {
        return;
    }
    float c = float(GRID_CELL);
    ivec3 counts = ivec3(GRID_COUNTS);
    vec3 dir = m.ray.dir;
    vec3 p = m.ray.org + max(t0, m.t_enter) * dir;
    ivec3 cell = clamp(ivec3(floor(p / c)), ivec3(0), counts - 1);
    ivec3 stp = ivec3(sign(dir));
    int guard = counts.x + counts.y + counts.z + 4;
    while (guard-- > 0 && !m.done) {
        count_iteration(COUNT_STEP);
        uint index = uint(cell.x) + uint(counts.x) * (uint(cell.y) + uint(counts.y) * uint(cell.z));
        if (GRID_CELL_ACTIVE(m, index)) {
            vec3 lo = vec3(cell) * c;
            vec3 hi = min(lo + c, vec3(params.dims));
            vec2 s = region_span(m, lo, hi, eps);
            march_region(m, vec2(max(s.x, t0), min(s.y, t1)));
        }
        // The nearest crossing of a cell plane along the ray.
        float best = 3.4e38;
        int axis = -1;
        for (int a = 0; a < 3; ++a) {
            if (stp[a] != 0) {
                float plane = float(cell[a] + (stp[a] > 0 ? 1 : 0)) * c;
                precise float t = (plane - m.ray.org[a]) / dir[a];
                if (t < best) {
                    best = t;
                    axis = a;
                }
            }
        }
        if (axis < 0 || !(best < t1)) {
            return;
        }
        cell[axis] += stp[axis];
        if (cell[axis] < 0 || cell[axis] >= counts[axis]) {
            return;
        }
    }
}

#endif
