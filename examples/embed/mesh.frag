#version 460
// One opaque colour per cube face.

layout(location = 0) flat in uint face;
layout(location = 0) out vec4 colour;

const vec3 COLOURS[6] = vec3[6](
    vec3(0.8, 0.2, 0.2), vec3(0.2, 0.8, 0.2), vec3(0.2, 0.2, 0.8),
    vec3(0.8, 0.8, 0.2), vec3(0.2, 0.8, 0.8), vec3(0.8, 0.2, 0.8));

void main() {
    colour = vec4(COLOURS[face], 1.0);
}
