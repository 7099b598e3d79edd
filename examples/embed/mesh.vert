#version 460
// A cube from gl_VertexIndex (36 vertices, no vertex buffer): the host's mesh.

layout(push_constant) uniform Push {
    mat4 clip_from_world;
    vec4 centre_half; // xyz: centre (world); w: half edge
} push;

layout(location = 0) flat out uint face;

const vec3 CORNERS[8] = vec3[8](
    vec3(-1, -1, -1), vec3(1, -1, -1), vec3(-1, 1, -1), vec3(1, 1, -1),
    vec3(-1, -1, 1), vec3(1, -1, 1), vec3(-1, 1, 1), vec3(1, 1, 1));
// Two triangles per face: -x, +x, -y, +y, -z, +z.
const uint INDICES[36] = uint[36](
    0, 4, 6, 0, 6, 2,  1, 3, 7, 1, 7, 5,
    0, 1, 5, 0, 5, 4,  2, 6, 7, 2, 7, 3,
    0, 2, 3, 0, 3, 1,  4, 5, 7, 4, 7, 6);

void main() {
    vec3 p = push.centre_half.xyz + push.centre_half.w * CORNERS[INDICES[gl_VertexIndex]];
    face = uint(gl_VertexIndex) / 6u;
    gl_Position = push.clip_from_world * vec4(p, 1.0);
}
