// Linear invocation index for 1-D problems dispatched as a 2-D grid of
// workgroups (counts beyond maxComputeWorkGroupCount[0]); the host passes the
// grid's row width in workgroups.
#ifndef LACUNA_DISPATCH_GLSL
#define LACUNA_DISPATCH_GLSL

uint linear_group(uint groups_x) {
    return gl_WorkGroupID.y * groups_x + gl_WorkGroupID.x;
}

uint linear_index(uint groups_x) {
    return linear_group(groups_x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
}

#endif
