// Value → colour-ramp coordinate → texture coordinate.
// Twin of src/render/colormap.rs (ramp_coordinate, ramp_texcoord); tests check they agree.
#ifndef GALERKIN_COLORMAP_GLSL
#define GALERKIN_COLORMAP_GLSL

// Ramp coordinate of v over [lo, hi]: linear, or logarithmic when log_scale (values <= 0 map
// to 0), clamped to [0, 1].
float ramp_coordinate(float v, float lo, float hi, bool log_scale) {
    float t;
    if (log_scale) {
        t = (v <= 0.0 || lo <= 0.0 || hi <= lo) ? 0.0 : log(v / lo) / log(hi / lo);
    } else {
        t = (hi == lo) ? 0.0 : (v - lo) / (hi - lo);
    }
    return isnan(t) ? 0.0 : clamp(t, 0.0, 1.0);
}

// Texture coordinate on an n-texel ramp: t = 0 and 1 land on the first and last texel centres.
float ramp_texcoord(float t, float n) {
    return (t * (n - 1.0) + 0.5) / n;
}

#endif
