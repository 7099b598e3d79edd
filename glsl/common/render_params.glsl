// Per-frame render parameters. The host fills `shaders::blocks::RenderParams`,
// which build.rs generates from this block (derived from a FrameDesc). A read-only storage block, not a uniform
// block: lavapipe inlines uniform-block values used in branches into the
// shader and compiles a new variant whenever they change, i.e. every frame
// the camera moves (a ~50 ms stall per frame without Mesa's disk cache).
#ifndef LACUNA_RENDER_PARAMS_GLSL
#define LACUNA_RENDER_PARAMS_GLSL

#ifndef PARAMS_ACCESS
#define PARAMS_ACCESS readonly
#endif

layout(std430, set = 0, binding = PARAMS_BINDING) PARAMS_ACCESS buffer RenderParams {
    // Pixel (x, y) maps to the point base + (x + 0.5) * du + (y + 0.5) * dv,
    // all in voxel space (box [0, N] per axis, voxel i centred at i + 0.5).
    // Each vec3 shares its 16 bytes with a scalar, so the block has no gaps.
    vec3 base;
    uint perspective; // 0: orthographic rays along eye_or_dir; 1: rays from the eye eye_or_dir
    vec3 du;
    float step;       // the sample spacing dt, in voxels
    vec3 dv;
    float ert;        // early-ray-termination alpha (1: off, see ERT_OFF)
    vec3 eye_or_dir;
    uint lut_size;    // transfer-function LUT entries
    uvec3 dims;       // volume dimensions in voxels
    uint depth_limits; // 1: each ray ends at its t_max below
    uvec2 image;      // image size in pixels
    vec2 norm;        // value normalisation, v = (texel - norm.x) * norm.y
    // NDC (x, y, depth, 1) to homogeneous voxel space (host depth images).
    mat4 ndc_to_voxel;
    float far_depth;  // the depth of the far plane: no surface there
    uint jitter;      // 1: each pixel's lattice starts a hashed fraction of a step later
    uint clip_count;  // clip planes in use
    uint crop;        // 1: the crop box applies
    vec4 clip[6];     // keep a x + b y + c z + d >= 0 (voxel space)
    vec3 crop_lo;     // the crop box (voxel space)
    uint iso_count;   // iso values in use (mode iso)
    vec3 crop_hi;
    uint iso_colored; // 1: iso surfaces take iso_color, else the TF's colour at the value
    vec4 iso;         // iso values (normalised)
    vec3 iso_color;
    float gradient_lo; // gradient opacity: 0 at this gradient magnitude...
    vec3 light;       // direction toward a fixed light (physical space, unit)
    uint headlight;   // 1: the light is at the eye
    vec4 shading;     // ambient, diffuse, specular, shininess
    vec3 spacing;     // physical size of a voxel
    float gradient_hi; // ...1 at this one
    uint gradient_opacity; // 1: opacity times the gradient ramp (the CPU reference reads it; kernels take MARCH_SHADE == 2)
    // MIP (MinIP): values at or below (above) value_bound map to transparent;
    // a sample exceeds its footprint's value range by at most value_margin
    // (src/accel/mode.rs). Read by structures that skip per ray.
    float value_bound;
    float value_margin;
    // Iso frames' surface depth (frame_out.glsl): 0 not written; 1 NDC
    // depth through voxel_to_ndc (host camera matrices); 2 distance from the
    // ray's origin in physical units. no_hit_depth where a ray hits nothing.
    // 3: a rank's MIP (MinIP) segment writes its ray's largest (smallest)
    // sample instead, -1 (2) where it took none, for the ranks' compositing.
    uint depth_out;
    mat4 voxel_to_ndc;
    float no_hit_depth;
    // Several channels (VOLUME_CHANNELS > 1): how far apart channels' LUT
    // tables are, in tables (0: one transfer function for every channel),
    // and each channel's normalisation, v = (texel - lo) * scale.
    uint tf_channel_step;
    uint channel_pad0;
    uint channel_pad1;
    vec4 channel_lo;
    vec4 channel_scale;
    // A data-parallel rank's block (src/parallel), when segment == 1: only
    // the lattice samples inside [segment_lo, segment_hi] (voxel space).
    vec3 segment_lo;
    uint segment;
    vec3 segment_hi;
    uint segment_pad;
    // Per pixel (row-major), when depth_limits == 1: the ray's t where the
    // host's opaque surface is, written by glsl/render/depth_limit.comp.
    float t_max[];
} params;

#endif
