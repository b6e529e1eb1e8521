#version 450
// Batched dense solve A x = b by Gaussian elimination with partial pivoting (LU applied to the
// right-hand side as it is formed), one workgroup per system, in f32 (src/tensor/gpu_solve.rs).
// The matrices stay in the storage buffer: a 128 × 128 f32 system is 64 KiB, twice lavapipe's
// 32 KiB of shared memory. A and b are overwritten (A by U and the multipliers, b by x).
// A pivot of magnitude ≤ tol[s] stops system s and reports the step and pivot, as the CPU
// solve (tensor/linalg.rs) does with its f64 threshold.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) buffer Mats { float A[]; };          // batch × n × n, row-major
layout(std430, set = 0, binding = 1) buffer Rhs { float x[]; };           // batch × n
layout(std430, set = 0, binding = 2) readonly buffer Tol { float tol[]; }; // batch
struct Status { uint row_plus_one; float pivot; };                        // row 0: solved
layout(std430, set = 0, binding = 3) writeonly buffer Out { Status status[]; };
layout(push_constant) uniform Push { uint n; uint batch; } pc;

const uint WG = 64u;
shared float red_v[WG];
shared uint red_i[WG];

void sync() {
    memoryBarrierBuffer();
    barrier();
}

void main() {
    uint s = gl_WorkGroupID.x;
    if (s >= pc.batch) return;   // uniform across the workgroup
    uint lid = gl_LocalInvocationID.x;
    uint n = pc.n;
    uint a0 = s * n * n;
    uint x0 = s * n;
    for (uint k = 0u; k < n; ++k) {
        // Pivot: the largest |A[i][k]| for i ≥ k (lowest row on ties, as a serial scan would).
        float best = -1.0;
        uint bi = k;
        for (uint i = k + lid; i < n; i += WG) {
            float v = abs(A[a0 + i * n + k]);
            if (v > best) { best = v; bi = i; }
        }
        red_v[lid] = best;
        red_i[lid] = bi;
        barrier();
        for (uint st = WG / 2u; st > 0u; st >>= 1u) {
            if (lid < st) {
                float o = red_v[lid + st];
                if (o > red_v[lid] || (o == red_v[lid] && red_i[lid + st] < red_i[lid])) {
                    red_v[lid] = o;
                    red_i[lid] = red_i[lid + st];
                }
            }
            barrier();
        }
        uint p = red_i[0];
        float pivot = A[a0 + p * n + k];
        if (!(abs(pivot) > tol[s])) {   // also catches NaN
            if (lid == 0u) status[s] = Status(k + 1u, pivot);
            return;   // uniform: every invocation read the same pivot
        }
        barrier();   // everyone has read red_* and the pivot column before rows move
        if (p != k) {
            for (uint j = k + lid; j < n; j += WG) {
                float t = A[a0 + k * n + j];
                A[a0 + k * n + j] = A[a0 + p * n + j];
                A[a0 + p * n + j] = t;
            }
            if (lid == 0u) { float t = x[x0 + k]; x[x0 + k] = x[x0 + p]; x[x0 + p] = t; }
        }
        sync();
        float inv = 1.0 / pivot;
        for (uint i = k + 1u + lid; i < n; i += WG) A[a0 + i * n + k] *= inv;
        sync();
        // Trailing update, b as column n: each invocation owns columns, neighbours read
        // neighbouring words.
        for (uint j = k + 1u + lid; j <= n; j += WG) {
            float akj = j < n ? A[a0 + k * n + j] : x[x0 + k];
            for (uint i = k + 1u; i < n; ++i) {
                float l = A[a0 + i * n + k];
                if (j < n) A[a0 + i * n + j] -= l * akj;
                else x[x0 + i] -= l * akj;
            }
        }
        sync();
    }
    // Back substitution, one column of U at a time.
    for (uint k = n; k-- > 0u;) {
        float xk = x[x0 + k] / A[a0 + k * n + k];
        barrier();   // everyone has read x[k] before it is overwritten
        for (uint i = lid; i < k; i += WG) x[x0 + i] -= A[a0 + i * n + k] * xk;
        if (lid == 0u) x[x0 + k] = xk;
        sync();
    }
    if (lid == 0u) status[s] = Status(0u, 0.0);
}
