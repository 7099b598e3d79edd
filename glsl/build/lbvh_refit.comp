#version 460
// Bottom-up refit: one invocation per leaf writes its brick box and climbs;
// at each internal node the first arrival stops and the second (which then
// sees both children's boxes) writes the union and continues.
//
// The arrival counter is an acquire-release atomic of the Vulkan memory
// model: the first arrival's box writes are released by its increment and
// acquired by the second's. Plain memoryBarrierBuffer() is not enough: a
// compiler may hoist the sibling's box load above a relaxed atomic (lavapipe
// does), which silently loses the upper levels of the tree.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_memory_scope_semantics : require
#pragma use_vulkan_memory_model
#include "bvh_node.glsl"

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Payload { uint payload[]; };
layout(std430, set = 0, binding = 1) coherent buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = 2) readonly buffer Parents { int parents[]; };
layout(std430, set = 0, binding = 3) coherent buffer Visits { uint visits[]; };
// The leaf count n from the compaction (a recorded build dispatches over the
// brick capacity; threads past n return).
layout(std430, set = 0, binding = 4) readonly buffer Count { uint count_n; };
layout(push_constant) uniform Push {
    uvec4 dims;   // xyz: volume dims; w: brick edge
    uvec4 counts; // xyz: bricks per axis
    uint groups_x;
    uint cap;
} pc;
// The leaf count, at most the pass's capacity (`cap`, what the buffers
// were sized for): a count past it indexes nothing out of bounds.
#define n min(count_n, pc.cap)

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= n) {
        return;
    }
    uint b = payload[i];
    uvec3 c = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    ivec3 lo = ivec3(c * pc.dims.w);
    ivec3 hi = min(lo + int(pc.dims.w), ivec3(pc.dims.xyz));
    int node = int(n) - 1 + int(i);
    nodes[node].lo = ivec4(lo, -1);
    nodes[node].hi = ivec4(hi, int(b));
    while (node != 0) {
        int p = parents[node];
        uint arrived = atomicAdd(visits[p], 1u, gl_ScopeQueueFamily, gl_StorageSemanticsBuffer, gl_SemanticsAcquireRelease);
        if (arrived == 0u) {
            return;
        }
        BvhNode l = nodes[nodes[p].lo.w];
        BvhNode r = nodes[nodes[p].hi.w];
        nodes[p].lo.xyz = min(l.lo.xyz, r.lo.xyz);
        nodes[p].hi.xyz = max(l.hi.xyz, r.hi.xyz);
        node = p;
    }
}
