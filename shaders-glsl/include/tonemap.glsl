// Exposure tone mapping and sRGB encoding of radiance.
// Twin of src/render/tonemap.rs (tone_map, srgb_encode); the radiosity render test checks
// that they agree per pixel.
#ifndef GALERKIN_TONEMAP_GLSL
#define GALERKIN_TONEMAP_GLSL

// The sRGB transfer function of a linear value in [0, 1].
float srgb_encode(float c) {
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// 1 − exp(−exposure · L) per channel, then sRGB: never saturates abruptly, and a radiance of
// 1/exposure shows at 63 % of white (linear).
vec3 tone_map(vec3 radiance, float exposure) {
    vec3 c = 1.0 - exp(-exposure * max(radiance, vec3(0.0)));
    return vec3(srgb_encode(c.r), srgb_encode(c.g), srgb_encode(c.b));
}

#endif
