// The global sample lattice (DESIGN invariant 1) and the one span-marching
// function every march kernel uses. Sample k sits at t_k = t_enter + k * dt,
// always computed from k; skipping moves k, never accumulates dt.
// Needs ray.glsl, volume.glsl and tf.glsl.
#ifndef LACUNA_LATTICE_GLSL
#define LACUNA_LATTICE_GLSL

#include "opacity.glsl"
#include "light.glsl"

// What a ray accumulates (src/desc/look.rs `Mode::constant`), and whether
// composite samples are lit: specialization constants, so a composite frame
// compiles to the plain composite march.
layout(constant_id = 17) const uint MARCH_MODE = 0u;
layout(constant_id = 18) const uint MARCH_SHADE = 0u;
// MARCH_SHADE: 1 lit; 2 lit, opacity times the gradient-opacity ramp.
const uint SHADE_RAMP = 2u;
const uint MODE_COMPOSITE = 0u;
const uint MODE_MIP = 1u;
const uint MODE_MINIP = 2u;
const uint MODE_AVERAGE = 3u;
const uint MODE_ISO = 4u;

// Counting frames (src/accel/probe.rs): with MARCH_COUNT set, a kernel
// writes per pixel what its SIMD group ran instead of the colour: x the
// iterations of the sample loop, y of the traversal loop (walk, DDA or tree
// steps), z the regions entered (march_region), each counted once per
// group iteration by one elected lane (so a group's sum over its lanes is
// what the group ran, its slowest lane included), and w the ray's own
// samples. auto prices its candidates from these counts. A second half of
// the frame buffer, after the image's pixels, takes what naive would have
// run on each pixel's ray (march.glsl `count_naive`).
layout(constant_id = 22) const uint MARCH_COUNT = 0u;
uvec3 count_group = uvec3(0u);
uint count_lane_samples = 0u;
#define COUNT_SAMPLE 0
#define COUNT_STEP 1
#define COUNT_REGION 2
void count_iteration(int what) {
    if (MARCH_COUNT != 0u) {
        if (what == COUNT_SAMPLE) {
            count_lane_samples += 1u;
        }
        if (subgroupElect()) {
            count_group[what] += 1u;
        }
    }
}

struct March {
    Ray ray;
    float t_enter; // entry into the volume box (0 when the eye is inside)
    float t_exit;  // exit from the volume box
    float t_last;  // where the whole ray ends: its last sample's weight reaches here
    float dt;
    int k;         // next lattice index to sample
    int k_end;     // the first lattice index at or past t_exit
    bool done;     // past t_exit, or terminated early (or the last sample due)
    bool last_due; // the ray's last sample is left for march_finish
    vec4 acc;      // premultiplied RGBA, front to back
    // Per-frame values the samples use, read from the parameters once per
    // ray rather than once per sample.
    VolumeRay vr;
    float ert;     // early-termination alpha
    uint tf_n;     // LUT entries per table
    Lighting lt;   // shaded and iso frames
    vec4 iso;      // iso values, read once per ray (iso)
    uint iso_n;
    vec4 bracket;  // t0, v0, t1, v1 of the samples an iso value lies between
    float jitter;  // the pixel's lattice offset in steps, [0, 1) (0 without jitter)
    // Mode state: the extreme so far (mip, minip); the sum and count of
    // samples (average); the previous sample's value, whether it is the
    // sample just before k, and the surface hit (iso).
    float best;
    float sum;
    float count;
    float prev;
    bool has_prev;
    bool hit;
    float hit_t;
    float hit_v;
    // Several channels (VOLUME_CHANNELS > 1): entries between channels'
    // tables (0: one for all), and per channel the extreme, sum and count.
    uint tf_stride;
    vec4 best4;
    vec4 sum4;
    vec4 count4;
};

// Bisection steps refining an iso crossing: the step over 2^16.
const int ISO_BISECTIONS = 16;

float lattice_t(March m, int k) {
    // (k + 0) is k exactly: without jitter this is t_enter + k dt.
    precise float t = m.t_enter + (float(k) + m.jitter) * m.dt;
    return t;
}

