// The volume pass's transfer function (issue "isosurfaces and volume rendering"): its buffer
// — point count, unit distance D, background colour, padding; then (value, opacity) per point
// (TransferFunction::device_words) — at binding SPECTRAL_TRANSFER_BINDING of set 0, and the
// opacity ramp α(f) with its extinction σ(f). Twin of src/spectral/transfer.rs
// (TransferFunction::alpha, sigma), tested to agree by tests/includes_agree.rs.
#ifndef GALERKIN_SPECTRAL_TRANSFER_GLSL
#define GALERKIN_SPECTRAL_TRANSFER_GLSL

#ifndef SPECTRAL_TRANSFER_BINDING
#error "define SPECTRAL_TRANSFER_BINDING before including spectral_transfer.glsl"
#endif

layout(std430, set = 0, binding = SPECTRAL_TRANSFER_BINDING) readonly buffer Transfer {
    uint tf_count;
    float tf_unit;
    float tf_background[3];
    uint tf_pad[3];
    vec2 tf_points[];
};

// The largest opacity in σ = −ln(1 − α)/D (transfer.rs, MAX_OPACITY).
#define SPECTRAL_VOLUME_MAX_OPACITY (1.0 - 1.0 / 1048576.0)

// α(f): linear between the points, constant beyond (TransferFunction::alpha).
float volume_alpha(float f) {
    uint n = min(tf_count, 64u);
    if (f <= tf_points[0].x) return tf_points[0].y;
    for (uint k = 1u; k < n; ++k) {
        vec2 a = tf_points[k - 1u], b = tf_points[k];
        if (f <= b.x) return a.y + (f - a.x) / (b.x - a.x) * (b.y - a.y);
    }
    return tf_points[n - 1u].y;
}

// σ(f) = −ln(1 − α(f))/D (TransferFunction::sigma).
float volume_sigma(float f) {
    return -log(1.0 - min(volume_alpha(f), SPECTRAL_VOLUME_MAX_OPACITY)) / tf_unit;
}
#endif
