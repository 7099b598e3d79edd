// The four octree traversals of Havran's comparison, mirrored operation for
// operation by the CPU reference in src/octree/traverse.rs (read its header
// for the step counters and tie rules). The includer binds `oct_nodes`,
// defines OCTREE_KIND (0 = 84, 1 = 89, 2 = 93, 3 = rev) and implements
// `bool octree_leaf(uint node, float t0, float t1)` (true stops the walk).
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
const uint OCT_FRESH = 9u;

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

vec2 oct_span(OctRay r, OctNode n) {
    float t0 = -OCT_BIG;
    float t1 = OCT_BIG;
    for (int a = 0; a < 3; ++a) {
        float ta = oct_cross(r, n.lo[a], a);
        float tb = oct_cross(r, n.hi[a], a);
        bool pos = r.d[a] > 0.0;
        t0 = max(t0, pos ? ta : tb);
        t1 = min(t1, pos ? tb : ta);
    }
    return vec2(t0, t1);
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

// Gargantini & Atkinson 1993: sorted crossings of the three split planes.
void oct_o93(OctRay r) {
    vec2 s = oct_span(r, oct_nodes[0]);
    float ta0 = max(s.x, r.tmin);
    float tb0 = min(s.y, r.tmax);
    if (!(ta0 <= tb0)) {
        return;
    }
    uint st_node[64];
    vec2 st_t[64];
    int sp = 1;
    st_node[0] = 0u;
    st_t[0] = vec2(ta0, tb0);
    while (sp > 0) {
        sp -= 1;
        uint index = st_node[sp];
        float ta = st_t[sp].x;
        float tb = st_t[sp].y;
        OctNode n = oct_nodes[index];
        if (oct_is_leaf(n)) {
            if (oct_leaf(index, ta, tb)) {
                return;
            }
            continue;
        }
        oc.steps += 1u;
        uint child = 0u;
        float ct[3];
        int ca[3];
        int count = 0;
        for (int a = 0; a < 3; ++a) {
            float tm = oct_cross(r, n.split[a], a);
            bool high = r.d[a] > 0.0 ? tm <= ta : tm > ta;
            if (high) {
                child |= oct_axis_bit(a);
            }
            if (tm > ta && tm < tb) {
                int k = count;
                while (k > 0 && ct[k - 1] > tm) {
                    ct[k] = ct[k - 1];
                    ca[k] = ca[k - 1];
                    k -= 1;
                }
                ct[k] = tm;
                ca[k] = a;
                count += 1;
            }
        }
        uint kn[4];
        vec2 kt[4];
        int nk = 0;
        float start = ta;
        for (int i = 0; i < count; ++i) {
            if (ct[i] > start) {
                kn[nk] = n.info.x + child;
                kt[nk] = vec2(start, ct[i]);
                nk += 1;
            }
            child ^= oct_axis_bit(ca[i]);
            start = ct[i];
        }
        kn[nk] = n.info.x + child;
        kt[nk] = vec2(start, tb);
        nk += 1;
        for (int k = nk - 1; k >= 0; --k) {
            st_node[sp] = kn[k];
            st_t[sp] = kt[k];
            sp += 1;
        }
    }
}

float oct_max3(vec3 v) {
    return max(max(v.x, v.y), v.z);
}

float oct_min3(vec3 v) {
    return min(min(v.x, v.y), v.z);
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

// Revelles, Ureña & Lastra 2000: parametric, mirrored so d > 0 (mask).
void oct_rev(OctRay r) {
    OctNode root = oct_nodes[0];
    uint mask = 0u;
    vec3 t0;
    vec3 t1;
    for (int a = 0; a < 3; ++a) {
        float ta = oct_cross(r, root.lo[a], a);
        float tb = oct_cross(r, root.hi[a], a);
        if (r.d[a] > 0.0) {
            t0[a] = ta;
            t1[a] = tb;
        } else {
            mask |= oct_axis_bit(a);
            t0[a] = tb;
            t1[a] = ta;
        }
    }
    if (oct_max3(t0) > oct_min3(t1)) {
        return;
    }
    uint f_node[16];
    uint f_cur[16];
    vec3 f_t0[16];
    vec3 f_t1[16];
    vec3 f_tm[16];
    f_node[0] = 0u;
    f_cur[0] = OCT_FRESH;
    f_t0[0] = t0;
    f_t1[0] = t1;
    f_tm[0] = vec3(0.0);
    int sp = 1;
    while (sp > 0) {
        int top = sp - 1;
        uint index = f_node[top];
        OctNode n = oct_nodes[index];
        uint cur;
        if (f_cur[top] == OCT_FRESH) {
            float enter = oct_max3(f_t0[top]);
            float exit = oct_min3(f_t1[top]);
            if (exit < r.tmin || enter > r.tmax) {
                sp -= 1;
                continue;
            }
            if (oct_is_leaf(n)) {
                if (oct_leaf(index, max(enter, r.tmin), min(exit, r.tmax))) {
                    return;
                }
                sp -= 1;
                continue;
            }
            oc.steps += 1u;
            vec3 tm;
            for (int a = 0; a < 3; ++a) {
                tm[a] = oct_cross(r, n.split[a], a);
            }
            f_tm[top] = tm;
            cur = oct_first_child(f_t0[top], tm);
        } else {
            vec3 t1c;
            for (int a = 0; a < 3; ++a) {
                t1c[a] = (f_cur[top] & oct_axis_bit(a)) != 0u ? f_t1[top][a] : f_tm[top][a];
            }
            int axis = oct_exit_axis(t1c);
            if ((f_cur[top] & oct_axis_bit(axis)) != 0u) {
                sp -= 1;
                continue;
            }
            cur = f_cur[top] | oct_axis_bit(axis);
        }
        f_cur[top] = cur;
        vec3 c0;
        vec3 c1;
        for (int a = 0; a < 3; ++a) {
            if ((cur & oct_axis_bit(a)) != 0u) {
                c0[a] = f_tm[top][a];
                c1[a] = f_t1[top][a];
            } else {
                c0[a] = f_t0[top][a];
                c1[a] = f_tm[top][a];
            }
        }
        f_node[sp] = n.info.x + (cur ^ mask);
        f_cur[sp] = OCT_FRESH;
        f_t0[sp] = c0;
        f_t1[sp] = c1;
        f_tm[sp] = vec3(0.0);
        sp += 1;
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
