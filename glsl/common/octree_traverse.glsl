// The four octree traversals of Havran's comparison, mirrored operation for
// operation by the CPU reference in src/octree/traverse.rs (read its header
// for the step counters and tie rules; 93 and rev run without a stack, by
// parent links). The includer binds `oct_nodes`,
// defines OCTREE_KIND (0 = 84, 1 = 89, 2 = 93, 3 = rev) and implements
// `bool octree_leaf(uint node, float t0, float t1)` (true stops the walk).
// 93 and rev visit several nodes per leaf in one loop, so they hand each
// leaf on outside it: a march inside ran, masked, at every node (84 and 89
// step from leaf to leaf, one pass of their loop each).
#ifndef LACUNA_OCTREE_TRAVERSE_GLSL
#define LACUNA_OCTREE_TRAVERSE_GLSL

#include "octree_node.glsl"

bool octree_leaf(uint node, float t0, float t1);

struct OctCounters {
    uint steps;
    uint leaves;
    uint empty_leaves;
};

const float OCT_TINY = 1e-20;
const float OCT_BIG = 3.4e38;
const uint OCT_GUARD = 1048576u;

struct OctRay {
    vec3 o;
    vec3 d; // no component below OCT_TINY in magnitude
    float tmin;
    float tmax;
};

OctCounters oc;

vec3 oct_safe_dir(vec3 d, vec3 o) {
    vec3 r = d;
    for (int a = 0; a < 3; ++a) {
        if (abs(d[a]) < OCT_TINY) {
            precise float mid = (oct_nodes[0].lo[a] + oct_nodes[0].hi[a]) * 0.5;
            r[a] = o[a] >= mid ? -OCT_TINY : OCT_TINY;
        }
    }
    return r;
}

float oct_cross(OctRay r, float plane, int a) {
    precise float t = (plane - r.o[a]) / r.d[a];
    return t;
}

float oct_max3(vec3 v) {
    return max(max(v.x, v.y), v.z);
}

float oct_min3(vec3 v) {
    return min(min(v.x, v.y), v.z);
}

// A node's plane crossings (Revelles' parameters): per axis the t of its
// near plane (t0) and far plane (t1).
void oct_plane_params(OctRay r, OctNode n, out vec3 t0, out vec3 t1) {
    for (int a = 0; a < 3; ++a) {
        float ta = oct_cross(r, n.lo[a], a);
        float tb = oct_cross(r, n.hi[a], a);
        if (r.d[a] > 0.0) {
            t0[a] = ta;
            t1[a] = tb;
        } else {
            t0[a] = tb;
            t1[a] = ta;
        }
    }
}

// The node's t-span: (largest near crossing, smallest far crossing).
vec2 oct_span(OctRay r, OctNode n) {
    vec3 t0;
    vec3 t1;
    oct_plane_params(r, n, t0, t1);
    return vec2(oct_max3(t0), oct_min3(t1));
}

bool oct_leaf(uint index, float t0, float t1) {
    oc.leaves += 1u;
    if (oct_nodes[index].info.y == 0u) {
        oc.empty_leaves += 1u;
    }
    return octree_leaf(index, t0, t1);
}

uint oct_child_at(OctNode n, vec3 p, bvec3 high) {
    uint child = 0u;
    for (int a = 0; a < 3; ++a) {
        if (p[a] > n.split[a] || (p[a] == n.split[a] && high[a])) {
            child |= oct_axis_bit(a);
        }
    }
    return n.info.x + child;
}

uint oct_locate(uint node, vec3 p, bvec3 high, bool count_start) {
    bool first = true;
    while (!oct_is_leaf(oct_nodes[node])) {
        if (!first || count_start) {
            oc.steps += 1u;
        }
        first = false;
        node = oct_child_at(oct_nodes[node], p, high);
    }
    return node;
}

bool oct_contains(OctNode n, vec3 p, bvec3 high) {
    for (int a = 0; a < 3; ++a) {
        if (p[a] < n.lo[a] || p[a] > n.hi[a] || (p[a] == n.hi[a] && high[a]) || (p[a] == n.lo[a] && !high[a])) {
            return false;
        }
    }
    return true;
}

