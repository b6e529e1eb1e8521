#version 450
// Tiled SGEMM: C = A · B (or C += A · B), row-major A (m × k), B (k × n), C (m × n), each one
// binding (callers chunk larger arrays by rows). The tiling is include/gemm_tile.glsl.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, set = 0, binding = 0) readonly buffer MA { float A[]; };
layout(std430, set = 0, binding = 1) readonly buffer MB { float B[]; };
layout(std430, set = 0, binding = 2) buffer MC { float C[]; };
layout(push_constant) uniform Push { uint m; uint n; uint k; uint accumulate; } pc;

float gemm_load_a(uint row, uint kk) { return A[row * pc.k + kk]; }
float gemm_load_b(uint kk, uint col) { return B[kk * pc.n + col]; }
void gemm_store_c(uint row, uint col, float value) {
    uint i = row * pc.n + col;
    C[i] = (pc.accumulate != 0u ? C[i] : 0.0) + value;
}

#include "gemm_tile.glsl"

void main() { gemm_tile(pc.m, pc.n, pc.k); }
