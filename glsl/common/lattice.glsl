// The global sample lattice (DESIGN invariant 1) and the one span-marching
// function every march kernel uses. Sample k sits at t_k = t_enter + k * dt,
// always computed from k; skipping moves k, never accumulates dt.
// Needs ray.glsl, volume.glsl and tf.glsl.
#ifndef LACUNA_LATTICE_GLSL
#define LACUNA_LATTICE_GLSL

#include "opacity.glsl"

struct March {
    Ray ray;
    float t_enter; // entry into the volume box (0 when the eye is inside)
    float t_exit;  // exit from the volume box
    float dt;
    int k;         // next lattice index to sample
    int k_end;     // the first lattice index at or past t_exit
    bool done;     // past t_exit, or terminated early
    vec4 acc;      // premultiplied RGBA, front to back
    // Per-frame values the samples use, read from the parameters once per
    // ray rather than once per sample.
    VolumeRay vr;
    float ert;     // early-termination alpha
    uint tf_n;     // LUT entries per table
};

float lattice_t(March m, int k) {
    precise float t = m.t_enter + float(k) * m.dt;
    return t;
}

// The first lattice index at or past t, no lower than m.k. t_k never
// decreases with k, so every k below it has t_k < t: loops can count
// indices instead of comparing each sample's t.
int lattice_index(March m, float t) {
    int k = max(m.k, int(ceil((t - m.t_enter) / m.dt)));
    // ceil of a rounded quotient can be one off either way: fix it on t_k itself.
    while (k > m.k && lattice_t(m, k - 1) >= t) {
        k -= 1;
    }
    while (lattice_t(m, k) < t) {
        k += 1;
    }
    return k;
}

// Ends the march at t_exit (no later than the box exit).
void march_set_exit(inout March m, float t_exit) {
    m.t_exit = t_exit;
    m.done = !(m.t_enter < m.t_exit);
    m.k_end = m.done ? 0 : lattice_index(m, m.t_exit);
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
    march_set_exit(m, hit.y);
    return !m.done;
}

// Sets up pixel px's march along its camera ray (camera.glsl), ending at
// the host's opaque surface when the frame has a depth limit. The limit only
// shortens t_exit: the lattice stays t_enter + k * dt, so every structure
// still takes exactly naive's samples.
bool march_pixel(uvec2 px, out March m) {
    bool hit = march_begin(camera_ray(px), params.step, m);
    if (hit && params.depth_limits != 0u) {
        march_set_exit(m, min(m.t_exit, params.t_max[px.y * params.image.x + px.x]));
    }
    return !m.done;
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
    m.k = lattice_index(m, t);
    if (m.k >= m.k_end) {
        m.done = true;
    }
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

// Takes lattice sample k, which is not the ray's last (k + 1 < k_end), and
// moves to k + 1; ends the march on early termination. Each sample stands
// for [t_k, t_k + dt): all but the last have the full length, so they read
// the corrected LUT with no branch (a CPU SIMD lane runs both sides of one).
void march_full_sample(inout March m) {
    float t = lattice_t(m, m.k);
    composite(m, tf_lookup(sample_volume(m.vr, t), 0u, m.tf_n));
    m.k += 1;
    m.done = m.acc.a >= m.ert;
}

// Takes the ray's last sample (k = k_end - 1), weighted by its length up to
// the box exit, and ends the march.
void march_last_sample(inout March m) {
    float t = lattice_t(m, m.k);
    precise float w = min(m.dt, m.t_exit - t);
    composite(m, shade(m, sample_volume(m.vr, t), w));
    m.k += 1;
    m.done = true;
}

// Marches the samples k < stop (stop <= k_end), front to back: the full
// ones in a loop of their own, then the last one if the span reaches it.
void march_until(inout March m, int stop) {
    int full = min(stop, m.k_end - 1);
    while (!m.done && m.k < full) {
        march_full_sample(m);
    }
    if (!m.done && m.k < stop) {
        march_last_sample(m);
    }
}

// Marches every remaining sample of the ray.
void march_rest(inout March m) {
    march_until(m, m.k_end);
}

// Marches every lattice sample with t_k < t_end (and < t_exit), front to back.
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

// Marches the lattice samples of a region's span. Regions must come front to
// back; k never moves backwards, so overlapping spans take no sample twice.
void march_region(inout March m, vec2 span) {
    if (span.x < span.y) {
        march_skip_to(m, span.x);
        march_span(m, span.y);
    }
}

#endif
