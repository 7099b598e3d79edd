#version 460
// Cost-driven leaves (src/accel/cost.rs): after the refit, a second bottom-up
// climb prices every node as one leaf (entry + samples along its mean chord
// 4V/S) and as an inner node (step + children's costs weighted by S(c)/S);
// where the leaf is not dearer the node becomes a leaf (lo.w = -1; hi.w keeps
// its right child, unreached). Its box is the union of its subtree's bricks,
// so it covers every active brick below it and the march stays exact.
//
// One invocation per leaf, the second arrival at a node continues, with the
// refit's acquire-release arrival counter (see lbvh_refit.comp). The leaf
// count comes from the compaction's count buffer, not a push constant, so the
// kernel is not respecialised per transfer function.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_memory_scope_semantics : require
#pragma use_vulkan_memory_model
#include "bvh_node.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) coherent buffer Nodes { BvhNode nodes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Parents { int parents[]; };
layout(std430, set = 0, binding = 2) coherent buffer Visits { uint visits[]; };
// Per node: (expected cost per ray meeting it, surface area).
layout(std430, set = 0, binding = 3) coherent buffer Costs { vec2 costs[]; };
layout(std430, set = 0, binding = 4) readonly buffer Count { uint count_n; };
// x: sample cost per voxel of chord; y: inner step; z: leaf entry (ns).
layout(push_constant) uniform Push { vec4 model; uint cap; } pc;
// The leaf count, at most the pass's capacity (`cap`, what the buffers
// were sized for): a count past it indexes nothing out of bounds.
#define n min(count_n, pc.cap)

// (cost as one leaf, surface area) of box [lo, hi]; the operation order of
// CostModel::leaf, so the CPU reference decides alike.
vec2 leaf_cost(ivec3 lo, ivec3 hi) {
    precise vec3 e = vec3(max(hi - lo, ivec3(0)));
    precise float s = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    precise float v = e.x * e.y * e.z;
    precise float chord = s > 0.0 ? 4.0 * v / s : 0.0;
    precise float c = pc.model.z + pc.model.x * chord;
    return vec2(c, s);
}

void main() {
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= n) {
        return;
    }
    int node = int(n) - 1 + int(i);
    costs[node] = leaf_cost(nodes[node].lo.xyz, nodes[node].hi.xyz);
    while (node != 0) {
        int p = parents[node];
        uint arrived = atomicAdd(visits[p], 1u, gl_ScopeQueueFamily, gl_StorageSemanticsBuffer, gl_SemanticsAcquireRelease);
        if (arrived == 0u) {
            return;
        }
        BvhNode b = nodes[p];
        vec2 l = costs[b.lo.w];
        vec2 r = costs[b.hi.w];
        vec2 leaf = leaf_cost(b.lo.xyz, b.hi.xyz);
        precise float weighted = l.y * l.x + r.y * r.x;
        precise float inner = leaf.y > 0.0 ? pc.model.y + weighted / leaf.y : pc.model.y + l.x + r.x;
        if (leaf.x <= inner) {
            nodes[p].lo.w = -1;
            costs[p] = leaf;
        } else {
            costs[p] = vec2(inner, leaf.y);
        }
        node = p;
    }
}
