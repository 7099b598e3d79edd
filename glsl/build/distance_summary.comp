#version 460
// What `--accel auto` reads from a distance map, reduced on the GPU: active
// cells, faces between an active and an empty cell (fragmentation), the sum
// of empty cells' distances to an active cell and of active cells' distances
// to an empty cell (octant maps: over all eight, the host divides), each sum
// as a 64-bit count in two words.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint OCTANTS = 0u;
#include "dispatch.glsl"
#include "distance_map.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Flags { uint flags[]; };
layout(std430, set = 0, binding = 1) readonly buffer Distances { uint distances[]; };
// active, faces, empty cells' sum (low, high word), active cells' sum (low, high).
layout(std430, set = 0, binding = 2) buffer Summary { uint summary[6]; };
// per_invocation: consecutive cells each invocation sums before the
// workgroup's reduction (its barriers are dear on a CPU device, where a
// workgroup's SIMD groups take turns at each one).
layout(push_constant) uniform Push { uvec4 counts; uint groups_x; uint per_invocation; uint pad1; uint pad2; } pc;

shared uvec4 partial[64];

bool active_at(ivec3 c) {
    return flags[uint(c.x) + pc.counts.x * (uint(c.y) + pc.counts.y * uint(c.z))] != 0u;
}

// Cell i's terms: (active, active-empty faces, distance if empty, distance if active).
uvec4 cell_terms(uint i) {
    uvec4 t = uvec4(0u);
    ivec3 n = ivec3(pc.counts.xyz);
    ivec3 c = ivec3(i % pc.counts.x, (i / pc.counts.x) % pc.counts.y, i / (pc.counts.x * pc.counts.y));
    if (flags[i] != 0u) {
        t.x = 1u;
        for (uint ch = DISTANCE_CHANNELS / 2u; ch < DISTANCE_CHANNELS; ++ch) {
            t.w += distance_byte(distances[DISTANCE_WORDS * i + (ch >> 2u)], ch);
        }
        for (int a = 0; a < 3; ++a) {
            for (int s = -1; s <= 1; s += 2) {
                ivec3 q = c;
                q[a] += s;
                if (q[a] >= 0 && q[a] < n[a] && !active_at(q)) {
                    t.y += 1u;
                }
            }
        }
    } else {
        for (uint ch = 0u; ch < DISTANCE_CHANNELS / 2u; ++ch) {
            t.z += distance_byte(distances[DISTANCE_WORDS * i + (ch >> 2u)], ch);
        }
    }
    return t;
}

void main() {
    uint first = linear_index(pc.groups_x) * pc.per_invocation;
    uint end = min(first + pc.per_invocation, pc.counts.w);
    uvec4 mine = uvec4(0u);
    for (uint i = first; i < end; ++i) {
        mine += cell_terms(i);
    }
    uint l = gl_LocalInvocationID.x;
    partial[l] = mine;
    barrier();
    for (uint s = 32u; s > 0u; s >>= 1u) {
        if (l < s) {
            partial[l] += partial[l + s];
        }
        barrier();
    }
    if (l == 0u) {
        atomicAdd(summary[0], partial[0].x);
        atomicAdd(summary[1], partial[0].y);
        uint old = atomicAdd(summary[2], partial[0].z);
        if (old + partial[0].z < old) {
            atomicAdd(summary[3], 1u);
        }
        old = atomicAdd(summary[4], partial[0].w);
        if (old + partial[0].w < old) {
            atomicAdd(summary[5], 1u);
        }
    }
}
