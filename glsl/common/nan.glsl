// NaN tests by bit pattern: a compiler that assumes no NaN may fold isnan()
// away, but not an integer comparison. NaN voxels are "no data" (README,
// "NaN and infinities"): samples that read one are NaN and contribute
// nothing, and value ranges ignore them.
#ifndef LACUNA_NAN_GLSL
#define LACUNA_NAN_GLSL

bool is_nan(float v) {
    return (floatBitsToUint(v) & 0x7fffffffu) > 0x7f800000u;
}

#endif
