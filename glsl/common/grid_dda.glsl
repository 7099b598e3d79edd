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

// Marches active cells between t0 and t1 (already inside the volume span),
// runs of consecutive active cells as one span (RUN_CELLS, lattice.glsl).
// A MIP (MinIP) cell's test reads the running max (min) of the samples
// marched before its run: lower (higher) than after, so it only keeps more
// cells, each sample of which is naive's.
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
    float run_cap = RUN_CELLS * c;
    int guard = counts.x + counts.y + counts.z + 4;
    bool more = true;
    while (more && !m.done) {
        vec2 run = vec2(0.0);
        bool found = false;
        more = false;
        while (guard-- > 0) {
            count_iteration(COUNT_STEP);
            uint index = uint(cell.x) + uint(counts.x) * (uint(cell.y) + uint(counts.y) * uint(cell.z));
            bool joins = false;
            vec2 s = vec2(0.0);
            if (GRID_CELL_ACTIVE(m, index)) {
                vec3 lo = vec3(cell) * c;
                vec3 hi = min(lo + c, vec3(params.dims));
                s = region_span(m, lo, hi, eps);
                s = vec2(max(s.x, t0), min(s.y, t1));
                joins = s.x < s.y;
            }
            bool ends = run_add(run, found, joins, s, run_cap);
            // The nearest crossing of a cell plane along the ray.
            float t_next = 3.4e38;
            int axis = -1;
            for (int a = 0; a < 3; ++a) {
                if (stp[a] != 0) {
                    float plane = float(cell[a] + (stp[a] > 0 ? 1 : 0)) * c;
                    precise float t = (plane - m.ray.org[a]) / dir[a];
                    if (t < t_next) {
                        t_next = t;
                        axis = a;
                    }
                }
            }
            if (axis < 0 || !(t_next < t1)) {
                break;
            }
            cell[axis] += stp[axis];
            if (cell[axis] < 0 || cell[axis] >= counts[axis]) {
                break;
            }
            // A cell that ends the run is stepped past already.
            if (ends) {
                more = true;
                break;
            }
        }
        if (found) {
            march_region(m, run);
        }
    }
}

#endif
