#version 460
// Tight-box queries for the GPU k-d builder, one workgroup per query: the
// union of (brick tight box clipped to the query box) over the bricks the
// query overlaps, found as a range of the Morton-sorted brick list (a
// superset; bricks outside the query's brick range are skipped). One
// dispatch answers every query of a tree level.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
#include "morton.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Codes { uint codes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = 2) readonly buffer Boxes { ivec4 boxes[]; };
layout(std430, set = 0, binding = 3) readonly buffer Queries { ivec4 queries[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Results { ivec4 results[]; };
layout(push_constant) uniform Push {
    uvec4 counts; // xyz: bricks per axis; w: bricks
    uint queries;
    uint groups_x;
    uint brick;
    uint pad;
} pc;

shared int box[6];
shared uint range[2];

// First index whose code is >= key (codes ascending).
uint lower_bound(uint key) {
    uint lo = 0u;
    uint hi = pc.counts.w;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (codes[mid] < key) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

void main() {
    uint q = linear_group(pc.groups_x);
    if (q >= pc.queries) {
        return;
    }
    uint lid = gl_LocalInvocationID.x;
    ivec3 qlo = queries[2u * q].xyz;
    ivec3 qhi = queries[2u * q + 1u].xyz;
    bool empty = any(greaterThanEqual(qlo, qhi));
    ivec3 blo = qlo / int(pc.brick);
    ivec3 bhi = (qhi - 1) / int(pc.brick);
    if (lid == 0u) {
        box[0] = box[1] = box[2] = 0x7FFFFFFF;
        box[3] = box[4] = box[5] = int(0x80000000);
        range[0] = empty ? 0u : lower_bound(morton3(uvec3(blo)));
        range[1] = empty ? 0u : lower_bound(morton3(uvec3(bhi)) + 1u);
    }
    barrier();
    for (uint i = range[0] + lid; i < range[1]; i += 64u) {
        uint b = order[i];
        ivec3 bc = ivec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
        if (any(lessThan(bc, blo)) || any(greaterThan(bc, bhi))) {
            continue;
        }
        ivec3 lo = max(boxes[2u * b].xyz, qlo);
        ivec3 hi = min(boxes[2u * b + 1u].xyz, qhi);
        if (all(lessThan(lo, hi))) {
            atomicMin(box[0], lo.x);
            atomicMin(box[1], lo.y);
            atomicMin(box[2], lo.z);
            atomicMax(box[3], hi.x);
            atomicMax(box[4], hi.y);
            atomicMax(box[5], hi.z);
        }
    }
    barrier();
    if (lid == 0u) {
        results[2u * q] = ivec4(box[0], box[1], box[2], 0);
        results[2u * q + 1u] = ivec4(box[3], box[4], box[5], 0);
    }
}