// The first lattice index at or past t, no lower than m.k. t_k never
// decreases with k, so every k below it has t_k < t: loops can count
// indices instead of comparing each sample's t.
int lattice_index(March m, float t) {
    int k = max(m.k, int(ceil((t - m.t_enter) / m.dt - m.jitter)));
    // ceil of a rounded quotient can be one off either way: fix it on t_k itself.
    while (k > m.k && lattice_t(m, k - 1) >= t) {
        k -= 1;
    }
    while (lattice_t(m, k) < t) {
        k += 1;
    }
    return k;
}

// Stops the march at t_exit, its last sample weighted as before: a
// segment's end (march_pixel), not the ray's.
void march_set_stop(inout March m, float t_exit) {
    m.t_exit = t_exit;
    m.done = !(m.t_enter < m.t_exit);
    m.k_end = m.done ? 0 : lattice_index(m, m.t_exit);
}

// Ends the ray at t_exit (no later than the box exit).
void march_set_exit(inout March m, float t_exit) {
    march_set_stop(m, t_exit);
    m.t_last = t_exit;
}

// Sets up the march for a ray; false when the ray misses the volume box.
bool march_begin(Ray ray, float dt, out March m) {
    vec2 hit = intersect_box(ray, vec3(0.0), vec3(params.dims));
    m.ray = ray;
    m.t_enter = max(hit.x, 0.0);
    m.dt = dt;
    m.k = 0;
    m.acc = vec4(0.0);
    m.vr = volume_ray(ray.org, ray.dir);
    m.ert = params.ert;
    m.tf_n = params.lut_size;
    if (MARCH_SHADE != 0u || MARCH_MODE == MODE_ISO) {
        m.lt = lighting_for(ray.dir);
    }
    if (MARCH_MODE == MODE_ISO) {
        m.iso = params.iso;
        m.iso_n = params.iso_count;
    }
    m.jitter = 0.0;
    m.best = MARCH_MODE == MODE_MINIP ? 2.0 : -1.0;
    m.sum = 0.0;
    m.count = 0.0;
    m.prev = 0.0;
    m.has_prev = false;
    m.hit = false;
    m.last_due = false;
    m.hit_t = 0.0;
    m.hit_v = 0.0;
    m.bracket = vec4(0.0);
    if (VOLUME_CHANNELS > 1u) {
        m.tf_stride = params.tf_channel_step * 2u * m.tf_n;
        m.best4 = vec4(m.best);
        m.sum4 = vec4(0.0);
        m.count4 = vec4(0.0);
    }
    march_set_exit(m, hit.y);
    return !m.done;
}

// A fixed per-pixel fraction in [0, 1) (PCG hash of the pixel), the same on
// every device and in src/render/reference/mod.rs.
float pixel_jitter(uvec2 px) {
    uint h = px.x * 747796405u + px.y * 2891336453u + 277803737u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = (h >> 22u) ^ h;
    return float(h >> 8u) * (1.0 / 16777216.0);
}

// The part of the ray the clip planes and crop box keep: (lo, hi) in t.
vec2 clip_interval(Ray r) {
    vec2 keep = vec2(-3.4e38, 3.4e38);
    for (uint i = 0u; i < params.clip_count; ++i) {
        vec4 c = params.clip[i];
        precise float at = dot(c.xyz, r.org) + c.w;
        precise float along = dot(c.xyz, r.dir);
        if (along == 0.0) {
            if (!(at >= 0.0)) {
                keep = vec2(1.0, -1.0);
            }
        } else {
            precise float t = -at / along;
            if (along > 0.0) {
                keep.x = max(keep.x, t);
            } else {
                keep.y = min(keep.y, t);
            }
        }
    }
    if (params.crop != 0u) {
        vec2 box = intersect_box(r, params.crop_lo, params.crop_hi);
        keep = vec2(max(keep.x, box.x), min(keep.y, box.y));
    }
    return keep;
}

// The part of the ray inside the rank's block (params.segment_lo/hi). A ray
// lying in a face two blocks share belongs to the block above the face only
// (intersect_box keeps it in both), so no sample is taken twice.
vec2 segment_interval(Ray r) {
    for (int a = 0; a < 3; ++a) {
        if (r.dir[a] == 0.0 && r.org[a] == params.segment_hi[a] && params.segment_hi[a] < float(params.dims[a])) {
            return vec2(1.0, -1.0);
        }
    }
    return intersect_box(r, params.segment_lo, params.segment_hi);
}

