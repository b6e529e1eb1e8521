#version 450
// Test probe: the volume pass's opacity ramp (spectral_transfer.glsl) at given field values,
// for tests/includes_agree.rs to compare with TransferFunction::alpha and sigma.
#define SPECTRAL_TRANSFER_BINDING 0
#include "spectral_transfer.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 1) readonly buffer In { float f_in[]; };
// Per probe: (α(f), σ(f)).
layout(std430, set = 0, binding = 2) writeonly buffer Out { vec2 result[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    float f = f_in[i];
    result[i] = vec2(volume_alpha(f), volume_sigma(f));
}
