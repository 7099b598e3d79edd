#version 460
// One 1-D pass of the separable one-sided Chebyshev distance transform for
// octant maps, in linear time. An octant channel counts only cells ahead of
// its ray octant, so along `axis` it needs, per row,
//   d(x) = min over i ahead of x (i >= x, or i <= x for a negative octant)
//          of max(|x - i|, g(i)),
// and min-of-max separates over the axes like the two-sided transform. The
// row is swept from its far end towards the ray: candidates live in a deque
// ordered by distance, the nearest at the front. A new cell evicts the
// front entries whose g is not smaller (it is nearer and no worse, for good),
// and the back entry leaves once the one before it is as good: from then on
// the back's value grows by one a cell and its neighbour's by at most one.
// So the back holds the minimum and every cell enters and leaves once.
// After the pass along x a channel depends only on its octant's x sign, and
// after y only on the x and y signs: passes x and y compute those channels
// once and copy them to the octants that differ only in later signs. Only
// the channels of the octants the frames need are computed (the host's
// tasks); the march never reads the others. One invocation per row and task
// (a z sign and the channels of it to compute), sweeping both kinds of
// distance at once: one row walk, one flag read along x.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#define OCTANTS 1u
#include "dispatch.glsl"
#include "distance_map.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 1) buffer Dst { uint dst[]; };
// Per (row, task): two deques (the two kinds), each one entry per cell of
// the row (position << 8 | g).
layout(std430, set = 0, binding = 2) buffer Deque { uint deque[]; };
// Specialization constant 0 (the host sets it for rows of at most
// PRIVATE_ROW cells): the deque and the row's output words live in private
// arrays instead, and each output word is written once. lavapipe reads and
// writes a storage buffer one lane at a time with a bounds check each (as
// distance_rows.comp's envelope). Reading each source word once into a
// private array as well saved nothing measurable: the deque's loops are
// the cost.
layout(constant_id = 0) const uint PRIVATE_DEQUE = 0u;
#define PRIVATE_ROW 64
uint private_deque[2 * PRIVATE_ROW];
uint private_out[2 * PRIVATE_ROW];

// Entry k of the deque at `base` (the kind's offset, plus the row's and
// task's in the storage buffer).
uint deque_read(uint base, uint k) {
    return PRIVATE_DEQUE != 0u ? private_deque[base + k] : deque[base + k];
}

void deque_write(uint base, uint k, uint entry) {
    if (PRIVATE_DEQUE != 0u) {
        private_deque[base + k] = entry;
    } else {
        deque[base + k] = entry;
    }
}
// xyz: cells per axis, w: total; axis: 0, 1, 2. Each of `tasks` tasks
// (`task`): bit 0 the map word read for distances to active cells (0 or
// 1: channels 4 * word to 4 * word + 3; to empty cells, word + 2), bits
// 2-4 how many of its bytes to compute, bits 8-15 which (two bits each),
// bits 16-17 the words written: the word itself, the next (the same
// channels for the other z sign, from passes x and y).
layout(push_constant) uniform Push {
    uvec4 counts;
    uint axis;
    uint groups_x;
    uint rows;
    uint tasks;
    uvec4 task;
} pc;
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

// The source distances of cell i for the two kinds: channels ch and ch + 8.
uvec2 g(uint i, uint ch) {
    if (FIRST != 0u) {
        bool is_active = src[i] != 0u;
        return is_active ? uvec2(0u, DISTANCE_CAP) : uvec2(DISTANCE_CAP, 0u);
    }
    uint c1 = ch + DISTANCE_CHANNELS / 2u;
    return uvec2(distance_byte(src[DISTANCE_WORDS * i + (ch >> 2u)], ch),
                 distance_byte(src[DISTANCE_WORDS * i + (c1 >> 2u)], c1));
}

// An entry's value seen from x: max(distance, g).
uint value(uint entry, int x) {
    return max(uint(abs(int(entry >> 8u) - x)), entry & 255u);
}

