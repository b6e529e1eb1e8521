#version 450
// dst[r][b] = Σ_{i = start[r]}^{start[r+1]−1} src[perm[i]][b]: puts the rows of a
// premultiplication intermediate into the order the next stage groups them in (and sums the
// rows that the next stage treats as one), so that every stage reads contiguous ranges.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) readonly buffer Src { float src[]; };
layout(std430, set = 0, binding = 1) readonly buffer Perm { uint perm[]; };
layout(std430, set = 0, binding = 2) readonly buffer Start { uint start[]; };   // rows + 1
layout(std430, set = 0, binding = 3) writeonly buffer Dst { float dst[]; };
layout(push_constant) uniform Push { uint rows; uint block; } pc;

void main() {
    uint total = pc.rows * pc.block;
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint id = gl_GlobalInvocationID.x; id < total; id += stride) {
        uint r = id / pc.block;
        uint b = id - r * pc.block;
        float sum = 0.0;
        for (uint i = start[r]; i < start[r + 1u]; ++i) sum += src[perm[i] * pc.block + b];
        dst[id] = sum;
    }
}
