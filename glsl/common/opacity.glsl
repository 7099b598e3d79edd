// Opacity correction: alpha a per voxel of path length, over a path of w
// voxels, is 1 - (1 - a)^w. Exact 0 and 1 stay exact (a transparent entry
// must contribute exactly nothing). Shared by the corrected-LUT kernel and
// the march's shortened last sample; src/tf.rs::opacity mirrors it.
#ifndef LACUNA_OPACITY_GLSL
#define LACUNA_OPACITY_GLSL

float opacity(float a, float w) {
    if (!(a > 0.0)) {
        return 0.0;
    }
    if (a >= 1.0) {
        return 1.0;
    }
    precise float o = 1.0 - pow(1.0 - a, w);
    return o;
}

#endif
