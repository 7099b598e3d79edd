#version 460
// Traces a batch of rays through an octree over SPD primitives with one of
// Havran's four traversals (specialization constant 0), writing each ray's
// nearest hit (or, for shadow rays, the first hit found) and its counters.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint OCTREE_KIND = 3u;

#include "octree_node.glsl"
#include "dispatch.glsl"

struct TraceRay {
    vec4 org_tmin;
    vec4 dir_tmax;
};

layout(std430, set = 0, binding = 0) readonly buffer Nodes { OctNode oct_nodes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Refs { uint refs[]; };
layout(std430, set = 0, binding = 3) readonly buffer Verts { vec4 verts[]; };
#include "octree_prims.glsl"
layout(std430, set = 0, binding = 2) readonly buffer Prims { Prim prims[]; };
layout(std430, set = 0, binding = 4) readonly buffer Rays { TraceRay rays[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Results { uvec4 results[]; };

layout(push_constant) uniform Push {
    uint count;     // rays in this batch
    uint any_hit;   // 1: shadow rays (stop at the first hit found)
    uint groups_x;  // dispatch row width (dispatch.glsl)
} pc;

// The ray being traced, read by octree_leaf.
vec3 g_org;
vec3 g_dir;
float g_tmin;
float g_best;
uint g_prim;
uint g_tests;

bool octree_leaf(uint node, float t0, float t1) {
    uint count = oct_nodes[node].info.y;
    if (count == 0u) {
        return false;
    }
    uint first = oct_nodes[node].info.x;
    // A hit counts for this leaf up to its exit (with a rounding allowance);
    // farther ones belong to a later leaf.
    precise float limit = t1 + 1e-5 * max(abs(t1), 1.0);
    for (uint i = 0u; i < count; ++i) {
        uint k = refs[first + i];
        g_tests += 1u;
        float t = intersect_prim(prims[k], g_org, g_dir, g_tmin, g_best);
        if (t >= 0.0 && t > g_tmin) {
            if (pc.any_hit != 0u) {
                g_best = t;
                g_prim = k;
                return true;
            }
            if (t <= limit) {
                g_best = t;
                g_prim = k;
            }
        }
    }
    return g_prim != 0xffffffffu;
}

#include "octree_traverse.glsl"

void main() {
    uint i = linear_index(pc.groups_x);
    if (i >= pc.count) {
        return;
    }
    TraceRay r = rays[i];
    g_org = r.org_tmin.xyz;
    g_dir = r.dir_tmax.xyz;
    g_tmin = r.org_tmin.w;
    g_best = r.dir_tmax.w;
    g_prim = 0xffffffffu;
    g_tests = 0u;
    OctCounters c = octree_walk(OctRay(g_org, g_dir, g_tmin, g_best));
    results[2u * i] = uvec4(floatBitsToUint(g_prim == 0xffffffffu ? 0.0 : g_best), g_prim, g_tests, c.steps);
    results[2u * i + 1u] = uvec4(c.leaves, c.empty_leaves, 0u, 0u);
}
