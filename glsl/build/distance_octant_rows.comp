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
// once and copy them to the octants that differ only in later signs. One
// invocation per row and computed map word.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#define OCTANTS 1u
#include "dispatch.glsl"
#include "distance_map.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 1) buffer Dst { uint dst[]; };
// Per (row, word): the deque, one entry per cell of the row (position << 8 | g).
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
uint private_deque[PRIVATE_ROW];
uint private_out[PRIVATE_ROW];

uint deque_read(uint base, uint k) {
    return PRIVATE_DEQUE != 0u ? private_deque[k] : deque[base + k];
}

void deque_write(uint base, uint k, uint entry) {
    if (PRIVATE_DEQUE != 0u) {
        private_deque[k] = entry;
    } else {
        deque[base + k] = entry;
    }
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
    uint a1 = (pc.axis + 1u) % 3u;
    uint a2 = (pc.axis + 2u) % 3u;
    c[pc.axis] = 0u;
    c[a1] = row % pc.counts[a1];
    c[a2] = row / pc.counts[a1];
    uint stride = pc.axis == 0u ? 1u : (pc.axis == 1u ? pc.counts.x : pc.counts.x * pc.counts.y);
    return Row(c.x + pc.counts.x * (c.y + pc.counts.y * c.z), stride);
}

uint cell_index(Row r, uint x) {
    return r.origin + x * r.stride;
}

uint g(uint i, uint channel) {
    if (FIRST != 0u) {
        bool is_active = src[i] != 0u;
        bool seeks_active = channel < DISTANCE_CHANNELS / 2u;
        return is_active == seeks_active ? 0u : DISTANCE_CAP;
    }
    return distance_byte(src[DISTANCE_WORDS * i + (channel >> 2u)], channel);
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
    // Words 1 and 3 differ from words 0 and 2 only in the z sign.
    uint words = pc.axis == 2u ? 4u : 2u;
    uint id = linear_index(pc.groups_x);
    if (id >= pc.rows * words) {
        return;
    }
    uint row = id / words;
    Row cells = row_cells(row);
    uint word = pc.axis == 2u ? id % words : 2u * (id % words);
    // Within a word, channels 2 and 3 differ from 0 and 1 only in the y sign.
    uint lanes = pc.axis == 0u ? 2u : 4u;
    int n = int(pc.counts[pc.axis]);
    uint base = id * uint(n);
    for (uint j = 0u; j < lanes; ++j) {
        uint ch = 4u * word + j;
        uint octant = ch % (DISTANCE_CHANNELS / 2u);
        // A ray of a negative octant looks towards lower x: sweep upwards.
        bool negative = ((octant >> pc.axis) & 1u) != 0u;
        int step = negative ? 1 : -1;
        int x = negative ? 0 : n - 1;
        uint back = 0u;
        uint front = 0u; // one past the front entry
        // The first pass's g is 0 or CAP: the distance is to the last cell
        // sought, counted from the far end and capped, with no deque.
        uint run = DISTANCE_CAP;
        for (int s = 0; s < n; ++s, x += step) {
            uint i = cell_index(cells, uint(x));
            uint gx = g(i, ch);
            uint best;
            if (FIRST != 0u) {
                run = gx == 0u ? 0u : min(run + 1u, DISTANCE_CAP);
                best = run;
            } else {
                best = deque_step(base, x, gx, front, back);
            }
            uint d = min(best, DISTANCE_CAP);
            uint bytes = d << (8u * j) | (lanes == 2u ? d << (8u * (j + 2u)) : 0u);
            if (PRIVATE_DEQUE != 0u) {
                private_out[x] = j == 0u ? bytes : (private_out[x] | bytes);
                continue;
            }
            uint at = DISTANCE_WORDS * i + word;
            uint packed = j == 0u ? bytes : (dst[at] | bytes);
            dst[at] = packed;
            if (words == 2u) {
                dst[at + 1u] = packed;
            }
        }
    }
    if (PRIVATE_DEQUE != 0u) {
        for (int x = 0; x < n; ++x) {
            uint at = DISTANCE_WORDS * cell_index(cells, uint(x)) + word;
            dst[at] = private_out[x];
            if (words == 2u) {
                dst[at + 1u] = private_out[x];
            }
        }
    }
}
