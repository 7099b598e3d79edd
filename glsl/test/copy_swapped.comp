#version 460
// prims/copy.comp with its two bindings declared in the other order, for the
// test that the host binds resources by name (tests/gpu_core.rs): a binding
// renumbered in a kernel still gets its resource.

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) writeonly buffer Dst { uint dst[]; };
layout(std430, set = 0, binding = 1) readonly buffer Src { uint src[]; };

layout(push_constant) uniform Push {
    uint count;
    uint src_offset;
    uint dst_offset;
    uint groups_x; // workgroups per row of the 2-D dispatch
} pc;

void main() {
    uint i = (gl_WorkGroupID.y * pc.groups_x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i < pc.count) {
        dst[pc.dst_offset + i] = src[pc.src_offset + i];
    }
}
