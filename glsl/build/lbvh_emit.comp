#version 460
// Karras 2012 hierarchy emit: one invocation per internal node. Equal codes
// are ordered by index (delta = 32 + clz(i ^ j)), so duplicates still give a
// valid binary tree.
#extension GL_GOOGLE_include_directive : require
#include "bvh_node.glsl"

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Codes { uint codes[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Parents { int parents[]; };
// The leaf count n, as the compaction wrote it: a recorded build dispatches
// over the brick capacity and the threads past n - 1 return.
layout(std430, set = 0, binding = 3) readonly buffer Count { uint count_n; };
layout(push_constant) uniform Push { uint groups_x; uint cap; uint pad1; uint pad2; } pc;
// The leaf count, at most the pass's capacity (`cap`, what the buffers
// were sized for): a count past it indexes nothing out of bounds.
#define n min(count_n, pc.cap)

int delta(int i, int j) {
    if (j < 0 || j >= int(n)) {
        return -1;
    }
    uint a = codes[i];
    uint b = codes[j];
    if (a != b) {
        return 31 - findMSB(a ^ b);
    }
    return 32 + 31 - findMSB(uint(i ^ j));
}

void main() {
    uint id = linear_index(pc.groups_x);
    if (n < 2u || id >= n - 1u) {
        return;
    }
    int i = int(id);
    int d = delta(i, i + 1) - delta(i, i - 1) > 0 ? 1 : -1;
    int dmin = delta(i, i - d);
    int lmax = 2;
    while (delta(i, i + lmax * d) > dmin) {
        lmax *= 2;
    }
    int l = 0;
    for (int t = lmax / 2; t >= 1; t /= 2) {
        if (delta(i, i + (l + t) * d) > dmin) {
            l += t;
        }
    }
    int j = i + l * d;
    int dnode = delta(i, j);
    int s = 0;
    int t = l;
    do {
        t = (t + 1) / 2;
        if (delta(i, i + (s + t) * d) > dnode) {
            s += t;
        }
    } while (t > 1);
    int split = i + s * d + min(d, 0);
    int leaf0 = int(n) - 1;
    int left = min(i, j) == split ? leaf0 + split : split;
    int right = max(i, j) == split + 1 ? leaf0 + split + 1 : split + 1;
    nodes[i].lo.w = left;
    nodes[i].hi.w = right;
    parents[left] = i;
    parents[right] = i;
}
