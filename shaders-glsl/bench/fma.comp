#version 450
// FMA peak: eight independent chains of `iterations` FMAs per invocation, registers only.
// FLOPs = 2 * 8 * iterations * invocations. The sum is stored so nothing is optimised away.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) writeonly buffer Out { float sink[]; };
layout(push_constant) uniform Push { uint iterations; float a; float b; } pc;

void main() {
    float x = float(gl_GlobalInvocationID.x) * 1e-7;
    float v0 = x, v1 = x + 0.1, v2 = x + 0.2, v3 = x + 0.3;
    float v4 = x + 0.4, v5 = x + 0.5, v6 = x + 0.6, v7 = x + 0.7;
    for (uint i = 0u; i < pc.iterations; ++i) {
        v0 = fma(v0, pc.a, pc.b); v1 = fma(v1, pc.a, pc.b);
        v2 = fma(v2, pc.a, pc.b); v3 = fma(v3, pc.a, pc.b);
        v4 = fma(v4, pc.a, pc.b); v5 = fma(v5, pc.a, pc.b);
        v6 = fma(v6, pc.a, pc.b); v7 = fma(v7, pc.a, pc.b);
    }
    sink[gl_GlobalInvocationID.x] = ((v0 + v1) + (v2 + v3)) + ((v4 + v5) + (v6 + v7));
}