// Advances k to the first lattice point at or past t (never backwards).
void march_skip_to(inout March m, float t) {
    if (m.done) {
        return;
    }
    if (!(t < m.t_exit)) {
        m.done = true;
        return;
    }
    int k = lattice_index(m, t);
    // A skip leaves no previous sample to pair with (iso).
    m.has_prev = m.has_prev && k == m.k;
    m.k = k;
    if (m.k >= m.k_end) {
        m.done = true;
    }
}

// What a frame's rays may do beyond the plain march (src/desc/kernel.rs
// `cuts_constant`): CUT_* bits, all by default. The cuts of a ray's
// interval (jitter, a host depth image, clip planes or crop, a rank's
// segment) and the depth a ray writes. A constant, not only the
// parameters' flags: lavapipe runs every side of an `if`, and a frame with
// none of them ran their code (the lattice indices of the cut ends, the
// clip planes' loop, a depth through a matrix) for every ray: about 4 %
// of ch2's unshaded octant-map frame, 20-40 % of nbody:256's sparse one
// (docs/results/samples.md, docs/results/series-host/README.md).
layout(constant_id = 30) const uint MARCH_CUTS = 31u;
const uint CUT_JITTER = 1u;
const uint CUT_DEPTH = 2u;
const uint CUT_CLIP = 4u;
const uint CUT_SEGMENT = 8u;
const uint CUT_DEPTH_OUT = 16u;

// Sets up pixel px's march along its camera ray (camera.glsl), ending at
// the host's opaque surface when the frame has a depth limit. The limit only
// shortens t_exit: the lattice stays t_enter + k * dt, so every structure
// still takes exactly naive's samples.
bool march_pixel(uvec2 px, out March m) {
    bool hit = march_begin(camera_ray(px), params.step, m);
    if ((MARCH_CUTS & CUT_JITTER) != 0u && hit && params.jitter != 0u) {
        m.jitter = pixel_jitter(px);
        march_set_exit(m, m.t_exit);
    }
    if ((MARCH_CUTS & CUT_DEPTH) != 0u && hit && params.depth_limits != 0u) {
        march_set_exit(m, min(m.t_exit, params.t_max[px.y * params.image.x + px.x]));
    }
    // Clip planes and the crop box cut the ray's interval; the lattice
    // keeps its origin at the box entry.
    if ((MARCH_CUTS & CUT_CLIP) != 0u && hit && (params.clip_count != 0u || params.crop != 0u)) {
        vec2 keep = clip_interval(m.ray);
        march_set_exit(m, min(m.t_exit, keep.y));
        march_skip_to(m, keep.x);
    }
    // A data-parallel rank's part of the ray (src/parallel): the lattice
    // samples inside its block, each weighted as the whole ray weights it,
    // so the blocks' parts blended front to back are the whole ray.
    if ((MARCH_CUTS & CUT_SEGMENT) != 0u && hit && !m.done && params.segment != 0u) {
        int whole_first = m.k;
        vec2 part = segment_interval(m.ray);
        march_set_stop(m, min(m.t_exit, part.y));
        march_skip_to(m, part.x);
        // An iso segment pairs its first sample with the whole ray's sample
        // before it (in the ghost bricks, within one step of the block), as
        // one march would: a crossing between two blocks' samples is found
        // by the later block only.
        if (MARCH_MODE == MODE_ISO && !m.done && m.k > whole_first) {
            float v = sample_volume(m.vr, lattice_t(m, m.k - 1));
            m.prev = v;
            m.has_prev = !(VOLUME_NAN != 0u && is_nan(v));
        }
    }
    return !m.done;
}

// Composites one sample whose alpha is its opacity over its path length.
void composite(inout March m, vec4 c) {
    if (c.a > 0.0) {
        precise float a = min(c.a, 1.0);
        precise float transmit = 1.0 - m.acc.a;
        m.acc.rgb += transmit * a * c.rgb;
        m.acc.a += transmit * a;
    }
}

// The sample at value v standing for w voxels of path: full-length samples
// read the LUT corrected for dt; only a ray's shortened last sample (w < dt)
// corrects its interpolated raw alpha with a pow.
vec4 shade(March m, float v, float w) {
    if (w < m.dt) {
        vec4 c = tf_lookup(v, m.tf_n, m.tf_n);
        return vec4(c.rgb, opacity(c.a, w));
    }
    return tf_lookup(v, 0u, m.tf_n);
}

