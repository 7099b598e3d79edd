// Trilinear volume sampling with clamp-to-edge, by one of two filters chosen
// per kernel by a specialization constant (src/volume/filter.rs), so no
// sample branches on it:
// 0 (manual): by hand from eight texelFetch, so every device (and the CPU
//   reference) computes the same weights in full float precision;
// 1 (hardware): the sampler's linear filtering (a linear sampler bound),
//   one fetch, weights of the device's subTexelPrecisionBits. Its weights are
//   still a convex combination of the same eight voxels, so the one-voxel
//   apron of the classification still covers every value it returns.
#ifndef LACUNA_VOLUME_GLSL
#define LACUNA_VOLUME_GLSL

#include "nan.glsl"

layout(set = 0, binding = VOLUME_BINDING) uniform sampler3D volume_tex;
layout(constant_id = 16) const uint VOLUME_FILTER = 0u;
// 1: the volume holds NaN voxels ("no data"; src/volume, README "NaN"). A
// sample any of whose eight voxels is NaN is NaN (IEEE arithmetic carries
// it through the interpolation), and NaN samples contribute nothing. Only
// the manual filter samples such volumes: hardware filtering of NaN is the
// device's to define.
layout(constant_id = 19) const uint VOLUME_NAN = 0u;

// What sampling along one ray needs, loaded once per ray: a storage-buffer
// read per sample is dear on lavapipe, and the hardware path's coordinates
// are then a multiply and an add per axis rather than also a division.
struct VolumeRay {
    vec3 org;  // the ray in the filter's coordinates: voxels (manual) or
    vec3 dir;  // normalised texture coordinates (hardware)
    vec3 unit; // one voxel along each axis in those coordinates
    ivec3 hi;  // the last voxel per axis
    vec2 norm; // v = (texel - norm.x) * norm.y
};

VolumeRay volume_ray(vec3 org, vec3 dir) {
    VolumeRay v;
    vec3 dims = vec3(params.dims);
    if (VOLUME_FILTER == 1u) {
        // The sampler's u * N - 0.5 puts voxel i's centre at i + 0.5, as the
        // manual path (3D images allow no unnormalised coordinates).
        precise vec3 o = org / dims;
        precise vec3 d = dir / dims;
        v.org = o;
        v.dir = d;
        v.unit = 1.0 / dims;
    } else {
        v.org = org;
        v.dir = dir;
        v.unit = vec3(1.0);
    }
    v.hi = ivec3(params.dims) - 1;
    v.norm = params.norm;
    return v;
}

float volume_texel(ivec3 i, ivec3 hi) {
    return texelFetch(volume_tex, clamp(i, ivec3(0), hi), 0).r;
}

// The stored texel value at p, trilinearly interpolated by hand.
float sample_manual(vec3 p, ivec3 hi) {
    // `precise` everywhere on the sampling path: every kernel that inlines this
    // must round identically (no kernel-dependent FMA contraction).
    precise vec3 q = p - 0.5;
    vec3 fl = floor(q);
    precise vec3 f = q - fl;
    ivec3 i = ivec3(fl);
    float c000 = volume_texel(i, hi);
    float c100 = volume_texel(i + ivec3(1, 0, 0), hi);
    float c010 = volume_texel(i + ivec3(0, 1, 0), hi);
    float c110 = volume_texel(i + ivec3(1, 1, 0), hi);
    float c001 = volume_texel(i + ivec3(0, 0, 1), hi);
    float c101 = volume_texel(i + ivec3(1, 0, 1), hi);
    float c011 = volume_texel(i + ivec3(0, 1, 1), hi);
    float c111 = volume_texel(i + ivec3(1, 1, 1), hi);
    precise float c00 = mix(c000, c100, f.x);
    precise float c10 = mix(c010, c110, f.x);
    precise float c01 = mix(c001, c101, f.x);
    precise float c11 = mix(c011, c111, f.x);
    precise float c0 = mix(c00, c10, f.y);
    precise float c1 = mix(c01, c11, f.y);
    precise float raw = mix(c0, c1, f.z);
    return raw;
}

// The stored texel value at p (the filter's coordinates).
float sample_raw(VolumeRay r, vec3 p) {
    precise float raw;
    if (VOLUME_FILTER == 1u) {
        raw = textureLod(volume_tex, p, 0.0).r;
    } else {
        raw = sample_manual(p, r.hi);
    }
    return raw;
}

#ifdef GRADIENT_BINDING
// The volume's gradient (src/volume/gradient.rs): per voxel (x, y, z) in
// normalised value per voxel; bound for shaded and iso frames (the volume
// image stands in for it otherwise, and nothing reads it).
layout(set = 0, binding = GRADIENT_BINDING) uniform sampler3D gradient_tex;

// The gradient at p (the filter's coordinates), in normalised value per
// voxel, by the volume's filter: interpolated by hand with the weights
// sample_manual uses, or by the sampler.
vec3 sample_gradient(VolumeRay r, vec3 p) {
    if (VOLUME_FILTER == 1u) {
        return textureLod(gradient_tex, p, 0.0).xyz;
    }
    precise vec3 q = p - 0.5;
    vec3 fl = floor(q);
    precise vec3 f = q - fl;
    ivec3 i = ivec3(fl);
    ivec3 hi = r.hi;
    vec3 c000 = texelFetch(gradient_tex, clamp(i, ivec3(0), hi), 0).xyz;
    vec3 c100 = texelFetch(gradient_tex, clamp(i + ivec3(1, 0, 0), ivec3(0), hi), 0).xyz;
    vec3 c010 = texelFetch(gradient_tex, clamp(i + ivec3(0, 1, 0), ivec3(0), hi), 0).xyz;
    vec3 c110 = texelFetch(gradient_tex, clamp(i + ivec3(1, 1, 0), ivec3(0), hi), 0).xyz;
    vec3 c001 = texelFetch(gradient_tex, clamp(i + ivec3(0, 0, 1), ivec3(0), hi), 0).xyz;
    vec3 c101 = texelFetch(gradient_tex, clamp(i + ivec3(1, 0, 1), ivec3(0), hi), 0).xyz;
    vec3 c011 = texelFetch(gradient_tex, clamp(i + ivec3(0, 1, 1), ivec3(0), hi), 0).xyz;
    vec3 c111 = texelFetch(gradient_tex, clamp(i + ivec3(1, 1, 1), ivec3(0), hi), 0).xyz;
    precise vec3 c00 = mix(c000, c100, f.x);
    precise vec3 c10 = mix(c010, c110, f.x);
    precise vec3 c01 = mix(c001, c101, f.x);
    precise vec3 c11 = mix(c011, c111, f.x);
    precise vec3 c0 = mix(c00, c10, f.y);
    precise vec3 c1 = mix(c01, c11, f.y);
    precise vec3 g = mix(c0, c1, f.z);
    return g;
}
#endif

// Normalised value in [0, 1] at the ray's point t (NaN: no data).
float sample_volume(VolumeRay r, float t) {
    precise vec3 p = r.org + t * r.dir;
    precise float v = (sample_raw(r, p) - r.norm.x) * r.norm.y;
    if (VOLUME_NAN != 0u && is_nan(v)) {
        return v;
    }
    return clamp(v, 0.0, 1.0);
}

#endif
