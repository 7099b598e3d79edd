// Trilinear volume sampling with clamp-to-edge, done by hand from texelFetch so
// every device (and the CPU reference) computes the same weights in full float
// precision; hardware filtering uses low-precision weights on many GPUs.
#ifndef LACUNA_VOLUME_GLSL
#define LACUNA_VOLUME_GLSL

layout(set = 0, binding = VOLUME_BINDING) uniform sampler3D volume_tex;

float volume_texel(ivec3 i, ivec3 hi) {
    return texelFetch(volume_tex, clamp(i, ivec3(0), hi), 0).r;
}

// Normalised value in [0, 1] at voxel-space point p.
float sample_volume(vec3 p) {
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
    precise float v = (raw - params.march.z) * params.march.w;
    return clamp(v, 0.0, 1.0);
}

#endif
