// Where a march kernel's pixel goes: the RGBA32F frame buffer, or (compiled
// with FRAME_FORMAT, one variant per format: build.rs) a host's storage image
// in GENERAL layout. Premultiplied RGBA either way. An iso frame's surface
// depth goes to a float per pixel, row-major (the target's depth buffer or a
// host's storage buffer: src/render/target.rs).
#ifndef LACUNA_FRAME_OUT_GLSL
#define LACUNA_FRAME_OUT_GLSL

#ifdef FRAME_FORMAT
layout(set = 0, binding = FRAME_BINDING, FRAME_FORMAT) uniform writeonly image2D frame;

void frame_store(uvec2 px, vec4 c) {
    imageStore(frame, ivec2(px), c);
}
#else
layout(std430, set = 0, binding = FRAME_BINDING) writeonly buffer Frame {
    vec4 frame_pixels[];
};

void frame_store(uvec2 px, vec4 c) {
    frame_pixels[px.y * params.image.x + px.x] = c;
}
#endif

layout(std430, set = 0, binding = DEPTH_BINDING) writeonly buffer FrameDepth {
    float frame_depth[];
};

void depth_store(uvec2 px, float d) {
    frame_depth[px.y * params.image.x + px.x] = d;
}

#endif
