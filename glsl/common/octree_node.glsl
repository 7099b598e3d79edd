// Octree node (64 bytes), documented in src/octree/node.rs: box lo/hi, split
// point, info = (first child | first reference, reference count, parent,
// leaf bit | depth << 1). Child i is high in x if i & 4, y if i & 2, z if i & 1.
#ifndef LACUNA_OCTREE_NODE_GLSL
#define LACUNA_OCTREE_NODE_GLSL

struct OctNode {
    vec4 lo;
    vec4 hi;
    vec4 split;
    uvec4 info;
};

bool oct_is_leaf(OctNode n) {
    return (n.info.w & 1u) != 0u;
}

uint oct_axis_bit(int a) {
    return 4u >> uint(a);
}

#endif
