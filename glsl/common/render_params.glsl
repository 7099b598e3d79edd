// Per-frame render parameters, written by src/render/params.rs::RenderParams;
// keep both in the same order. A read-only storage block, not a uniform
// block: lavapipe inlines uniform-block values used in branches into the
// shader and compiles a new variant whenever they change, i.e. every frame
// the camera moves (a ~50 ms stall per frame without Mesa's disk cache).
// Every fixed member is a vec4 or mat4, so std430 and std140 lay it out alike.
#ifndef LACUNA_RENDER_PARAMS_GLSL
#define LACUNA_RENDER_PARAMS_GLSL

#ifndef PARAMS_ACCESS
#define PARAMS_ACCESS readonly
#endif

layout(std430, set = 0, binding = PARAMS_BINDING) PARAMS_ACCESS buffer RenderParamsBlock {
    // Pixel (x, y) maps to the point base + (x + 0.5) * du + (y + 0.5) * dv,
    // all in voxel space (box [0, N] per axis, voxel i centred at i + 0.5).
    vec4 base;
    vec4 du;
    vec4 dv;
    // xyz: orthographic ray direction, or the perspective eye; w: 0 = ortho, 1 = perspective.
    vec4 eye_or_dir;
    // xyz: volume dimensions in voxels; w: transfer-function LUT entries.
    uvec4 dims;
    // x, y: image size in pixels.
    uvec4 image;
    // x: step dt in voxels; y: early-ray-termination alpha (> 1 = off);
    // z, w: value normalisation, v = (texel - z) * w.
    vec4 march;
    // NDC (x, y, depth, 1) to homogeneous voxel space (host depth images).
    mat4 ndc_to_voxel;
    // x: the far plane's depth (no surface); y: 1 when rays end at t_max.
    vec4 depth;
    // Per pixel (row-major), when depth.y == 1: the ray's t where the host's
    // opaque surface is, written by glsl/render/depth_limit.comp.
    float t_max[];
} params;

#endif