// The sample colour at value v standing for w voxels of path, lit when the
// frame is shaded (p: the sample's point in the filter's coordinates).
vec4 composite_sample(March m, float v, float w, vec3 p, bool full) {
    vec4 c = full ? tf_lookup(v, 0u, m.tf_n) : shade(m, v, w);
    if (MARCH_SHADE != 0u && c.a > 0.0) {
        c = light_sample(m.vr, m.lt, p, c, MARCH_SHADE == SHADE_RAMP);
    }
    return c;
}

// Whether an iso value lies between the lattice samples' values v0 and v1:
// then the march ends there, and iso_refine finds the crossing after the
// loop (bisection inside the march loop made lavapipe's whole loop 18x
// slower, taken or not).
void iso_bracket(inout March m, float t0, float v0, float t1, float v1) {
    for (uint i = 0u; i < m.iso_n; ++i) {
        float iso = m.iso[i];
        if ((v0 < iso) != (v1 < iso)) {
            m.hit = true;
            m.bracket = vec4(t0, v0, t1, v1);
            m.done = true;
            return;
        }
    }
}

// The first crossing of an iso value in the bracket the march ended at,
// refined by bisection on the trilinear field along the ray: the smallest
// crossing's t and value.
void iso_refine(inout March m) {
    if (!m.hit) {
        return;
    }
    float best_t = 3.4e38;
    float best_v = 0.0;
    for (uint i = 0u; i < m.iso_n; ++i) {
        float iso = m.iso[i];
        bool below = m.bracket.y < iso;
        if (below == (m.bracket.w < iso)) {
            continue;
        }
        float a = m.bracket.x;
        float b = m.bracket.z;
        for (int it = 0; it < ISO_BISECTIONS; ++it) {
            precise float mid = 0.5 * (a + b);
            if ((sample_volume(m.vr, mid) < iso) == below) {
                a = mid;
            } else {
                b = mid;
            }
        }
        precise float t = 0.5 * (a + b);
        if (t < best_t) {
            best_t = t;
            best_v = iso;
        }
    }
    m.hit_t = best_t;
    m.hit_v = best_v;
}

// Channels mix as densities (README, "Channels"): opacity
// 1 - prod(1 - a_c), the colour each channel's weighted by its opacity a_c.
// A channel of opacity 0 adds nothing, and where one channel alone shows,
// the mix is that channel's colour and opacity bit for bit.
vec4 mix_channels(vec4 col[4]) {
    precise float keep = 1.0;
    precise vec3 sum = vec3(0.0);
    precise float weight = 0.0;
    uint shown = 0u;
    vec4 only = vec4(0.0);
    for (uint c = 0u; c < VOLUME_CHANNELS; ++c) {
        float a = min(col[c].a, 1.0);
        if (a > 0.0) {
            shown += 1u;
            only = col[c];
            keep = keep * (1.0 - a);
            sum = sum + a * col[c].rgb;
            weight = weight + a;
        }
    }
    if (shown <= 1u) {
        return only;
    }
    precise vec3 rgb = sum / weight;
    return vec4(rgb, 1.0 - keep);
}

// Channel table `base`'s colour at v standing for w voxels (as shade).
vec4 channel_shade(March m, uint base, float v, float w, bool full) {
    if (!full && w < m.dt) {
        vec4 c = tf_lookup(v, base + m.tf_n, m.tf_n);
        return vec4(c.rgb, opacity(c.a, w));
    }
    return tf_lookup(v, base, m.tf_n);
}

