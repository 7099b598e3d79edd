#version 460
// One 1-D pass of the separable Chebyshev distance transform over the cell
// grid (three passes: x, then y, then z). The L-infinity distance to the
// nearest cell of a kind is the min over those cells of the max of the 1-D
// offsets, so after the pass along axis a each cell holds, per channel,
//   d_a(c) = min over r of max(|r|, d_prev(c + r e_a))
// (the first pass reads the active flags: 0 for a cell of the kind sought,
// CAP otherwise). The search grows r only while r can still improve the
// minimum, so a cell costs O(its own distance). Octant channels search only
// ahead of their octant. Channels: see distance_map.glsl.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint OCTANTS = 0u;
#include "dispatch.glsl"
#include "distance_map.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Dst { uint dst[]; };
// xyz: cells per axis, w: total; axis: 0, 1, 2; first: src holds the flags.
layout(push_constant) uniform Push { uvec4 counts; uint axis; uint first; uint groups_x; uint pad; } pc;

uint read(ivec3 c, uint channel) {
    uint i = uint(c.x) + pc.counts.x * (uint(c.y) + pc.counts.y * uint(c.z));
    if (pc.first != 0u) {
        bool is_active = src[i] != 0u;
        bool seeks_active = channel < DISTANCE_CHANNELS / 2u;
        return is_active == seeks_active ? 0u : DISTANCE_CAP;
    }
    return distance_byte(src[DISTANCE_WORDS * i + (channel >> 2u)], channel);
}

// min over r in the searched directions of max(|r|, d_prev(c + r e_axis)).
uint search(ivec3 c, uint channel, bool ahead, bool behind) {
    int n = int(pc.counts[pc.axis]);
    uint best = read(c, channel);
    for (uint r = 1u; r < best; ++r) {
        int fwd = c[pc.axis] + int(r);
        int bwd = c[pc.axis] - int(r);
        bool f = ahead && fwd < n;
        bool b = behind && bwd >= 0;
        if (!f && !b) {
            break;
        }
        ivec3 q = c;
        if (f) {
            q[pc.axis] = fwd;
            best = min(best, max(r, read(q, channel)));
        }
        if (b) {
            q[pc.axis] = bwd;
            best = min(best, max(r, read(q, channel)));
        }
    }
    return best;
}

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= pc.counts.w) {
        return;
    }
    ivec3 c = ivec3(i % pc.counts.x, (i / pc.counts.x) % pc.counts.y, i / (pc.counts.x * pc.counts.y));
    uvec4 packed = uvec4(0u);
    for (uint ch = 0u; ch < DISTANCE_CHANNELS; ++ch) {
        uint octant = ch % (DISTANCE_CHANNELS / 2u);
        bool negative = OCTANTS != 0u && ((octant >> pc.axis) & 1u) != 0u;
        bool both = OCTANTS == 0u;
        uint d = search(c, ch, both || !negative, both || negative);
        packed[ch >> 2u] |= d << (8u * (ch & 3u));
    }
    for (uint w = 0u; w < DISTANCE_WORDS; ++w) {
        dst[DISTANCE_WORDS * i + w] = packed[w];
    }
}
