// Trilinear volume sampling with clamp-to-edge, by one of two filters chosen
// per kernel by a specialization constant (src/volume/filter.rs), so no
// sample branches on it:
// 0 (manual): by hand, in f32, so every device (and the CPU reference)
//   computes the same weights in full float precision. Integer volumes are
//   interpolated in their stored units (0..255, 0..65535) and scaled once.
//   The eight voxels come from the volume's cells copy when it has one
//   (VOLUME_CELLS: every cell's eight corner voxels in one texel, one fetch;
//   src/volume/cells.rs), else from eight texelFetch: the same values and
//   the same arithmetic, so the same sample bit for bit.
// 1 (hardware): the sampler's linear filtering (a linear sampler bound),
//   one fetch, weights of the device's subTexelPrecisionBits. Its weights are
//   still a convex combination of the same eight voxels, so the one-voxel
//   apron of the classification still covers every value it returns.
#ifndef LACUNA_VOLUME_GLSL
#define LACUNA_VOLUME_GLSL

#include "nan.glsl"

layout(set = 0, binding = VOLUME_BINDING) uniform sampler3D volume_tex;
layout(constant_id = 16) const uint VOLUME_FILTER = 0u;
// 1: the volume holds NaN voxels ("no data"; src/volume, README "NaN"). A
// sample any of whose eight voxels is NaN is NaN (IEEE arithmetic carries
// it through the interpolation), and NaN samples contribute nothing. Only
// the manual filter samples such volumes: hardware filtering of NaN is the
// device's to define.
layout(constant_id = 19) const uint VOLUME_NAN = 0u;
// How texels are stored (src/volume/cells.rs `CellsLayout`): 0 float32,
// 1 unorm8, 2 unorm16. The manual filter interpolates integer texels in
// their stored units.
layout(constant_id = 20) const uint VOLUME_KIND = 0u;
// 1: the manual filter reads the cells copy (CELLS_BINDING).
layout(constant_id = 21) const uint VOLUME_CELLS = 0u;
// Channels per texel, 1 to 4 (src/volume/channels.rs): with more than one,
// every channel sits in one texel of the widest kind among them, and the
// march samples them all at once (sample_channels).
layout(constant_id = 26) const uint VOLUME_CHANNELS = 1u;
// Bricked storage: bricks of this edge in the pool image bound as the
// volume, found through the brick table (bricks.glsl); 0: dense storage.
// Only the manual filter samples it (src/volume/pool.rs).
layout(constant_id = 27) const uint VOLUME_BRICK = 0u;
const uint KIND_FLOAT = 0u;
const uint KIND_UNORM8 = 1u;
const uint KIND_UNORM16 = 2u;

#ifdef BRICK_TABLE_BINDING
#include "bricks.glsl"
#endif
#ifdef CELLS_BINDING
// Cell (i, j, k) of the cells copy, i in -1..N-1 per axis, stored at
// (i + 1) + (W + 1) * ((j + 1) + (H + 1) * (k + 1)), holds the voxels
// clamp(i + dx, j + dy, k + dz) for dx, dy, dz in {0, 1}, x fastest: unorm8
// as the bytes of two words (one RG32UI texel), unorm16 as the halves of
// four (one RGBA32UI texel), float32 as the bits of eight (two RGBA32UI
// texels, z = k then k + 1).
layout(set = 0, binding = CELLS_BINDING) uniform usamplerBuffer volume_cells;
#endif
// What sampling along one ray needs, loaded once per ray: a storage-buffer
// read per sample is dear on lavapipe, and the hardware path's coordinates
// are then a multiply and an add per axis rather than also a division.
struct VolumeRay {
    vec3 org;  // the ray in the filter's coordinates: voxels (manual) or
    vec3 dir;  // normalised texture coordinates (hardware)
    vec3 unit; // one voxel along each axis in those coordinates
    ivec3 hi;  // the last voxel per axis
    vec2 norm; // v = (texel - norm.x) * norm.y
    vec4 lo;   // per channel (VOLUME_CHANNELS > 1): v = (texel - lo) * scale
    vec4 scale;
};