// take_sample for several channels: composite mixes the channels' colours;
// mip, minip and average keep an extreme, sum and count per channel.
void take_channels(inout March m, float t, float w, bool full) {
    vec4 v = sample_channels(m.vr, t);
    if (MARCH_MODE == MODE_COMPOSITE) {
        vec4 col[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
        for (uint c = 0u; c < VOLUME_CHANNELS; ++c) {
            if (!(VOLUME_NAN != 0u && is_nan(v[c]))) {
                col[c] = channel_shade(m, c * m.tf_stride, v[c], w, full);
            }
        }
        composite(m, mix_channels(col));
        return;
    }
    bool all_done = true;
    for (uint c = 0u; c < VOLUME_CHANNELS; ++c) {
        if (VOLUME_NAN != 0u && is_nan(v[c])) {
            all_done = all_done && (MARCH_MODE == MODE_MIP ? m.best4[c] >= 1.0 : m.best4[c] <= 0.0);
            continue;
        }
        if (MARCH_MODE == MODE_MIP) {
            m.best4[c] = max(m.best4[c], v[c]);
            all_done = all_done && m.best4[c] >= 1.0;
        } else if (MARCH_MODE == MODE_MINIP) {
            m.best4[c] = min(m.best4[c], v[c]);
            all_done = all_done && m.best4[c] <= 0.0;
        } else if (MARCH_MODE == MODE_AVERAGE) {
            m.sum4[c] += v[c];
            m.count4[c] += 1.0;
        }
    }
    if (MARCH_MODE == MODE_MIP || MARCH_MODE == MODE_MINIP) {
        m.done = all_done;
    }
}

// Takes the sample at t (value v) standing for w voxels; `full`: w == dt.
void take_sample(inout March m, float t, float w, bool full) {
    if (VOLUME_CHANNELS > 1u) {
        take_channels(m, t, w, full);
        return;
    }
    float v = sample_volume(m.vr, t);
    if (VOLUME_NAN != 0u && is_nan(v)) {
        m.has_prev = false;
        return;
    }
    if (MARCH_MODE == MODE_COMPOSITE) {
        precise vec3 p = m.vr.org + t * m.vr.dir;
        composite(m, composite_sample(m, v, w, p, full));
    } else if (MARCH_MODE == MODE_MIP) {
        m.best = max(m.best, v);
        // Nothing exceeds 1: the rest of the ray cannot change the result.
        m.done = m.best >= 1.0;
    } else if (MARCH_MODE == MODE_MINIP) {
        m.best = min(m.best, v);
        m.done = m.best <= 0.0;
    } else if (MARCH_MODE == MODE_AVERAGE) {
        m.sum += v;
        m.count += 1.0;
    } else {
        if (m.has_prev) {
            iso_bracket(m, lattice_t(m, m.k - 1), m.prev, t, v);
        }
        m.prev = v;
        m.has_prev = true;
    }
}

// Takes lattice sample k, which is not the ray's last (k + 1 < k_end), and
// moves to k + 1; ends the march on early termination. Each sample stands
// for [t_k, t_k + dt): all but the last have the full length, so they read
// the corrected LUT with no branch (a CPU SIMD lane runs both sides of one).
void march_full_sample(inout March m) {
    count_iteration(COUNT_SAMPLE);
    float t = lattice_t(m, m.k);
    take_sample(m, t, m.dt, true);
    m.k += 1;
    if (MARCH_MODE == MODE_COMPOSITE) {
        m.done = m.acc.a >= m.ert;
    }
}

// Lit composite frames of one channel light only visible samples, per
// SIMD group: the group takes full samples in a loop of their own, each lane
// moving past its transparent ones, until some lane holds a visible one;
// then the group lights and composites (the lanes whose sample is visible).
// A GPU skips the lighting of an `if (c.a > 0)` that no lane of a group
// takes; lavapipe runs every `if` for every lane, so lighting a transparent
// sample cost what lighting a visible one does, and only a loop's exit
// skips code there (ch2 lit, octant map: about 2x the unlit frame before,
// 1.2 to 1.4x after; README, "What a sample costs on a CPU device"). The
// samples, their order and their arithmetic are march_full_sample's.
const bool LIT_RUNS = MARCH_MODE == MODE_COMPOSITE && MARCH_SHADE != 0u && VOLUME_CHANNELS == 1u;

void march_lit_run(inout March m, int full) {
    bool visible = false;
    float t = 0.0;
    vec4 c = vec4(0.0);
    while (true) {
        count_iteration(COUNT_SAMPLE);
        t = lattice_t(m, m.k);
        float v = sample_volume(m.vr, t);
        c = tf_lookup(v, 0u, m.tf_n);
        visible = c.a > 0.0 && !(VOLUME_NAN != 0u && is_nan(v));
        // Every lane still in the loop leaves with the group's first visible
        // sample; a lane past its full samples leaves alone.
        bool any_visible = subgroupAny(visible);
        if (!visible) {
            m.k += 1;
        }
        if (any_visible || m.k >= full) {
            break;
        }
    }
    // After the loop lavapipe reads t, c and visible as the group's last
    // iteration computed them, also for a lane that left before (its k at
    // `full`): only a lane whose k is still inside the span holds its own.
    if (visible && m.k < full) {
        precise vec3 p = m.vr.org + t * m.vr.dir;
        composite(m, light_sample(m.vr, m.lt, p, c, MARCH_SHADE == SHADE_RAMP));
        m.k += 1;
        m.done = m.acc.a >= m.ert;
    }
}

// Takes the march's last sample (k = k_end - 1), weighted by its length up
// to the ray's end (a full step where only a segment ends), and ends the march.
void march_last_sample(inout March m) {
    count_iteration(COUNT_SAMPLE);
    float t = lattice_t(m, m.k);
    precise float w = min(m.dt, m.t_last - t);
    take_sample(m, t, w, false);
    m.k += 1;
    m.done = true;
}

// The pixel's premultiplied RGBA once the march ended.
vec4 march_result(March m) {
    if (MARCH_MODE == MODE_COMPOSITE) {
        return m.acc;
    }
    if (MARCH_MODE == MODE_ISO) {
        if (!m.hit) {
            return vec4(0.0);
        }
        // Opaque, in the iso colour or the TF's colour at the value, lit.
        vec3 rgb = params.iso_colored != 0u ? params.iso_color : tf_lookup(m.hit_v, m.tf_n, m.tf_n).rgb;
        precise vec3 p = m.vr.org + m.hit_t * m.vr.dir;
        return vec4(light_sample(m.vr, m.lt, p, vec4(rgb, 1.0), false).rgb, 1.0);
    }
    if (VOLUME_CHANNELS > 1u) {
        // Each channel's value through its raw table, mixed, premultiplied.
        vec4 col[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
        for (uint c = 0u; c < VOLUME_CHANNELS; ++c) {
            float x = m.best4[c];
            if (MARCH_MODE == MODE_AVERAGE) {
                precise float mean = m.sum4[c] / m.count4[c];
                x = m.count4[c] == 0.0 ? -1.0 : mean;
            }
            if (x >= 0.0 && x <= 1.0) {
                col[c] = tf_lookup(x, c * m.tf_stride + m.tf_n, m.tf_n);
            }
        }
        vec4 mixed = mix_channels(col);
        return vec4(mixed.rgb * mixed.a, mixed.a);
    }
    float v = m.best;
    if (MARCH_MODE == MODE_AVERAGE) {
        if (m.count == 0.0) {
            return vec4(0.0);
        }
        precise float mean = m.sum / m.count;
        v = mean;
    } else if (v < 0.0 || v > 1.0) {
        // No sample (a missed or fully clipped ray, or only no-data samples).
        return vec4(0.0);
    }
    // One value through the raw LUT: its colour and opacity, premultiplied.
    vec4 c = tf_lookup(v, m.tf_n, m.tf_n);
    return vec4(c.rgb * c.a, c.a);
}

// An iso frame's depth at the surface hit (render_params.glsl, depth_out).
float march_depth(March m) {
    if (params.depth_out == 3u) {
        // A ray value at or past value_bound maps to transparent, and
        // structures skip regions of only such values: it is written as no
        // sample, so every structure writes naive's value bit for bit.
        bool minip = MARCH_MODE == MODE_MINIP;
        bool shows = minip ? m.best < params.value_bound : m.best > params.value_bound;
        return shows ? m.best : (minip ? 2.0 : -1.0);
    }
    if (!m.hit) {
        return params.no_hit_depth;
    }
    precise vec3 p = m.ray.org + m.hit_t * m.ray.dir;
    if (params.depth_out == 1u) {
        precise vec4 q = params.voxel_to_ndc * vec4(p, 1.0);
        return q.z / q.w;
    }
    return length((p - m.ray.org) * params.spacing);
}

// Marches the samples k < stop (stop <= k_end), front to back: the full
// ones in a loop of their own; where the span reaches the ray's last one,
// it is left due (march_finish takes it) and the march ends.
void march_until(inout March m, int stop) {
    int full = min(stop, m.k_end - 1);
    // One loop or the other (a constant): lavapipe runs a loop's body once
    // even when no lane enters it.
    if (LIT_RUNS) {
        while (!m.done && m.k < full) {
            march_lit_run(m, full);
        }
    } else {
        while (!m.done && m.k < full) {
            march_full_sample(m);
        }
    }
    // The ray's last sample (k = k_end - 1) is taken once, after the
    // traversal (march_finish): taken here, its code ran, masked, for every
    // region of every ray, as lavapipe runs every `if`.
    if (!m.done && m.k < stop) {
        m.last_due = true;
        m.done = true;
    }
}

// After march_ray (main): the last sample a span left due, which nothing
// follows.
void march_finish(inout March m) {
    if (m.last_due) {
        m.last_due = false;
        march_last_sample(m);
    }
}

// Marches every remaining sample of the ray (the last one left due).
void march_rest(inout March m) {
    march_until(m, m.k_end);
}

// Marches every lattice sample with t_k < t_end (and < t_exit), front to
// back (the ray's last one left due).
void march_span(inout March m, float t_end) {
    if (m.done) {
        return;
    }
    // A NaN end marches nothing.
    int stop = t_end < m.t_exit ? lattice_index(m, t_end) : (t_end >= m.t_exit ? m.k_end : m.k);
    march_until(m, stop);
}

// Conservative margin (voxels) by which region boxes grow before their spans
// are marched: covers the rounding of t and of sample positions, so a sample
// naive marching takes inside an active region is never skipped. Taking an
// extra sample is harmless: it is naive's sample, with naive's value.
float region_margin(March m) {
    vec3 o = abs(m.ray.org);
    float scale = max(max(o.x, o.y), o.z) + abs(m.t_exit) + float(max(max(params.dims.x, params.dims.y), params.dims.z));
    return 1.0 / 4096.0 + scale * (1.0 / 262144.0);
}

// The span of box [lo, hi] (grown by eps) along the ray, clipped to the volume.
vec2 region_span(March m, vec3 lo, vec3 hi, float eps) {
    vec2 h = intersect_box(m.ray, lo - eps, hi + eps);
    return vec2(max(h.x, m.t_enter), min(h.y, m.t_exit));
}

// Regions that follow one another along a ray make one run, marched as one
// span (the distance maps' boxes, the grid's cells); a run ends at a region
// that is empty or whose span is, or once it is RUN_CELLS cells of ray long
// (the region that reaches the cap is the run's last). A SIMD group's sample
// loop runs for the longest of its lanes' spans, so where neighbouring rays'
// regions split a run at different places the group paid for every split:
// on lavapipe menger:243's and ch2's octant-map frames took 1.13 to 1.27x
// as long without runs, the grid's 1.3 to 1.5x. Walking on past where early
// termination ends a ray costs steps, hence the cap (docs/results/samples.md,
// "Runs of active regions"). Merging is exact: a run spans from its first
// region's entry to the furthest exit of its regions (a box ahead can end
// before a longer one behind it, grown by the margin), so it covers each
// region's span and the rounding gaps between them, and a sample taken
// there is naive's own.
const float RUN_CELLS = 4.0;

// Adds a region to `run` (`found`: the run has one): `joins` when the
// region is active and its span (`span`) nonempty. Returns whether the run
// is over: at a region that does not join, or once the run is `cap` long.
bool run_add(inout vec2 run, inout bool found, bool joins, vec2 span, float cap) {
    if (joins) {
        run = found ? vec2(run.x, max(run.y, span.y)) : span;
        found = true;
    }
    return found && (!joins || run.y - run.x >= cap);
}

// Marches the lattice samples of a region's span. Regions must come front to
// back; k never moves backwards, so overlapping spans take no sample twice.
void march_region(inout March m, vec2 span) {
    if (span.x < span.y) {
        count_iteration(COUNT_REGION);
        if (MARCH_MODE == MODE_ISO) {
            // Iso tests pairs of consecutive samples: a pair that straddles
            // the region's entry or exit is the region's too. Pairs wholly
            // outside active regions cross nothing (docs/structures.md,
            // "Classification under each look").
            span = vec2(span.x - m.dt, span.y + m.dt);
        }
        march_skip_to(m, span.x);
        march_span(m, span.y);
    }
}

#endif
