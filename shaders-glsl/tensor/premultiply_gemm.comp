#version 450
// The final stage of premultiplication (src/reduce/premultiply/gpu.rs) as one GEMM whose
// operands are formed while the tiles load, so the Khatri–Rao intermediate is never stored:
//   C[t][s·block + b] (+)= Σ_r  F[fref[r]][t] · U[uref[r]][s] · X[r][b]
// over the rows r of a chunk (entries summed per distinct pair of first-unit and last-unit
// coordinates). A (m × k) = F rows by reference, transposed; B (k × n) = the row-wise
// Kronecker product of U rows (by reference) and X. Tiling: include/gemm_tile.glsl.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, set = 0, binding = 0) readonly buffer FirstRows { float F[]; };   // first rows × m
layout(std430, set = 0, binding = 1) readonly buffer FirstRef { uint fref[]; };  // k
layout(std430, set = 0, binding = 2) readonly buffer UnitRows { float U[]; };    // unit rows × size
layout(std430, set = 0, binding = 3) readonly buffer UnitRef { uint uref[]; };   // k
layout(std430, set = 0, binding = 4) readonly buffer Values { float X[]; };      // k × block
layout(std430, set = 0, binding = 5) buffer Out { float C[]; };                  // m × (size·block)
layout(push_constant) uniform Push { uint m; uint k; uint size; uint block; uint accumulate; } pc;

float gemm_load_a(uint row, uint kk) { return F[fref[kk] * pc.m + row]; }
float gemm_load_b(uint kk, uint col) {
    uint s = col / pc.block, b = col - s * pc.block;
    return U[uref[kk] * pc.size + s] * X[kk * pc.block + b];
}
void gemm_store_c(uint row, uint col, float value) {
    uint i = row * pc.size * pc.block + col;
    C[i] = (pc.accumulate != 0u ? C[i] : 0.0) + value;
}

#include "gemm_tile.glsl"

void main() { gemm_tile(pc.m, pc.size * pc.block, pc.k); }
