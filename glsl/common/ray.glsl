// Rays and ray/box intersection, robust to direction components that are exactly 0.
#ifndef LACUNA_RAY_GLSL
#define LACUNA_RAY_GLSL

struct Ray {
    vec3 org;
    vec3 dir; // unit length in voxel space: t is measured in voxels
};

// Slab test against [lo, hi]. A zero direction component never divides: the
// ray is inside that slab for all t or for none. Returns (t_near, t_far);
// empty when t_near > t_far.
vec2 intersect_box(Ray r, vec3 lo, vec3 hi) {
    float t0 = -3.4e38;
    float t1 = 3.4e38;
    for (int a = 0; a < 3; ++a) {
        if (r.dir[a] == 0.0) {
            if (r.org[a] < lo[a] || r.org[a] > hi[a]) {
                return vec2(1.0, -1.0);
            }
        } else {
            precise float inv = 1.0 / r.dir[a];
            precise float ta = (lo[a] - r.org[a]) * inv;
            precise float tb = (hi[a] - r.org[a]) * inv;
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    return vec2(t0, t1);
}

#endif
