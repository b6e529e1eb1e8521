#version 450
// One Jacobi sweep of the radiosity equation (seed 000 Eq. 14) over rows row0 .. row0 + rows:
// b_out[i] = e[i] + ρ[i] ∘ Σ_j F[i][j] b_in[j], per colour channel. One invocation per row.

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Rows { float f[]; };
layout(std430, set = 0, binding = 1) readonly buffer Albedo { vec4 albedo[]; };
layout(std430, set = 0, binding = 2) readonly buffer Emission { vec4 emission[]; };
layout(std430, set = 0, binding = 3) readonly buffer Previous { vec4 b_in[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Next { vec4 b_out[]; };

layout(push_constant) uniform Push {
    uint n;
    uint row0;
    uint rows;
    uint pad;
} pc;

void main() {
    uint r = gl_GlobalInvocationID.x;
    if (r >= pc.rows) {
        return;
    }
    uint i = pc.row0 + r;
    vec3 s = vec3(0.0);
    uint base = r * pc.n;
    for (uint j = 0; j < pc.n; ++j) {
        float fij = f[base + j];
        if (fij != 0.0) {
            s += fij * b_in[j].rgb;
        }
    }
    b_out[i] = vec4(emission[i].rgb + albedo[i].rgb * s, 0.0);
}
