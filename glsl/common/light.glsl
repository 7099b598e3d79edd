// Gradient shading (src/desc/look.rs `Shading`): Blinn-Phong with white
// light, two-sided, lighting a sample's transfer-function colour by the
// gradient of the trilinear field (central differences one voxel apart,
// in normalised value per unit of physical length). A zero or non-finite
// gradient leaves the colour lit as if facing the light, without the
// specular term. Needs volume.glsl; src/render/reference.rs mirrors it.
#ifndef LACUNA_LIGHT_GLSL
#define LACUNA_LIGHT_GLSL

// The gradient at p (the filter's coordinates) in physical space.
vec3 volume_gradient(VolumeRay r, vec3 p) {
    vec3 g;
    for (int a = 0; a < 3; ++a) {
        vec3 e = vec3(0.0);
        e[a] = r.unit[a];
        precise float hi = sample_raw(r, p + e);
        precise float lo = sample_raw(r, p - e);
        precise float d = (hi - lo) * 0.5 * r.norm.y;
        g[a] = d / params.spacing[a];
    }
    return g;
}

// The sample colour c lit at p, seen along the ray direction `dir` (voxel
// space); its opacity times the gradient-opacity ramp when that is on.
vec4 light_sample(VolumeRay r, vec3 p, vec3 dir, vec4 c) {
    vec3 g = volume_gradient(r, p);
    precise float len = length(g);
    vec4 ks = params.shading; // ambient, diffuse, specular, shininess
    precise vec3 view = normalize(-dir * params.spacing);
    vec3 l = params.headlight != 0u ? view : params.light;
    vec3 lit;
    // Not finite only where a NaN voxel is read (NaN volumes).
    if (len > 0.0 && len < 3.4e38) {
        precise vec3 n = g / len;
        precise vec3 h = normalize(l + view);
        precise float nd = abs(dot(n, l));
        precise float nh = abs(dot(n, h));
        precise vec3 shaded = c.rgb * (ks.x + ks.y * nd) + vec3(ks.z * pow(nh, ks.w));
        lit = shaded;
    } else {
        precise vec3 flat_lit = c.rgb * (ks.x + ks.y);
        lit = flat_lit;
    }
    float a = c.a;
    if (params.gradient_opacity != 0u) {
        precise float ramp = (len - params.gradient_lo) / (params.gradient_hi - params.gradient_lo);
        a *= is_nan(ramp) ? 0.0 : clamp(ramp, 0.0, 1.0);
    }
    return vec4(min(lit, vec3(1.0)), a);
}

#endif