// Glassner 1984 (neighbours = false) and Samet 1989 (neighbours = true).
void oct_stepping(OctRay r, bool neighbours) {
    OctNode root = oct_nodes[0];
    vec2 s = oct_span(r, root);
    float t = max(s.x, r.tmin);
    float end = min(s.y, r.tmax);
    if (!(t <= end)) {
        return;
    }
    vec3 p;
    bvec3 high;
    for (int a = 0; a < 3; ++a) {
        precise float v = r.o[a] + r.d[a] * t;
        p[a] = clamp(v, root.lo[a], root.hi[a]);
        high[a] = r.d[a] > 0.0;
    }
    uint node = oct_locate(0u, p, high, true);
    for (uint guard = 0u; guard < OCT_GUARD; ++guard) {
        OctNode n = oct_nodes[node];
        vec3 far;
        float exit = OCT_BIG;
        for (int a = 0; a < 3; ++a) {
            far[a] = r.d[a] > 0.0 ? n.hi[a] : n.lo[a];
            exit = min(exit, oct_cross(r, far[a], a));
        }
        exit = max(exit, t);
        if (oct_leaf(node, t, min(exit, end)) || exit >= end) {
            return;
        }
        for (int a = 0; a < 3; ++a) {
            if (oct_cross(r, far[a], a) <= exit) {
                p[a] = far[a];
                high[a] = r.d[a] > 0.0;
            } else {
                precise float v = r.o[a] + r.d[a] * exit;
                if (v >= n.hi[a]) {
                    p[a] = n.hi[a];
                    high[a] = false;
                } else if (v <= n.lo[a]) {
                    p[a] = n.lo[a];
                    high[a] = true;
                } else {
                    p[a] = v;
                    high[a] = r.d[a] > 0.0;
                }
            }
        }
        t = exit;
        if (neighbours) {
            uint up = node;
            while (true) {
                if (up == 0u) {
                    return;
                }
                up = oct_nodes[up].info.z;
                oc.steps += 1u;
                if (oct_contains(oct_nodes[up], p, high)) {
                    break;
                }
            }
            node = oct_locate(up, p, high, false);
        } else {
            if (!oct_contains(root, p, high)) {
                return;
            }
            node = oct_locate(0u, p, high, true);
        }
    }
}

// Gargantini & Atkinson's step: the children of n pierced in (ta, tb) come in
// ray order from the sorted crossings of its split planes (zero-length pieces
// skipped; equal crossings in axis order). Returns the child after `from`, or
// the first when `from` is NONE, or NONE after the last. No arrays: private
// arrays indexed at run time are slow on some drivers.
uint oct_o93_next(OctRay r, OctNode n, float ta, float tb, uint from) {
    const uint NONE = 0xffffffffu;
    uint child = 0u;
    vec3 tm;
    bvec3 pending;
    for (int a = 0; a < 3; ++a) {
        tm[a] = oct_cross(r, n.split[a], a);
        bool high = r.d[a] > 0.0 ? tm[a] <= ta : tm[a] > ta;
        if (high) {
            child |= oct_axis_bit(a);
        }
        pending[a] = tm[a] > ta && tm[a] < tb;
    }
    bool take = from == NONE;
    float start = ta;
    for (int step = 0; step < 4; ++step) {
        float tc = tb;
        int axis = 3;
        for (int a = 0; a < 3; ++a) {
            if (pending[a] && (axis == 3 || tm[a] < tc)) {
                tc = tm[a];
                axis = a;
            }
        }
        if (axis == 3 || tc > start) {
            if (take) {
                return child;
            }
            take = child == from;
        }
        if (axis == 3) {
            return NONE;
        }
        child ^= oct_axis_bit(axis);
        pending[axis] = false;
        start = tc;
    }
    return NONE;
}

uint oct_first_child(vec3 t0, vec3 tm) {
    int plane = 0;
    float m = t0.x;
    if (t0.y > m) {
        plane = 1;
        m = t0.y;
    }
    if (t0.z > m) {
        plane = 2;
        m = t0.z;
    }
    uint c = 0u;
    for (int a = 0; a < 3; ++a) {
        if (a != plane && tm[a] < m) {
            c |= oct_axis_bit(a);
        }
    }
    return c;
}

int oct_exit_axis(vec3 t1) {
    if (t1.x < t1.y) {
        if (t1.x < t1.z) {
            return 0;
        }
    } else if (t1.y < t1.z) {
        return 1;
    }
    return 2;
}

// Climbs from `node` to its parent, `from` the child it came from (93
// and rev keep no stack); false at the root, where the walk is over.
bool oct_climb(inout uint node, inout uint from) {
    if (node == 0u) {
        return false;
    }
    uint parent = oct_nodes[node].info.z;
    from = node - oct_nodes[parent].info.x;
    node = parent;
    return true;
}

