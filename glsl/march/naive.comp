#version 460
// Naive ray marching: every lattice sample from entry to exit.
#extension GL_GOOGLE_include_directive : require

#include "march.glsl"

void march_ray(inout March m) {
    march_rest(m);
}
