// The volume pass's transfer function (issue "isosurfaces and volume rendering"): its buffer
// — point count, unit distance D, background colour, the isosurface sheets' count and opacity,
// whether the medium is clear; then (value, opacity) per point, then the sheets' iso values
// (TransferFunction::device_words) — at binding SPECTRAL_TRANSFER_BINDING of set 0, and the
// opacity ramp α(f) with its extinction σ(f). Twin of src/spectral/transfer.rs
// (TransferFunction::alpha, sigma), tested to agree by tests/includes_agree.rs.
#ifndef GALERKIN_SPECTRAL_TRANSFER_GLSL
#define GALERKIN_SPECTRAL_TRANSFER_GLSL

#ifndef SPECTRAL_TRANSFER_BINDING
#error "define SPECTRAL_TRANSFER_BINDING before including spectral_transfer.glsl"
#endif

// The most opacity points (transfer.rs, MAX_TRANSFER_POINTS) and sheets (MAX_ISO_VALUES).
#define SPECTRAL_TRANSFER_POINTS 64
#define SPECTRAL_TRANSFER_SHEETS 8

layout(std430, set = 0, binding = SPECTRAL_TRANSFER_BINDING) readonly buffer Transfer {
    uint tf_count;
    float tf_unit;
    float tf_background[3];
    // Isosurfaces composited inside the volume as sheets of opacity tf_sheet_alpha (volume.frag).
    uint tf_sheet_count;
    float tf_sheet_alpha;
    // 1 when every opacity is 0: a clear medium, only the sheets show.
    uint tf_clear;
    vec2 tf_points[SPECTRAL_TRANSFER_POINTS];
    float tf_sheets[SPECTRAL_TRANSFER_SHEETS];
};

// The largest opacity in σ = −ln(1 − α)/D (transfer.rs, MAX_OPACITY).
#define SPECTRAL_VOLUME_MAX_OPACITY (1.0 - 1.0 / 1048576.0)

// α(f): linear between the points, constant beyond (TransferFunction::alpha).
float volume_alpha(float f) {
    uint n = min(tf_count, uint(SPECTRAL_TRANSFER_POINTS));
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