// Revelles, Ureña & Lastra 2000: parametric, mirrored so d > 0 (mask),
// without a stack: returning from a child climbs the parent link and
// recomputes the parent's parameters from its box.
void oct_rev(OctRay r) {
    const uint NONE = 0xffffffffu;
    uint mask = 0u;
    for (int a = 0; a < 3; ++a) {
        if (r.d[a] <= 0.0) {
            mask |= oct_axis_bit(a);
        }
    }
    vec3 t0;
    vec3 t1;
    oct_plane_params(r, oct_nodes[0], t0, t1);
    if (oct_max3(t0) > oct_min3(t1)) {
        return;
    }
    uint node = 0u;
    uint from = NONE;
    bool more = true;
    while (more) {
        // To the next leaf, handed on outside this loop (its march inside
        // ran, masked, at every node a SIMD group visited: lavapipe runs
        // every `if`).
        bool found = false;
        uint leaf = 0u;
        vec2 span = vec2(0.0);
        more = false;
        while (true) {
            OctNode n = oct_nodes[node];
            oct_plane_params(r, n, t0, t1);
            uint next = NONE;
            if (from == NONE) {
                float enter = oct_max3(t0);
                float exit = oct_min3(t1);
                if (!(exit < r.tmin || enter > r.tmax)) {
                    if (oct_is_leaf(n)) {
                        found = true;
                        leaf = node;
                        span = vec2(max(enter, r.tmin), min(exit, r.tmax));
                    } else {
                        oc.steps += 1u;
                        vec3 tm;
                        for (int a = 0; a < 3; ++a) {
                            tm[a] = oct_cross(r, n.split[a], a);
                        }
                        next = oct_first_child(t0, tm);
                    }
                }
            } else {
                uint c = from ^ mask;
                vec3 t1c;
                for (int a = 0; a < 3; ++a) {
                    t1c[a] = (c & oct_axis_bit(a)) != 0u ? t1[a] : oct_cross(r, n.split[a], a);
                }
                int axis = oct_exit_axis(t1c);
                if ((c & oct_axis_bit(axis)) == 0u) {
                    next = c | oct_axis_bit(axis);
                }
            }
            if (next != NONE) {
                node = n.info.x + (next ^ mask);
                from = NONE;
                continue;
            }
            if (!oct_climb(node, from)) {
                break;
            }
            if (found) {
                more = true;
                break;
            }
        }
        if (found && oct_leaf(leaf, span.x, span.y)) {
            return;
        }
    }
}

// A node's t-span from its box, clipped to [tmin, tmax].
vec2 oct_clipped_span(OctRay r, OctNode n) {
    vec2 s = oct_span(r, n);
    return vec2(max(s.x, r.tmin), min(s.y, r.tmax));
}

// Gargantini & Atkinson 1993, without a stack: returning from a child climbs
// the parent link, recomputes the parent's pierced children and moves on.
void oct_o93(OctRay r) {
    const uint NONE = 0xffffffffu;
    vec2 s0 = oct_clipped_span(r, oct_nodes[0]);
    if (!(s0.x <= s0.y)) {
        return;
    }
    uint node = 0u;
    uint from = NONE;
    bool more = true;
    while (more) {
        // To the next leaf, handed on outside this loop (as oct_rev).
        bool found = false;
        uint leaf = 0u;
        vec2 span = vec2(0.0);
        more = false;
        while (true) {
            OctNode n = oct_nodes[node];
            vec2 s = oct_clipped_span(r, n);
            uint next = NONE;
            if (from == NONE) {
                if (oct_is_leaf(n)) {
                    found = true;
                    leaf = node;
                    span = s;
                } else {
                    oc.steps += 1u;
                    next = oct_o93_next(r, n, s.x, s.y, NONE);
                }
            } else {
                next = oct_o93_next(r, n, s.x, s.y, from);
            }
            if (next != NONE) {
                node = n.info.x + next;
                from = NONE;
                continue;
            }
            if (!oct_climb(node, from)) {
                break;
            }
            if (found) {
                more = true;
                break;
            }
        }
        if (found && oct_leaf(leaf, span.x, span.y)) {
            return;
        }
    }
}

// Walks the octree along r, handing leaves to octree_leaf in ray order.
OctCounters octree_walk(OctRay r) {
    oc = OctCounters(0u, 0u, 0u);
    r.d = oct_safe_dir(r.d, r.o);
    if (OCTREE_KIND == 0u) {
        oct_stepping(r, false);
    } else if (OCTREE_KIND == 1u) {
        oct_stepping(r, true);
    } else if (OCTREE_KIND == 2u) {
        oct_o93(r);
    } else {
        oct_rev(r);
    }
    return oc;
}

#endif
