// Surface primitives of the SPD scenes (format in src/octree/prims.rs) and
// their ray intersections, mirrored operation for operation by the CPU
// reference (`precise` everywhere: no fused multiply-adds). The includer
// binds `prims` (Prim[]) and `verts` (vec4[]). Directions are unit length.
#ifndef LACUNA_OCTREE_PRIMS_GLSL
#define LACUNA_OCTREE_PRIMS_GLSL

struct Prim {
    vec4 a;
    vec4 b;
    vec4 c;
    uvec4 info;
};

float dot3(vec3 a, vec3 b) {
    precise float r = a.x * b.x + a.y * b.y + a.z * b.z;
    return r;
}

// Nearest t in (tmin, tmax) where o + t d meets prim p, or -1 (no hit).
float intersect_prim(Prim p, vec3 o, vec3 d, float tmin, float tmax) {
    if (p.info.x == 0u) {
        precise vec3 oc = o - p.a.xyz;
        precise float b = dot3(oc, d);
        precise vec3 f = oc - b * d;
        precise float disc = p.a.w * p.a.w - dot3(f, f);
        if (disc < 0.0) {
            return -1.0;
        }
        precise float h = sqrt(disc);
        precise float t0 = -b - h;
        if (t0 > tmin && t0 < tmax) {
            return t0;
        }
        precise float t1 = -b + h;
        return (t1 > tmin && t1 < tmax) ? t1 : -1.0;
    }
    if (p.info.x == 1u) {
        vec3 u = p.b.xyz;
        precise vec3 w = o - p.a.xyz;
        precise float a0 = dot3(w, u);
        precise float ad = dot3(d, u);
        precise vec3 wp = w - a0 * u;
        precise vec3 dp = d - ad * u;
        float k = p.c.x;
        precise float rr = p.a.w + k * a0;
        precise float qa = dot3(dp, dp) - k * k * ad * ad;
        precise float qb = 2.0 * (dot3(wp, dp) - rr * k * ad);
        precise float qc = dot3(wp, wp) - rr * rr;
        precise float disc = qb * qb - 4.0 * qa * qc;
        if (qa == 0.0 || disc < 0.0) {
            return -1.0;
        }
        precise float s = sqrt(disc);
        precise float t0 = (-qb - s) / (2.0 * qa);
        precise float t1 = (-qb + s) / (2.0 * qa);
        if (t0 > t1) {
            float x = t0;
            t0 = t1;
            t1 = x;
        }
        for (int i = 0; i < 2; ++i) {
            float t = i == 0 ? t0 : t1;
            if (t > tmin && t < tmax) {
                precise float along = a0 + t * ad;
                precise float radius = p.a.w + k * along;
                if (along >= 0.0 && along <= p.b.w && radius >= 0.0) {
                    return t;
                }
            }
        }
        return -1.0;
    }
    vec3 n = p.b.xyz;
    precise float denom = dot3(n, d);
    if (denom == 0.0) {
        return -1.0;
    }
    precise float t = (p.b.w - dot3(n, o)) / denom;
    if (!(t > tmin && t < tmax)) {
        return -1.0;
    }
    precise vec3 hit = o + t * d;
    int drop = int(p.info.w);
    int iu = (drop + 1) % 3;
    int iv = (drop + 2) % 3;
    float pu = hit[iu];
    float pv = hit[iv];
    uint first = p.info.y;
    uint count = p.info.z;
    bool odd = false;
    uint j = count - 1u;
    for (uint i = 0u; i < count; ++i) {
        vec4 va = verts[first + i];
        vec4 vb = verts[first + j];
        if ((va[iv] > pv) != (vb[iv] > pv)) {
            precise float x = (vb[iu] - va[iu]) * (pv - va[iv]) / (vb[iv] - va[iv]) + va[iu];
            if (pu < x) {
                odd = !odd;
            }
        }
        j = i;
    }
    return odd ? t : -1.0;
}

#endif
