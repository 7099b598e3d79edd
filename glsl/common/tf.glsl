// Transfer function: an RGBA LUT over normalised values [0, 1], linearly
// interpolated between entries. The LUT holds two tables of n entries,
// written per frame by glsl/build/opacity_lut.comp: first alpha corrected for
// the frame's step dt (a full-length sample's opacity), then the raw alpha
// per voxel of path length (for a shortened sample). It is read as a texel
// buffer: lavapipe fetches texels with vector loads, where it reads a
// storage buffer one lane at a time (the lookup then cost a third of a naive
// sample). The values and the interpolation are the same either way.
#ifndef LACUNA_TF_GLSL
#define LACUNA_TF_GLSL

layout(set = 0, binding = TF_BINDING) uniform samplerBuffer tf_lut;

// Table `base` (0: corrected, n: raw) of n entries at value v.
vec4 tf_lookup(float v, uint base, uint n) {
    precise float x = v * float(n - 1u);
    float fl = floor(x);
    uint i = min(uint(fl), n - 1u);
    uint j = min(i + 1u, n - 1u);
    precise float f = x - fl;
    precise vec4 c = mix(texelFetch(tf_lut, int(base + i)), texelFetch(tf_lut, int(base + j)), f);
    return c;
}

#endif
