#version 450
// Streaming bandwidth (STREAM triad): a = b + s * c over vec4s, grid-stride.
// Bytes moved = 3 * 16 * n4.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) writeonly buffer A { vec4 a[]; };
layout(std430, set = 0, binding = 1) readonly buffer B { vec4 b[]; };
layout(std430, set = 0, binding = 2) readonly buffer C { vec4 c[]; };
layout(push_constant) uniform Push { float s; uint n4; } pc;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < pc.n4; i += stride) {
        a[i] = b[i] + pc.s * c[i];
    }
}
