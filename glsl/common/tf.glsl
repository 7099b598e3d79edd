// Transfer function: an RGBA LUT over normalised values [0, 1], linearly
// interpolated between entries. The buffer holds two tables of TF_SIZE
// entries, written per frame by glsl/build/opacity_lut.comp: first alpha
// corrected for the frame's step dt (a full-length sample's opacity), then
// the raw alpha per voxel of path length (for a shortened sample).
// The includer defines TF_SIZE (the LUT entry count expression).
#ifndef LACUNA_TF_GLSL
#define LACUNA_TF_GLSL

layout(std430, set = 0, binding = TF_BINDING) readonly buffer TransferLut {
    vec4 tf_lut[];
};

// Table `base` (0: corrected, TF_SIZE: raw) at value v.
vec4 tf_lookup(float v, uint base) {
    uint n = TF_SIZE;
    precise float x = v * float(n - 1u);
    float fl = floor(x);
    uint i = min(uint(fl), n - 1u);
    uint j = min(i + 1u, n - 1u);
    precise float f = x - fl;
    precise vec4 c = mix(tf_lut[base + i], tf_lut[base + j], f);
    return c;
}

#endif