VolumeRay volume_ray(vec3 org, vec3 dir) {
    VolumeRay v;
    vec3 dims = vec3(params.dims);
    if (VOLUME_FILTER == 1u) {
        // The sampler's u * N - 0.5 puts voxel i's centre at i + 0.5, as the
        // manual path (3D images allow no unnormalised coordinates).
        precise vec3 o = org / dims;
        precise vec3 d = dir / dims;
        v.org = o;
        v.dir = d;
        v.unit = 1.0 / dims;
    } else {
        v.org = org;
        v.dir = dir;
        v.unit = vec3(1.0);
    }
    v.hi = ivec3(params.dims) - 1;
    v.norm = params.norm;
    if (VOLUME_CHANNELS > 1u) {
        v.lo = params.channel_lo;
        v.scale = params.channel_scale;
    }
    return v;
}

// The scale from stored units to the texel's value: 1 for float volumes.
float volume_unit() {
    return VOLUME_KIND == KIND_UNORM8 ? 255.0 : (VOLUME_KIND == KIND_UNORM16 ? 65535.0 : 1.0);
}

// Voxel i (clamped) in stored units: an integer-valued float for unorm
// volumes (the texel's value rounds back to its integer exactly).
float volume_texel(ivec3 i, ivec3 hi) {
    float t = texelFetch(volume_tex, clamp(i, ivec3(0), hi), 0).r;
    return VOLUME_KIND == KIND_FLOAT ? t : round(t * volume_unit());
}

// Every channel's voxel i (clamped) in stored units (VOLUME_CHANNELS > 1).
vec4 volume_texels(ivec3 i, ivec3 hi) {
    vec4 t = texelFetch(volume_tex, clamp(i, ivec3(0), hi), 0);
    return VOLUME_KIND == KIND_FLOAT ? t : round(t * volume_unit());
}

ivec3 cell_corner(int b) {
    return ivec3(b & 1, (b >> 1) & 1, (b >> 2) & 1);
}

#ifdef BRICK_TABLE_BINDING
// Every channel of the eight voxels of the cell whose low corner is voxel i
// (clamped), from the pool, in stored units, x fastest: each voxel's
// clamped index lies in the slot of the brick of the first, so one table
// read serves the cell.
void cell_pool_voxels(ivec3 i, ivec3 hi, out vec4 c[8]) {
    ivec3 lo = clamp(i, ivec3(0), hi);
    ivec4 t = brick_texel(lo, hi, int(VOLUME_BRICK));
    ivec3 step = (clamp(i + 1, ivec3(0), hi) - lo) * (t.w & 1);
    for (int b = 0; b < 8; ++b) {
        vec4 v = pool_fetch(t.w >> 1, t.xyz + step * cell_corner(b));
        c[b] = VOLUME_KIND == KIND_FLOAT ? v : round(v * volume_unit());
    }
}
#endif

// The eight voxels of the cell whose low corner is voxel i (clamped to the
// volume), in stored units, x fastest: [0] c000, [1] c100, ... [7] c111.
void cell_voxels(ivec3 i, ivec3 hi, out float c[8]) {
#ifdef BRICK_TABLE_BINDING
    if (VOLUME_BRICK != 0u) {
        vec4 t[8];
        cell_pool_voxels(i, hi, t);
        for (int b = 0; b < 8; ++b) {
            c[b] = t[b].r;
        }
        return;
    }
#endif
#ifdef CELLS_BINDING
    if (VOLUME_CELLS != 0u) {
        ivec3 n = hi + 2;
        ivec3 j = clamp(i + 1, ivec3(0), n - 1);
        int at = j.x + n.x * (j.y + n.y * j.z);
        if (VOLUME_KIND == KIND_UNORM8) {
            uvec2 w = texelFetch(volume_cells, at).xy;
            for (int b = 0; b < 4; ++b) {
                c[b] = float((w.x >> (8u * uint(b))) & 255u);
                c[4 + b] = float((w.y >> (8u * uint(b))) & 255u);
            }
        } else if (VOLUME_KIND == KIND_UNORM16) {
            uvec4 w = texelFetch(volume_cells, at);
            for (int b = 0; b < 4; ++b) {
                c[2 * b] = float(w[b] & 65535u);
                c[2 * b + 1] = float(w[b] >> 16u);
            }
        } else {
            uvec4 lo = texelFetch(volume_cells, 2 * at);
            uvec4 up = texelFetch(volume_cells, 2 * at + 1);
            for (int b = 0; b < 4; ++b) {
                c[b] = uintBitsToFloat(lo[b]);
                c[4 + b] = uintBitsToFloat(up[b]);
            }
        }
        return;
    }
#endif
    for (int b = 0; b < 8; ++b) {
        c[b] = volume_texel(i + cell_corner(b), hi);
    }
}

