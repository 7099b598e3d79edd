// Transfer function: an RGBA LUT over normalised values [0, 1], linearly
// interpolated between entries. Alpha is opacity per voxel of path length.
// The includer defines TF_SIZE (the LUT entry count expression).
#ifndef LACUNA_TF_GLSL
#define LACUNA_TF_GLSL

layout(std430, set = 0, binding = TF_BINDING) readonly buffer TransferLut {
    vec4 tf_lut[];
};

vec4 tf_lookup(float v) {
    uint n = TF_SIZE;
    precise float x = v * float(n - 1u);
    float fl = floor(x);
    uint i = min(uint(fl), n - 1u);
    uint j = min(i + 1u, n - 1u);
    precise float f = x - fl;
    precise vec4 c = mix(tf_lut[i], tf_lut[j], f);
    return c;
}

#endif
