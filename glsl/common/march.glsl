// The prologue of every march kernel (glsl/march/*.comp): the common
// bindings, the workgroup, the lattice march and main. A kernel is
//
//     #version 460
//     #extension GL_GOOGLE_include_directive : require
//     #include "march.glsl"
//     ... its own bindings (binding = OWN_BINDING + i; the host binds them by
//     name), specialization constants, push block and traversal ...
//     void march_ray(inout March m) { ... }
//
// march_ray marches pixel's ray m (entered by march_pixel, so m.t_enter <
// m.t_exit) through the structure on the global lattice (lattice.glsl); a
// march that reaches the ray's last sample leaves it due and ends (m.done),
// and main takes it after march_ray (march_finish).
#ifndef LACUNA_MARCH_GLSL
#define LACUNA_MARCH_GLSL
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require

#define PARAMS_BINDING 0
#define VOLUME_BINDING 1
#define TF_BINDING 2
#define FRAME_BINDING 3
#define DEPTH_BINDING 4
#define GRADIENT_BINDING 5
#define CELLS_BINDING 6
#define GRADIENT_CELLS_BINDING 7
#define BRICK_TABLE_BINDING 8
#define POOL_BINDING 9 // and 10, 11
#define STATUS_BINDING 12
#define OWN_BINDING 13

// 8x8: march_pixel_id's Morton order assumes it.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
// Every tile at 1; at S > 1 the frame's blocks of PROBE_BLOCK x PROBE_BLOCK
// tiles whose block coordinates are multiples of S, for auto's counting and
// trial frames (src/accel/probe.rs): a sparse sample of the frame in
// blocks, so neighbouring rays share the caches as in the whole frame.
layout(constant_id = 23) const uint MARCH_TILE_STRIDE = 1u;
const uint PROBE_BLOCK = 4u;

// The tile workgroup `wg` marches.
uvec2 march_tile(uvec2 wg) {
    if (MARCH_TILE_STRIDE == 1u) {
        return wg;
    }
    return (wg / PROBE_BLOCK) * (PROBE_BLOCK * MARCH_TILE_STRIDE) + wg % PROBE_BLOCK;
}

#include "render_params.glsl"
#include "ray.glsl"
#include "camera.glsl"
#include "volume.glsl"
#include "tf.glsl"
#include "lattice.glsl"
#include "frame_out.glsl"

// lavapipe (gallivm) ends a SIMD group's loops after LP_MAX_TGSI_LOOP_ITERATIONS
// passes of all its loops together, without a word: a march past that ends
// its rays early. 1 (on such a device, src/accel/kernels.rs) counts, after the
// march, the groups that may have been cut short in march_status.
layout(constant_id = 24) const uint MARCH_LOOP_CHECK = 0u;

layout(std430, set = 0, binding = STATUS_BINDING) buffer MarchStatus {
    uint cut_groups;
} march_status;

// The budget is one counter per group for every loop of the kernel, and a
// loop ends after a pass that leaves it at 0 or below. So a loop of two
// passes run last runs only one when at most one pass was left: every cut
// is counted, and so is a march that stopped a pass short of the cap (a
// false alarm, never a missed cut). Its trip count is read from memory so
// that no compiler can unroll it away.
void check_loop_cap() {
    if (MARCH_LOOP_CHECK == 0u) {
        return;
    }
    uint passes = 0u;
    uint want = 2u + (params.image.x >> 31u);
    for (uint i = 0u; i < want; ++i) {
        passes++;
    }
    if (passes < want && subgroupElect()) {
        atomicAdd(march_status.cut_groups, 1u);
    }
}

void march_ray(inout March m);

// The pixel of this invocation: the workgroup's 8x8 tile in Morton order,
// so a SIMD group of 8 lanes (lavapipe) marches a 4x2 block of pixels and
// one of 32 an 8x4 block, not a row. Neighbouring rays in both directions
// take more alike paths than a row does (a group runs until its slowest
// lane is done): on lavapipe this took 10-14 % fewer group iterations of
// the sample loop than rows of 8 (docs/results/samples.md). Each pixel's
// ray, and so the image, is the same either way.
uvec2 march_pixel_id() {
    uint n = gl_LocalInvocationIndex;
    uvec2 in_tile = uvec2((n & 1u) | ((n >> 1u) & 2u) | ((n >> 2u) & 4u),
                          ((n >> 1u) & 1u) | ((n >> 2u) & 2u) | ((n >> 3u) & 4u));
    return march_tile(gl_WorkGroupID.xy) * gl_WorkGroupSize.xy + in_tile;
}

// A counting frame's second half (after the image's pixels): what naive
// marching would take on this pixel's ray, derived from this march
// without running naive's (src/accel/probe.rs, `FrameProbe::count_both`):
// its full samples, all its samples and the lane's SIMD group. Every exact
// structure ends a ray that terminates (early ray termination, a MIP of
// 1, a MinIP of 0, an iso hit) after the very sample naive ends it after,
// so naive takes the samples from its first index k0 to there, or to
// k_end. The host sums, per group, its most full samples and one more
// iteration where any lane has its last sample left, as naive's loop runs.
void count_naive(uvec2 px, bool marched, int k0, March m) {
#ifndef FRAME_FORMAT
    bool ended = false;
    if (MARCH_MODE == MODE_COMPOSITE) {
        ended = m.acc.a >= m.ert;
    } else if (MARCH_MODE == MODE_ISO) {
        ended = m.hit;
    } else if (MARCH_MODE == MODE_MIP || MARCH_MODE == MODE_MINIP) {
        ended = true;
        for (uint c = 0u; c < VOLUME_CHANNELS; ++c) {
            float b = VOLUME_CHANNELS > 1u ? m.best4[c] : m.best;
            ended = ended && (MARCH_MODE == MODE_MIP ? b >= 1.0 : b <= 0.0);
        }
    }
    int n = marched ? (ended ? m.k : m.k_end) - k0 : 0;
    int full = marched ? min(n, max(m.k_end - 1 - k0, 0)) : 0;
    uint at = params.image.x * params.image.y + px.y * params.image.x + px.x;
    // A probe whose buffer holds one half (a frame near the device's
    // storage range) counts naive by its own march instead.
    if (at < uint(frame_pixels.length())) {
        frame_pixels[at] = vec4(float(full), float(n), float(gl_SubgroupID), 1.0);
    }
#endif
}

void main() {
    uvec2 px = march_pixel_id();
    if (px.x >= params.image.x || px.y >= params.image.y) {
        return;
    }
    March m;
    bool marched = march_pixel(px, m);
    int k0 = m.k;
    if (marched) {
        march_ray(m);
        march_finish(m);
        if (MARCH_MODE == MODE_ISO) {
            iso_refine(m);
        }
    }
    if (MARCH_COUNT != 0u) {
        frame_store(px, vec4(vec3(count_group), float(count_lane_samples)));
        count_naive(px, marched, k0, m);
    } else {
        frame_store(px, march_result(m));
        // Only iso frames hit a surface; the others write the far depth.
        if ((MARCH_CUTS & CUT_DEPTH_OUT) != 0u && params.depth_out != 0u) {
            depth_store(px, march_depth(m));
        }
    }
    // Last: a loop the pixel's result runs (lighting an iso hit) may be cut too.
    check_loop_cap();
}

#endif