// The texel value at p, trilinearly interpolated by hand.
float sample_manual(vec3 p, ivec3 hi) {
    // `precise` everywhere on the sampling path: every kernel that inlines this
    // must round identically (no kernel-dependent FMA contraction).
    precise vec3 q = p - 0.5;
    vec3 fl = floor(q);
    precise vec3 f = q - fl;
    float c[8];
    cell_voxels(ivec3(fl), hi, c);
    precise float c00 = mix(c[0], c[1], f.x);
    precise float c10 = mix(c[2], c[3], f.x);
    precise float c01 = mix(c[4], c[5], f.x);
    precise float c11 = mix(c[6], c[7], f.x);
    precise float c0 = mix(c00, c10, f.y);
    precise float c1 = mix(c01, c11, f.y);
    precise float raw = mix(c0, c1, f.z);
    if (VOLUME_KIND != KIND_FLOAT) {
        raw = raw * (1.0 / volume_unit());
    }
    return raw;
}

// The stored texel value at p (the filter's coordinates).
float sample_raw(VolumeRay r, vec3 p) {
    precise float raw;
    if (VOLUME_FILTER == 1u) {
        raw = textureLod(volume_tex, p, 0.0).r;
    } else {
        raw = sample_manual(p, r.hi);
    }
    return raw;
}

// Every channel's texel value at p, trilinearly interpolated by hand with
// sample_manual's weights: eight fetches read every channel.
vec4 sample_manual_channels(vec3 p, ivec3 hi) {
    precise vec3 q = p - 0.5;
    vec3 fl = floor(q);
    precise vec3 f = q - fl;
    ivec3 i = ivec3(fl);
    vec4 c[8];
#ifdef BRICK_TABLE_BINDING
    if (VOLUME_BRICK != 0u) {
        cell_pool_voxels(i, hi, c);
    } else
#endif
    for (int b = 0; b < 8; ++b) {
        c[b] = volume_texels(i + cell_corner(b), hi);
    }
    precise vec4 c00 = mix(c[0], c[1], f.x);
    precise vec4 c10 = mix(c[2], c[3], f.x);
    precise vec4 c01 = mix(c[4], c[5], f.x);
    precise vec4 c11 = mix(c[6], c[7], f.x);
    precise vec4 c0 = mix(c00, c10, f.y);
    precise vec4 c1 = mix(c01, c11, f.y);
    precise vec4 raw = mix(c0, c1, f.z);
    if (VOLUME_KIND != KIND_FLOAT) {
        raw = raw * (1.0 / volume_unit());
    }
    return raw;
}

// Each channel's normalised value in [0, 1] at the ray's point t (NaN: no
// data in that channel; channels past VOLUME_CHANNELS read 0).
vec4 sample_channels(VolumeRay r, float t) {
    precise vec3 p = r.org + t * r.dir;
    precise vec4 raw;
    if (VOLUME_FILTER == 1u) {
        raw = textureLod(volume_tex, p, 0.0);
    } else {
        raw = sample_manual_channels(p, r.hi);
    }
    precise vec4 v = (raw - r.lo) * r.scale;
    for (int c = 0; c < 4; ++c) {
        if (!(VOLUME_NAN != 0u && is_nan(v[c]))) {
            v[c] = clamp(v[c], 0.0, 1.0);
        }
    }
    return v;
}