// Adds cell x (value gx) to the deque [back, front) and returns the
// minimum seen from x.
uint deque_step(uint base, int x, uint gx, inout uint front, inout uint back) {
    while (front > back && (deque_read(base, front - 1u) & 255u) >= gx) {
        front -= 1u;
    }
    deque_write(base, front, uint(x) << 8u | gx);
    front += 1u;
    uint best = value(deque_read(base, back), x);
    while (front - back >= 2u) {
        uint next = value(deque_read(base, back + 1u), x);
        if (next > best) {
            break;
        }
        back += 1u;
        best = next;
    }
    return best;
}

void main() {
    uint id = linear_index(pc.groups_x);
    if (id >= pc.rows * pc.tasks) {
        return;
    }
    uint row = id / pc.tasks;
    Row cells = row_cells(row);
    uint task = pc.task[id % pc.tasks];
    uint word = task & 1u;
    uint count = (task >> 2u) & 7u;
    bool to_word = ((task >> 16u) & 1u) != 0u;
    bool to_next = ((task >> 17u) & 1u) != 0u;
    int n = int(pc.counts[pc.axis]);
    // The two kinds' deques: in private arrays, or at the row's and task's
    // place in the storage buffer.
    uint base0 = PRIVATE_DEQUE != 0u ? 0u : 2u * id * uint(n);
    uint base1 = base0 + uint(n);
    // Private output: the first kind's words, then the second's.
    const uint second = PRIVATE_ROW;
    for (uint k = 0u; k < count; ++k) {
        uint j = (task >> (8u + 2u * k)) & 3u;
        uint ch = 4u * word + j;
        uint octant = ch % (DISTANCE_CHANNELS / 2u);
        // A ray of a negative octant looks towards lower x: sweep upwards.
        bool negative = ((octant >> pc.axis) & 1u) != 0u;
        int step = negative ? 1 : -1;
        int x = negative ? 0 : n - 1;
        uvec2 back = uvec2(0u);
        uvec2 front = uvec2(0u); // one past the front entries
        // The first pass's g is 0 or CAP: the distance is to the last cell
        // sought, counted from the far end and capped, with no deque.
        uvec2 run = uvec2(DISTANCE_CAP);
        for (int s = 0; s < n; ++s, x += step) {
            uint i = cell_index(cells, uint(x));
            uvec2 gx = g(i, ch);
            uvec2 best;
            if (FIRST != 0u) {
                run = mix(min(run + 1u, uvec2(DISTANCE_CAP)), uvec2(0u), equal(gx, uvec2(0u)));
                best = run;
            } else {
                best.x = deque_step(base0, x, gx.x, front.x, back.x);
                best.y = deque_step(base1, x, gx.y, front.y, back.y);
            }
            uvec2 d = min(best, uvec2(DISTANCE_CAP));
            // Along x, channels 2 and 3 of a word differ from 0 and 1 only
            // in the y sign: one sweep serves both.
            uvec2 bytes = d << (8u * j) | (FIRST != 0u ? d << (8u * (j + 2u)) : uvec2(0u));
            if (PRIVATE_DEQUE != 0u) {
                private_out[x] = k == 0u ? bytes.x : (private_out[x] | bytes.x);
                private_out[second + x] = k == 0u ? bytes.y : (private_out[second + x] | bytes.y);
                continue;
            }
            uint at = DISTANCE_WORDS * i + word;
            uint from = to_word ? at : at + 1u;
            uint packed0 = k == 0u ? bytes.x : (dst[from] | bytes.x);
            uint packed1 = k == 0u ? bytes.y : (dst[from + 2u] | bytes.y);
            if (to_word) {
                dst[at] = packed0;
                dst[at + 2u] = packed1;
            }
            if (to_next) {
                dst[at + 1u] = packed0;
                dst[at + 3u] = packed1;
            }
        }
    }
    if (PRIVATE_DEQUE != 0u) {
        for (int x = 0; x < n; ++x) {
            uint at = DISTANCE_WORDS * cell_index(cells, uint(x)) + word;
            if (to_word) {
                dst[at] = private_out[x];
                dst[at + 2u] = private_out[second + x];
            }
            if (to_next) {
                dst[at + 1u] = private_out[x];
                dst[at + 3u] = private_out[second + x];
            }
        }
    }
}
