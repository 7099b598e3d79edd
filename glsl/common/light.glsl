// Gradient shading (src/desc/shading.rs `Shading`): Blinn-Phong with white
// light, two-sided, lighting a sample's transfer-function colour by the
// gradient of the trilinear field (central differences one voxel apart,
// read from the gradient volume: src/volume/gradient.rs), in normalised
// value per shortest voxel side. A zero or non-finite gradient leaves
// the colour lit as if facing the light, without the specular term. Needs
// volume.glsl; src/render/reference/mod.rs mirrors it.
#ifndef LACUNA_LIGHT_GLSL
#define LACUNA_LIGHT_GLSL

// The Phong exponent where it is a whole number (1 to 128; 0: any other,
// through pow): x^n by repeated squaring, in place of pow's logarithm and
// exponential (about 9 % of a lit ch2 frame on lavapipe). Each squaring
// doubles the relative error: within 1e-5 of pow at 128 (about 64 ulps).
// src/render/reference/mod.rs mirrors it.
layout(constant_id = 29) const uint MARCH_SHININESS = 0u;

float specular_power(float x, float s) {
    if (MARCH_SHININESS == 0u) {
        return pow(x, s);
    }
    // Eight bit tests of a constant, which the compiler unrolls and folds
    // once the exponent is specialized (a loop whose trip count was the
    // exponent stayed a loop on lavapipe, slower than pow).
    float r = 1.0;
    float b = x;
    for (uint bit = 0u; bit < 8u; ++bit) {
        if (((MARCH_SHININESS >> bit) & 1u) != 0u) {
            r *= b;
        }
        if ((MARCH_SHININESS >> (bit + 1u)) != 0u) {
            b *= b;
        }
    }
    return r;
}

// What lighting a ray's samples needs, read from the parameters once per
// ray (a storage-buffer read per sample is dear on lavapipe): the light and
// half vectors for this ray's view direction, the Phong weights, the
// voxel spacing and the gradient-opacity ramp.
struct Lighting {
    vec3 l;
    vec3 h;
    vec4 ks;       // ambient, diffuse, specular, shininess
    vec2 ramp_lo_hi;
};

// The lighting of a ray along `dir` (voxel space).
Lighting lighting_for(vec3 dir) {
    Lighting lt;
    // The spacing relative to the shortest side: the spacing itself
    // overflows (or underflows) normalize's square at 1e20 (1e-20) a voxel.
    precise vec3 relative = params.spacing / min(min(params.spacing.x, params.spacing.y), params.spacing.z);
    precise vec3 view = normalize(-dir * relative);
    lt.l = params.headlight != 0u ? view : params.light;
    precise vec3 h = normalize(lt.l + view);
    lt.h = h;
    lt.ks = params.shading;
    lt.ramp_lo_hi = vec2(params.gradient_lo, params.gradient_hi);
    return lt;
}

// The sample colour c lit at p (the filter's coordinates); its opacity
// times the gradient-opacity ramp when `ramp` (a constant: a CPU SIMD lane
// would run the ramp's code whether or not it is on). The gradient volume is
// scaled by the spacing already (its ramp too), and the normal is the gradient times the
// inverse square root of its square: no division per sample.
vec4 light_sample(VolumeRay r, Lighting lt, vec3 p, vec4 c, bool ramp) {
    precise vec3 g = sample_gradient(r, p);
    precise float d = dot(g, g);
    vec3 lit;
    // Not finite only where a NaN voxel is read (NaN volumes).
    if (d > 0.0 && d < 3.4e38) {
        precise vec3 n = g * inversesqrt(d);
        precise float nd = abs(dot(n, lt.l));
        precise float nh = abs(dot(n, lt.h));
        precise vec3 shaded = c.rgb * (lt.ks.x + lt.ks.y * nd) + vec3(lt.ks.z * specular_power(nh, lt.ks.w));
        lit = shaded;
    } else {
        precise vec3 flat_lit = c.rgb * (lt.ks.x + lt.ks.y);
        lit = flat_lit;
    }
    float a = c.a;
    if (ramp) {
        precise float len = sqrt(d);
        precise float ramp = (len - lt.ramp_lo_hi.x) / (lt.ramp_lo_hi.y - lt.ramp_lo_hi.x);
        a *= is_nan(ramp) ? 0.0 : clamp(ramp, 0.0, 1.0);
    }
    return vec4(min(lit, vec3(1.0)), a);
}

#endif
