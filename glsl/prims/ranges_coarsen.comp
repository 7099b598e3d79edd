#version 460
// Ranges of bricks `ratio` times as wide from the ranges of finer bricks
// over the same apron (brick_minmax.comp's output): per coarse brick and
// channel, the min of its fine bricks' minima and the max of their maxima.
// Exactly the coarse brick's own ranges: its fine bricks' boxes, each
// widened by the apron and clamped to the volume, cover its widened box
// and nothing outside it; and the normalisation (v - lo) * scale clamped
// to [0, 1] never reverses an order for a finite scale >= 0, so the
// extreme of the normalised extremes is the normalised extreme. An empty
// fine range (NaN voxels only: min 1 > max 0) leaves the others as they are.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "dispatch.glsl"
layout(std430, set = 0, binding = 0) readonly buffer Fine { vec2 fine[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Coarse { vec2 coarse[]; };
layout(push_constant) uniform Push {
    uvec4 fine_counts; // xyz: fine bricks per axis; w: channels
    uvec4 counts;      // xyz: coarse bricks per axis; w: total coarse bricks
    uint ratio;        // coarse edge / fine edge
    uint groups_x;
} pc;

void main() {
    uint b = linear_index(pc.groups_x);
    if (b >= pc.counts.w) {
        return;
    }
    uvec3 bc = uvec3(b % pc.counts.x, (b / pc.counts.x) % pc.counts.y, b / (pc.counts.x * pc.counts.y));
    uvec3 lo = bc * pc.ratio;
    uvec3 hi = min(lo + pc.ratio, pc.fine_counts.xyz);
    uint channels = pc.fine_counts.w;
    for (uint c = 0u; c < channels; ++c) {
        vec2 r = vec2(1.0, 0.0);
        for (uint z = lo.z; z < hi.z; ++z) {
            for (uint y = lo.y; y < hi.y; ++y) {
                for (uint x = lo.x; x < hi.x; ++x) {
                    vec2 f = fine[(x + pc.fine_counts.x * (y + pc.fine_counts.y * z)) * channels + c];
                    r = vec2(min(r.x, f.x), max(r.y, f.y));
                }
            }
        }
        coarse[b * channels + c] = r;
    }
}
