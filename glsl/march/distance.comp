#version 460
// Chebyshev distance-map skipping (Deakin & Knackstedt 2020). From the cell
// holding the ray, a distance d > 0 means the cube of cells within d-1 of it
// is empty (with octant maps: the cells up to d-1 ahead of the ray on every
// axis), so the ray moves to that box's exit in one O(1) step: no stack, no
// tree. An active cell (d = 0) is marched on the global lattice with the
// usual margin, as the grid marches its cells; a distance to the nearest
// empty cell likewise lets the ray cross a whole cube of active cells as one
// span, and active boxes that follow one another are one run (RUN_CELLS,
// lattice.glsl). Only active cells' spans move k, so skipping is exact for
// the same reasons as the grid's 3D-DDA.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"
layout(constant_id = 0) const uint OCTANTS = 0u;

#include "distance_map.glsl"

// One texel a cell (RGBA32UI with OCTANTS, else R32UI): read as texels, as
// llvmpipe loads a storage buffer lane by lane through the stack on a CPU
// with AVX2 (docs/results/samples.md).
layout(set = 0, binding = OWN_BINDING) uniform usamplerBuffer distance_texels;
layout(push_constant) uniform Grid {
    uvec3 counts; // cells per axis
    uint cell;    // cell edge in voxels
    // The octants the map holds distances for (bit o; an octant map may
    // hold fewer than eight), and one of them.
    uint built;
    uint probe;
} grid;

// The words of `cell`: its byte distances, DISTANCE_CHANNELS of them.
uvec4 cell_words(ivec3 cell) {
    ivec3 n = ivec3(grid.counts);
    uint i = uint(cell.x) + uint(n.x) * (uint(cell.y) + uint(n.y) * uint(cell.z));
    return texelFetch(distance_texels, int(i));
}

// The distance from the cell of `words` to the nearest cell of the other
// kind, for a ray of `octant`; 1 (this cell alone) for an octant the map
// does not hold, so such a ray walks cell by cell, exactly.
uint distance_at(uvec4 words, bool is_active, uint octant) {
    uint ch = distance_channel(is_active, octant);
    uint d = distance_byte(words[ch >> 2u], ch);
    return ((grid.built >> octant) & 1u) != 0u ? d : 1u;
}

// A held octant's distance to an active cell is 0 exactly in active cells.
bool active_at(uvec4 words) {
    return distance_byte(words[grid.probe >> 2u], grid.probe) == 0u;
}

// The traversal: the current cell, and whether any cell is left.
struct Walk {
    ivec3 cell;
    bool more;
};

// One step: the box of cells of `w.cell`'s kind (the cube of half-width d-1,
// or with octants the cells up to d-1 ahead on every axis), then on to the
// cell past the box's exit. Returns whether the box is active, and its span.
bool walk_step(inout Walk w, March m, uint octant, float eps, out vec2 span) {
    count_iteration(COUNT_STEP);
    float c = float(grid.cell);
    ivec3 counts = ivec3(grid.counts);
    vec3 dir = m.ray.dir;
    ivec3 stp = ivec3(sign(dir));
    ivec3 cell = w.cell;
    uvec4 words = cell_words(cell);
    bool is_active = active_at(words);
    int d = max(int(distance_at(words, is_active, octant)) - 1, 0);
    ivec3 lo = cell - d;
    ivec3 hi = cell + d;
    if (OCTANTS != 0u) {
        ivec3 far = cell + (ivec3(1) - 2 * ivec3(octant & 1u, (octant >> 1u) & 1u, (octant >> 2u) & 1u)) * d;
        lo = min(cell, far);
        hi = max(cell, far);
    }
    span = vec2(0.0);
    if (is_active) {
        vec3 blo = max(vec3(lo), vec3(0.0)) * c;
        vec3 bhi = min(vec3(hi + 1) * c, vec3(params.dims));
        span = region_span(m, blo, bhi, eps);
    }
    // The exit of the box [lo, hi + 1) * c: the nearest plane ahead.
    float best = 3.4e38;
    int axis = -1;
    for (int a = 0; a < 3; ++a) {
        if (stp[a] != 0) {
            float plane = float(stp[a] > 0 ? hi[a] + 1 : lo[a]) * c;
            precise float t = (plane - m.ray.org[a]) / dir[a];
            if (t < best) {
                best = t;
                axis = a;
            }
        }
    }
    if (axis < 0 || !(best < m.t_exit)) {
        w.more = false;
        return is_active;
    }
    // The next cell: past the box on the exit axis; on the others the exit
    // point's cell, kept within the box and the grid and never behind the
    // current cell (rounding cannot walk the ray backwards, so the walk ends
    // within its guard).
    vec3 q = m.ray.org + best * dir;
    ivec3 next = clamp(ivec3(floor(q / c)), max(lo, ivec3(0)), min(hi, counts - 1));
    next = mix(max(next, cell), min(next, cell), lessThan(stp, ivec3(0)));
    next = mix(next, cell, equal(stp, ivec3(0)));
    next[axis] = stp[axis] > 0 ? hi[axis] + 1 : lo[axis] - 1;
    w.more = next[axis] >= 0 && next[axis] < counts[axis];
    w.cell = next;
    return is_active;
}

// Walks to each run of active boxes (RUN_CELLS, lattice.glsl) in turn and
// marches it: the samples run in a loop of their own, with nothing else in
// it (a CPU SIMD lane executes both sides of a branch, so a loop that either
// samples or walks pays for both on every sample).
void march_distance(inout March m, float eps) {
    float c = float(grid.cell);
    ivec3 counts = ivec3(grid.counts);
    vec3 dir = m.ray.dir;
    // A zero component never crosses its axis; count it as positive.
    uint octant = (dir.x < 0.0 ? 1u : 0u) | (dir.y < 0.0 ? 2u : 0u) | (dir.z < 0.0 ? 4u : 0u);
    Walk w;
    w.cell = clamp(ivec3(floor((m.ray.org + m.t_enter * dir) / c)), ivec3(0), counts - 1);
    w.more = true;
    float run_cap = RUN_CELLS * c;
    // Every step moves at least one cell forward on some axis.
    int guard = counts.x + counts.y + counts.z + 4;
    while (!m.done) {
        vec2 run = vec2(0.0);
        bool found = false;
        while (w.more && guard-- > 0) {
            vec2 span;
            bool joins = walk_step(w, m, octant, eps, span) && span.x < span.y;
            // A box that ends the run is walked past already.
            if (run_add(run, found, joins, span, run_cap)) {
                break;
            }
        }
        if (!found) {
            break;
        }
        march_region(m, run);
    }
}

void march_ray(inout March m) {
    march_distance(m, region_margin(m));
}
