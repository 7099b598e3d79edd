#version 460
// One 1-D pass of the separable Chebyshev distance transform for cube maps,
// in linear time: one invocation per grid row along `axis`, computing
//   d(x) = min over i of max(|x - i|, g(i))
// as the lower envelope of the functions max(|x - i|, g(i)) (Meijster,
// Roerdink & Hesselink 2000, chessboard metric), for both channels (to the
// nearest active cell, to the nearest empty cell). The first pass reads the
// active flags: g = 0 for a cell of the kind sought, CAP otherwise; a capped
// g only lowers results, so distances stay safe underestimates.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#define OCTANTS 0u
#include "dispatch.glsl"
#include "distance_map.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 1) buffer Dst { uint dst[]; };
// Per row, the envelope's entries below the top: apex, its g, its start
// (3 words per cell).
layout(std430, set = 0, binding = 2) buffer Stack { uint stack[]; };
// Specialization constant 0 (the host sets it for rows of at most
// PRIVATE_ROW cells): the envelope lives in private arrays instead. lavapipe
// reads and writes a storage buffer one lane at a time with a bounds check
// each, and in private arrays the rebuild of 32^3 cells ran about 1.6x faster.
layout(constant_id = 0) const uint PRIVATE_STACK = 0u;
#define PRIVATE_ROW 64
uint private_s[PRIVATE_ROW];
uint private_g[PRIVATE_ROW];
uint private_t[PRIVATE_ROW];

void stack_write(uint base, int q, int s, int gs, int t) {
    if (PRIVATE_STACK != 0u) {
        private_s[q] = uint(s);
        private_g[q] = uint(gs);
        private_t[q] = uint(t);
    } else {
        uint e = base + 3u * uint(q);
        stack[e] = uint(s);
        stack[e + 1u] = uint(gs);
        stack[e + 2u] = uint(t);
    }
}

// Entry q: (apex, its g, its start).
ivec3 stack_read(uint base, int q) {
    if (PRIVATE_STACK != 0u) {
        return ivec3(private_s[q], private_g[q], private_t[q]);
    }
    uint e = base + 3u * uint(q);
    return ivec3(stack[e], stack[e + 1u], stack[e + 2u]);
}
// xyz: cells per axis, w: total; axis: 0, 1, 2.
layout(push_constant) uniform Push { uvec4 counts; uint axis; uint groups_x; uint rows; } pc;
// Specialization constant 1: the pass reads the active flags (the first
// pass, along x) rather than map words. A constant, as lavapipe would
// otherwise read both at every cell (it runs every side of an `if`).
layout(constant_id = 1) const uint FIRST = 0u;

// A row's cells are origin + x * stride: the divisions (scalarised on a
// CPU device, about a third of the pass) run once per row, not per cell.
struct Row {
    uint origin;
    uint stride;
};

Row row_cells(uint row) {
    uvec3 c;
    // The lower other axis varies fastest from row to row: neighbouring
    // lanes' cells are neighbours in memory along y and z passes (x then
    // varies fastest; with z, lanes of a y pass read a plane apart each,
    // and the pass took 2.3 times as long as the z pass).
    uint a1 = pc.axis == 0u ? 1u : 0u;
    uint a2 = pc.axis == 2u ? 1u : 3u - pc.axis - a1;
    c[pc.axis] = 0u;
    c[a1] = row % pc.counts[a1];
    c[a2] = row / pc.counts[a1];
    uint stride = pc.axis == 0u ? 1u : (pc.axis == 1u ? pc.counts.x : pc.counts.x * pc.counts.y);
    return Row(c.x + pc.counts.x * (c.y + pc.counts.y * c.z), stride);
}

uint cell_index(Row r, uint x) {
    return r.origin + x * r.stride;
}

int g(Row cells, uint x, uint channel) {
    uint i = cell_index(cells, x);
    if (FIRST != 0u) {
        bool is_active = src[i] != 0u;
        return is_active == (channel == 0u) ? 0 : int(DISTANCE_CAP);
    }
    return int(distance_byte(src[i], channel));
}

int f(int x, int i, int gi) {
    return max(abs(x - i), gi);
}

// The first x from which apex u's function is below apex i's (i < u).
int sep(int i, int u, int gi, int gu) {
    int mid = (i + u) / 2;
    return gi <= gu ? max(i + gu, mid) : min(u - gi, mid);
}

void main() {
    uint row = linear_index(pc.groups_x);
    if (row >= pc.rows) {
        return;
    }
    Row cells = row_cells(row);
    int n = int(pc.counts[pc.axis]);
    uint base = 3u * row * uint(n);
    for (uint ch = 0u; ch < 2u; ++ch) {
        // Envelope entry q: apex s, its g, and the start t of its interval.
        int q = 0;
        int s = 0;
        int gs = g(cells, 0u, ch);
        int t = 0;
        for (int u = 1; u < n; ++u) {
            int gu = g(cells, uint(u), ch);
            while (q >= 0 && f(t, s, gs) > f(t, u, gu)) {
                q -= 1;
                if (q >= 0) {
                    ivec3 top = stack_read(base, q);
                    s = top.x;
                    gs = top.y;
                    t = top.z;
                }
            }
            int w = q < 0 ? 0 : 1 + sep(s, u, gs, gu);
            if (q < 0 || w < n) {
                if (q >= 0) {
                    stack_write(base, q, s, gs, t);
                }
                q += 1;
                s = u;
                gs = gu;
                t = w;
            }
        }
        // The top entry lives in (s, gs, t); the ones below it on the stack.
        for (int x = n - 1; x >= 0; --x) {
            uint d = uint(min(f(x, s, gs), int(DISTANCE_CAP)));
            uint i = cell_index(cells, uint(x));
            dst[i] = ch == 0u ? d : (dst[i] | d << 8u);
            if (x == t && q > 0) {
                q -= 1;
                ivec3 top = stack_read(base, q);
                s = top.x;
                gs = top.y;
                t = top.z;
            }
        }
    }
}
