#version 450
// Test probe: evaluates include/lagrange.glsl and include/spectral_element.glsl at given
// inputs so tests can compare them with their Rust twins (spectral/basis.rs, spectral/mesh.rs).
#include "spectral_element.glsl"

layout(local_size_x = 64) in;
// Per probe: (element, xi, eta, 0) and (x, y, guess xi, guess eta). The bases are the
// specialization constants of spectral_element.glsl.
layout(std430, set = 0, binding = 2) readonly buffer Probes { vec4 probes[]; };
// Per probe 16 vec4: (value, x, y, combined value), (dx/dxi, dx/deta), (inverse xi, eta,
// converged, combined map's distance from the map),
// then for k = 0..12: (field l_k(xi), l_k'(xi), geometry g_k(xi), g_k'(xi)).
layout(std430, set = 0, binding = 3) writeonly buffer Out { vec4 result[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    vec4 q = probes[2u * i];
    vec4 t = probes[2u * i + 1u];
    uint e = uint(q.x);
    vec3 dxi, deta;
    vec3 x = spectral_map(e, q.yz, dxi, deta);
    // The fragment stage's combined evaluation (value with map, coefficients as the flat
    // varyings carry them): its value, and how far its map strays from spectral_map's.
    vec4 given[SPECTRAL_FLAT_VEC4S];
    spectral_flat_coefficients(e, given);
    vec3 y, dyi, dyeta;
    float combined = spectral_value_and_map(e, q.yz, given, y, dyi, dyeta);
    float stray = max(length(y - x), max(length(dyi - dxi), length(dyeta - deta)));
    result[16u * i + 0u] = vec4(spectral_value(e, q.yz), x.xy, combined);
    result[16u * i + 1u] = vec4(dxi.xy, deta.xy);
    vec2 r = t.zw;
    bool ok = spectral_inverse_map(e, t.xy, r);
    result[16u * i + 2u] = vec4(r, ok ? 1.0 : 0.0, stray);
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], g[SPECTRAL_MAX_NODES], dg[SPECTRAL_MAX_NODES];
    spectral_field_eval(q.y, true, a, da);
    spectral_geometry_eval(q.y, true, g, dg);
    for (uint k = 0u; k < SPECTRAL_MAX_NODES; ++k) result[16u * i + 3u + k] = vec4(a[k], da[k], g[k], dg[k]);
}
