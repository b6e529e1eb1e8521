#version 450
// The colour ramp's U_max computed on the device (seed 003 §4.2.3): the largest finite U
// (channel 0) over the pixels of a data pass (NaN marks pixels with no surface). Each
// invocation strides over the pixels, the workgroup reduces in shared memory, and one atomic
// per workgroup folds it into the result as float bits — U ≥ 0, where the order of the bits
// is the order of the values.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Pixels { vec4 pixels[]; };
layout(std430, set = 0, binding = 1) buffer Result { uint result; };
layout(push_constant) uniform Push { uint n; } pc;

shared float partial[64];

void main() {
    uint lid = gl_LocalInvocationID.x;
    float m = 0.0;
    for (uint i = gl_GlobalInvocationID.x; i < pc.n; i += gl_NumWorkGroups.x * 64u) {
        float u = pixels[i].x;
        if (!isnan(u) && !isinf(u)) m = max(m, u);
    }
    partial[lid] = m;
    barrier();
    for (uint s = 32u; s > 0u; s >>= 1u) {
        if (lid < s) partial[lid] = max(partial[lid], partial[lid + s]);
        barrier();
    }
    if (lid == 0u) atomicMax(result, floatBitsToUint(partial[0]));
}
