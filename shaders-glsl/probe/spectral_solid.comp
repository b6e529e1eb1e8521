#version 450
// Test probe: evaluates include/spectral_element.glsl's solid-element functions (hexahedra and,
// with SPECTRAL_SIMPLEX, tetrahedra: spectral_simplex.glsl) at given reference points so tests
// can compare them with their Rust twins (SpectralMesh::map_hex, value_hex,
// value_gradient_at, inverse_map_hex).
#include "spectral_element.glsl"

layout(local_size_x = 64) in;
// Per probe: (element, xi, eta, zeta), then (x, y, z of the point to pull back, 0).
layout(std430, set = 0, binding = 2) readonly buffer Probes { vec4 probes[]; };
// Per probe 6 vec4: (x, value), the Jacobian's columns (3), (f, f_xi, f_eta, f_zeta), and the
// pulled-back point (xi, eta, zeta, converged).
layout(std430, set = 0, binding = 3) writeonly buffer Out { vec4 result[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    vec4 q = probes[2u * i];
    vec4 t = probes[2u * i + 1u];
    uint e = uint(q.x);
    mat3 j;
    vec3 x = spectral_map_hex(e, q.yzw, j);
    result[6u * i + 0u] = vec4(x, spectral_value_hex(e, q.yzw));
    result[6u * i + 1u] = vec4(j[0], 0.0);
    result[6u * i + 2u] = vec4(j[1], 0.0);
    result[6u * i + 3u] = vec4(j[2], 0.0);
    result[6u * i + 4u] = spectral_slot_value_gradient_hex(e, 0u, q.yzw);
    vec3 r = vec3(SPECTRAL_SIMPLEX ? 0.25 : 0.5);
    bool ok = spectral_inverse_map_hex(e, t.xyz, r);
    result[6u * i + 5u] = vec4(r, ok ? 1.0 : 0.0);
}
