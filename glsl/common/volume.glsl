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

layout(set = 0, binding = VOLUME_BINDING) uniform sampler3D volume_tex;
layout(constant_id = 16) const uint VOLUME_FILTER = 0u;

float volume_texel(ivec3 i, ivec3 hi) {
    return texelFetch(volume_tex, clamp(i, ivec3(0), hi), 0).r;
}

// Normalised value in [0, 1] at voxel-space point p.
// The stored texel value at p, trilinearly interpolated by hand.
float sample_manual(vec3 p) {
    ivec3 hi = ivec3(params.dims.xyz) - 1;
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

// Normalised value in [0, 1] at voxel-space point p.
float sample_volume(vec3 p) {
    precise float raw;
    if (VOLUME_FILTER == 1u) {
        // Normalised coordinates (3D images allow no others): the sampler's
        // u * N - 0.5 puts voxel i's centre at i + 0.5, as the manual path.
        precise vec3 uvw = p / vec3(params.dims.xyz);
        raw = textureLod(volume_tex, uvw, 0.0).r;
    } else {
        raw = sample_manual(p);
    }
    precise float v = (raw - params.march.z) * params.march.w;
    return clamp(v, 0.0, 1.0);
}

#endif
