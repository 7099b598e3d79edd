// Max alpha of the transfer function over a value range, from the sparse
// table built by src/tf.rs (level k holds the max over entries i .. i + 2^k - 1,
// stored at k * TF_SIZE + i). The entry range is widened by one on each side
// (DESIGN invariant 2), matching TransferFunction::max_alpha.
#ifndef LACUNA_TF_RANGE_GLSL
#define LACUNA_TF_RANGE_GLSL

layout(std430, set = 0, binding = TF_MAX_BINDING) readonly buffer TransferMax {
    float tf_max[];
};

// As tf_max_alpha, in the table at entry `base` (a channel's).
float tf_max_alpha_at(uint base, float lo, float hi) {
    if (lo > hi) {
        return 0.0;
    }
    uint n = TF_SIZE;
    float scale = float(n - 1u);
    int i = max(int(floor(clamp(lo, 0.0, 1.0) * scale)) - 1, 0);
    int j = min(int(ceil(clamp(hi, 0.0, 1.0) * scale)) + 1, int(n) - 1);
    uint len = uint(j - i + 1);
    uint k = uint(findMSB(len));
    return max(tf_max[base + k * n + uint(i)], tf_max[base + k * n + uint(j + 1) - (1u << k)]);
}

float tf_max_alpha(float lo, float hi) {
    return tf_max_alpha_at(0u, lo, hi);
}

#endif
