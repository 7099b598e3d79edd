// Front-to-back stack traversal of a tree in the BvhNode format (LBVH and
// k-d trees alike): children are visited by entry t, and siblings lie on
// opposite sides of their split plane, so leaves come in ray order. The
// includer defines TREE_LEAF(m, span, eps) (what to do with a leaf's span),
// and binds `nodes` and `leaf_count`.
#ifndef LACUNA_TREE_TRAVERSE_GLSL
#define LACUNA_TREE_TRAVERSE_GLSL

vec2 node_span(March m, int node, float eps) {
    return region_span(m, vec3(nodes[node].lo.xyz), vec3(nodes[node].hi.xyz), eps);
}

// Pops nodes until a leaf's span, then marches it outside that loop: a
// march inside it ran its sample loop, masked, at every node a SIMD group
// popped, as lavapipe runs every `if` (the grid's DDA likewise, lattice.glsl
// RUN_CELLS).
void traverse_tree(inout March m) {
    if (leaf_count == 0u) {
        return;
    }
    float eps = region_margin(m);
    int stack[64];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0 && !m.done) {
        vec2 leaf = vec2(0.0);
        bool found = false;
        while (sp > 0) {
            count_iteration(COUNT_STEP);
            int node = stack[--sp];
            vec2 span = node_span(m, node, eps);
            // Missed, or wholly behind the samples already taken.
            if (!(span.x < span.y) || !(span.y > lattice_t(m, m.k))) {
                continue;
            }
            int left = nodes[node].lo.w;
            if (left < 0) {
                leaf = span;
                found = true;
                break;
            }
            int right = nodes[node].hi.w;
            vec2 sl = node_span(m, left, eps);
            vec2 sr = node_span(m, right, eps);
            bool hl = sl.x < sl.y;
            bool hr = sr.x < sr.y;
            if (hl && hr) {
                bool left_first = sl.x <= sr.x;
                stack[sp++] = left_first ? right : left;
                stack[sp++] = left_first ? left : right;
            } else if (hl) {
                stack[sp++] = left;
            } else if (hr) {
                stack[sp++] = right;
            }
        }
        if (found) {
            TREE_LEAF(m, leaf, eps);
        }
    }
}

#endif
