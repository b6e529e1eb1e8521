#version 450
// dst[i][b] = src[perm[i]][b]: puts the rows of a premultiplication intermediate into the order
// the next stage groups them in, so that every stage reads contiguous ranges.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) readonly buffer Src { float src[]; };
layout(std430, set = 0, binding = 1) readonly buffer Perm { uint perm[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Dst { float dst[]; };
layout(push_constant) uniform Push { uint rows; uint block; } pc;

void main() {
    uint total = pc.rows * pc.block;
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint id = gl_GlobalInvocationID.x; id < total; id += stride) {
        uint i = id / pc.block;
        uint b = id % pc.block;
        dst[id] = src[perm[i] * pc.block + b];
    }
}
