#version 450
// One sparse stage of premultiplication (src/reduce/premultiply/gpu.rs): for every group of
// entries that agree on the remaining sparse axes, out[group][t][b] =
//   Σ_{rows r of the group} U_r[t] · Σ_{entries e of row r} vals[e][b],
// where a row gathers the entries sharing the contracted unit's coordinates and U_r is the
// unit's row: a basis row (an axis), or for a symmetric group the packed symmetrised row
// U_r[t] = Σ over distinct permutations σ of the row's coordinates of Π_l B[σ_l][tuple_t[l]].
// Entries are stored in row order; coordinates are indices into a table of basis rows.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vals { float vals[]; };        // entries × block
layout(std430, set = 0, binding = 1) readonly buffer RowStart { uint row_start[]; };  // rows + 1
layout(std430, set = 0, binding = 2) readonly buffer GroupRow { uint group_row[]; };  // groups + 1
layout(std430, set = 0, binding = 3) readonly buffer RowRef { uint row_ref[]; };      // rows × g
layout(std430, set = 0, binding = 4) readonly buffer Table { float table[]; };        // table rows × m
layout(std430, set = 0, binding = 5) readonly buffer Tuples { uint tuples[]; };       // size × g
layout(std430, set = 0, binding = 6) writeonly buffer Out { float outv[]; };          // groups × size × block
layout(push_constant) uniform Push { uint groups; uint size; uint block; uint g; uint m; } pc;

const uint MAX_G = 6u;

float unit_row(uint r, uint t) {
    if (pc.g == 1u) {
        return table[row_ref[r] * pc.m + t];
    }
    uint p[MAX_G];
    for (uint l = 0u; l < pc.g; ++l) p[l] = row_ref[r * pc.g + l];   // sorted ascending
    float sum = 0.0;
    for (;;) {
        float prod = 1.0;
        for (uint l = 0u; l < pc.g; ++l) prod *= table[p[l] * pc.m + tuples[t * pc.g + l]];
        sum += prod;
        // Next distinct permutation (lexicographic).
        int i = int(pc.g) - 1;
        while (i > 0 && p[i - 1] >= p[i]) --i;
        if (i <= 0) break;
        int j = int(pc.g) - 1;
        while (p[j] <= p[i - 1]) --j;
        uint tmp = p[i - 1]; p[i - 1] = p[j]; p[j] = tmp;
        for (int a = i, b = int(pc.g) - 1; a < b; ++a, --b) { tmp = p[a]; p[a] = p[b]; p[b] = tmp; }
    }
    return sum;
}

void main() {
    uint total = pc.groups * pc.size * pc.block;
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint id = gl_GlobalInvocationID.x; id < total; id += stride) {
        uint b = id % pc.block;
        uint t = (id / pc.block) % pc.size;
        uint grp = id / (pc.block * pc.size);
        float acc = 0.0;
        for (uint r = group_row[grp]; r < group_row[grp + 1u]; ++r) {
            float v = 0.0;
            for (uint e = row_start[r]; e < row_start[r + 1u]; ++e) v += vals[e * pc.block + b];
            acc += unit_row(r, t) * v;
        }
        outv[id] = acc;
    }
}
