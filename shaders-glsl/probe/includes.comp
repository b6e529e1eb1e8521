#version 450
// Test probe: evaluates the shared GLSL includes at given inputs so tests can compare them with
// their Rust twins directly (render/colormap.rs, demo/polynomial.rs).
#include "colormap.glsl"
#include "polynomial.glsl"

layout(local_size_x = 64) in;
// Per probe: (v, lo, hi, log) for the ramp functions and (x, y) for the cubic.
layout(std430, set = 0, binding = 0) readonly buffer In { vec4 ramp_in[]; };
layout(std430, set = 0, binding = 1) readonly buffer Xy { vec2 xy[]; };
layout(std430, set = 0, binding = 2) readonly buffer Coeff { float coefficients[10]; };
// Per probe: (ramp_coordinate, ramp_texcoord(t, 256), bivariate_cubic, 0).
layout(std430, set = 0, binding = 3) writeonly buffer Out { vec4 result[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    vec4 r = ramp_in[i];
    float t = ramp_coordinate(r.x, r.y, r.z, r.w > 0.5);
    float c[10];
    for (int k = 0; k < 10; ++k) c[k] = coefficients[k];
    result[i] = vec4(t, ramp_texcoord(t, 256.0), bivariate_cubic(c, xy[i]), 0.0);
}
