#version 460
// Element-wise copy of u32 words, dst[dst_offset + i] = src[src_offset + i].
// Dispatched as 2-D groups so counts beyond maxComputeWorkGroupCount[0] fit.

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) readonly buffer Src { uint src[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Dst { uint dst[]; };

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
