// LBVH node (32 bytes), documented in src/accel/lbvh/mod.rs:
//   lo.xyz, hi.xyz: integer voxel-space box; lo.w: left child, or -1 for a
//   leaf; hi.w: right child, or for a leaf its brick index.
// Internal nodes are 0 .. n-2 (root 0), leaves n-1 .. 2n-2; with n = 1 the
// single leaf is node 0.
#ifndef LACUNA_BVH_NODE_GLSL
#define LACUNA_BVH_NODE_GLSL

struct BvhNode {
    ivec4 lo;
    ivec4 hi;
};

#endif
