#version 450
// Shared-memory tiled SGEMM: C = A * B (or C += A * B), row-major A (m x k), B (k x n), C (m x n).
// Each operand is one binding (callers chunk larger arrays by rows).
// An 8 x 8 workgroup computes a 64 x 64 tile of C, walking k in steps of 32 through two shared
// tiles (2 * 64 * 32 floats = 16 KiB of lavapipe's 32 KiB). Invocation (tx, ty) owns rows
// ty*8 .. ty*8+7 and the interleaved columns tx, tx+8, …, tx+56: neighbouring invocations (SIMD
// lanes on a CPU rasteriser, threads of a warp) read neighbouring words, and the row operand
// is shared by all of them. Each invocation does 64 FMAs per 16 shared loads.
// Measured on lavapipe (Mesa 25, 512^3): 8x8 blocks with k-steps of 32 ran 5.1 GFLOP/s,
// k-steps of 16 3.7, 4x4 blocks on a 16x16 group 3.1. Edges are zero-padded on load and
// masked on store, so any m, n, k works.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, set = 0, binding = 0) readonly buffer MA { float A[]; };
layout(std430, set = 0, binding = 1) readonly buffer MB { float B[]; };
layout(std430, set = 0, binding = 2) buffer MC { float C[]; };
layout(push_constant) uniform Push { uint m; uint n; uint k; uint accumulate; } pc;

const uint TILE = 64u;
const uint KT = 32u;
shared float As[TILE][KT];   // As[row][kk]
shared float Bs[KT][TILE];   // Bs[kk][col]

void main() {
    uint tx = gl_LocalInvocationID.x;
    uint ty = gl_LocalInvocationID.y;
    uint lid = ty * 8u + tx;
    uint row0 = gl_WorkGroupID.y * TILE;
    uint col0 = gl_WorkGroupID.x * TILE;
    float acc[8][8];
    for (int i = 0; i < 8; ++i) for (int j = 0; j < 8; ++j) acc[i][j] = 0.0;
    for (uint k0 = 0u; k0 < pc.k; k0 += KT) {
        // 64 invocations load the 2048 words of each tile: 32 each.
        for (uint e = 0u; e < 32u; ++e) {
            uint idx = lid + 64u * e;
            uint ar = idx / KT, ak = idx % KT;
            uint gr = row0 + ar, gk = k0 + ak;
            As[ar][ak] = (gr < pc.m && gk < pc.k) ? A[gr * pc.k + gk] : 0.0;
            uint bk = idx / TILE, bc = idx % TILE;
            uint gk2 = k0 + bk, gc = col0 + bc;
            Bs[bk][bc] = (gk2 < pc.k && gc < pc.n) ? B[gk2 * pc.n + gc] : 0.0;
        }
        barrier();
        for (uint kk = 0u; kk < KT; ++kk) {
            float a[8]; float b[8];
            for (uint i = 0u; i < 8u; ++i) a[i] = As[ty * 8u + i][kk];
            for (uint j = 0u; j < 8u; ++j) b[j] = Bs[kk][tx + 8u * j];
            for (int i = 0; i < 8; ++i) for (int j = 0; j < 8; ++j) acc[i][j] = fma(a[i], b[j], acc[i][j]);
        }
        barrier();
    }
    for (uint i = 0u; i < 8u; ++i) {
        uint r = row0 + ty * 8u + i;
        if (r >= pc.m) continue;
        for (uint j = 0u; j < 8u; ++j) {
            uint c = col0 + tx + 8u * j;
            if (c < pc.n) C[r * pc.n + c] = (pc.accumulate != 0u ? C[r * pc.n + c] : 0.0) + acc[i][j];
        }
    }
}