#ifdef GRADIENT_BINDING
// The volume's gradient (src/volume/gradient.rs): per voxel (x, y, z) in
// normalised value per voxel; bound for shaded and iso frames (the volume
// image stands in for it otherwise, and nothing reads it).
layout(set = 0, binding = GRADIENT_BINDING) uniform sampler3D gradient_tex;

// 1: the manual filter reads the gradient's cells copy (GRADIENT_CELLS_BINDING):
// per cell its eight corners' (x, y, z) halves, corner-major, two halves a
// word, in three RGBA32UI texels (src/volume/gradient_cells.rs).
layout(constant_id = 25) const uint GRADIENT_CELLS = 0u;
#ifdef GRADIENT_CELLS_BINDING
layout(set = 0, binding = GRADIENT_CELLS_BINDING) uniform usamplerBuffer gradient_cells;
#endif

// The gradients of the eight voxels of the cell whose low corner is voxel i
// (clamped), x fastest: from the gradient's cells copy in three fetches, or
// eight texelFetch: the same halves either way.
void cell_gradients(ivec3 i, ivec3 hi, out vec3 g[8]) {
#ifdef GRADIENT_CELLS_BINDING
    if (GRADIENT_CELLS != 0u) {
        ivec3 n = hi + 2;
        ivec3 j = clamp(i + 1, ivec3(0), n - 1);
        int at = 3 * (j.x + n.x * (j.y + n.y * j.z));
        uvec4 t0 = texelFetch(gradient_cells, at);
        uvec4 t1 = texelFetch(gradient_cells, at + 1);
        uvec4 t2 = texelFetch(gradient_cells, at + 2);
        uint w[12] = uint[12](t0.x, t0.y, t0.z, t0.w, t1.x, t1.y, t1.z, t1.w, t2.x, t2.y, t2.z, t2.w);
        for (int b = 0; b < 4; ++b) {
            // Corners 2b and 2b + 1: six halves in three words.
            vec2 h0 = unpackHalf2x16(w[3 * b]);
            vec2 h1 = unpackHalf2x16(w[3 * b + 1]);
            vec2 h2 = unpackHalf2x16(w[3 * b + 2]);
            g[2 * b] = vec3(h0.x, h0.y, h1.x);
            g[2 * b + 1] = vec3(h1.y, h2.x, h2.y);
        }
        return;
    }
#endif
    for (int b = 0; b < 8; ++b) {
        ivec3 c = i + ivec3(b & 1, (b >> 1) & 1, (b >> 2) & 1);
        g[b] = texelFetch(gradient_tex, clamp(c, ivec3(0), hi), 0).xyz;
    }
}

// The gradient at p (the filter's coordinates), in normalised value per
// voxel, by the volume's filter: interpolated by hand with the weights
// sample_manual uses, or by the sampler.
vec3 sample_gradient(VolumeRay r, vec3 p) {
    if (VOLUME_FILTER == 1u) {
        return textureLod(gradient_tex, p, 0.0).xyz;
    }
    precise vec3 q = p - 0.5;
    vec3 fl = floor(q);
    precise vec3 f = q - fl;
    vec3 c[8];
    cell_gradients(ivec3(fl), r.hi, c);
    precise vec3 c00 = mix(c[0], c[1], f.x);
    precise vec3 c10 = mix(c[2], c[3], f.x);
    precise vec3 c01 = mix(c[4], c[5], f.x);
    precise vec3 c11 = mix(c[6], c[7], f.x);
    precise vec3 c0 = mix(c00, c10, f.y);
    precise vec3 c1 = mix(c01, c11, f.y);
    precise vec3 g = mix(c0, c1, f.z);
    return g;
}
#endif

// Normalised value in [0, 1] at the ray's point t (NaN: no data).
float sample_volume(VolumeRay r, float t) {
    precise vec3 p = r.org + t * r.dir;
    precise float v = (sample_raw(r, p) - r.norm.x) * r.norm.y;
    if (VOLUME_NAN != 0u && is_nan(v)) {
        return v;
    }
    return clamp(v, 0.0, 1.0);
}

#endif
